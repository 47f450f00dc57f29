#!/usr/bin/env bash
# Coverage-guided fuzzing of every reader with AFL++ through `cargo afl` (stable toolchain).
#
#   scripts/fuzz.sh [SECONDS_PER_TARGET] [TARGET...]     # default: 600 s, every target
#
# Needs `cargo install cargo-afl` once (it builds AFL++ itself). Each target starts from the committed corpus
# (fuzz/corpus/<target>/) and writes its findings to target/fuzz/<target>/; copy any crash or hang into the
# corpus with a name that says what it found, fix the reader, and `cargo test -p oeg-fuzz` keeps it fixed.
# Inputs run under a 4 GiB memory limit (-m 4096), so an allocation past it counts as a crash.
set -euo pipefail
cd "$(dirname "$0")/.."
SECONDS_PER_TARGET="${1:-600}"
shift || true
TARGETS=("$@")
if [ ${#TARGETS[@]} -eq 0 ]; then
    TARGETS=(graph pcd log map scenario png urdf sweep row npy nav2 truth path check_path bag kitti)
fi
if ! cargo afl --version >/dev/null 2>&1; then
    echo "cargo-afl is not installed: run 'cargo install cargo-afl' first" >&2
    exit 2
fi
cargo afl build --release -p oeg-fuzz --features afl
BIN=target/release/oeg-fuzz
export AFL_SKIP_CPUFREQ=1 AFL_I_DONT_CARE_ABOUT_MISSING_CRASHES=1 AFL_NO_UI=1
for t in "${TARGETS[@]}"; do
    out="target/fuzz/$t"
    mkdir -p "$out"
    echo "== $t: ${SECONDS_PER_TARGET} s"
    cargo afl fuzz -V "$SECONDS_PER_TARGET" -m 4096 -t 5000 -i "fuzz/corpus/$t" -o "$out" -- "$BIN" "$t" \
        >"$out/afl.log" 2>&1 || true
    stats="$out/default/fuzzer_stats"
    if [ -f "$stats" ]; then
        grep -E '^(execs_done|execs_per_sec|corpus_count|saved_crashes|saved_hangs|run_time) ' "$stats" | tr -s ' '
    else
        echo "no statistics: see $out/afl.log" >&2
    fi
done
