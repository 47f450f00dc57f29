#!/usr/bin/env bash
# Measures what the README's two commands cost a newcomer on this machine, in a fresh clone of HEAD (the crates
# already downloaded), and writes the figures into README.md between the cost markers, stamped with this command
# and the commit: the build and the run of `cargo run --release`, and the wall time and largest process of
# `cargo test --workspace --release` (GNU time's maximum resident set size of the command's processes).
#
#   bash scripts/measure-front-door.sh     # about 20 minutes on 2 cores; run it with nothing else running
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
commit=$(git rev-parse --short HEAD)
[ -n "$(git status --porcelain 2>/dev/null)" ] && commit="$commit with uncommitted changes"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
git clone --quiet "$root" "$work/clone"
ln -s "$root/../shared" "$work/shared" 2>/dev/null || true
cd "$work/clone"
measure() { # measure NAME COMMAND...: "seconds kilobytes" of the command into $work/NAME
    /usr/bin/time -f "%e %M" -o "$work/$1" "${@:2}" >"$work/$1.log" 2>&1 || {
        echo "failed: ${*:2} (log: $work/$1.log)" >&2
        tail -20 "$work/$1.log" >&2
        exit 1
    }
}
echo "building (cargo build --release) ..."
measure build cargo build --release
echo "running the default scenario (cargo run --release) ..."
measure run cargo run --release
echo "running the tests (cargo test --workspace --release) ..."
measure test cargo test --workspace --release
read -r build_s _ <"$work/build"
read -r run_s run_kb <"$work/run"
read -r test_s test_kb <"$work/test"
fragment=$(
    awk -v b="$build_s" -v r="$run_s" -v rk="$run_kb" -v t="$test_s" -v tk="$test_kb" 'BEGIN {
        printf "| command | wall time | largest process |\n|---|---|---|\n"
        printf "| `cargo run --release`, first time: the build | %.0f s | |\n", b
        printf "| `cargo run --release`: the default run | %.1f s | %.0f MiB |\n", r, rk / 1024
        printf "| `cargo test --workspace --release`, after the build above | %.1f min | %.1f GiB |\n", t / 60, tk / 1048576
    }'
)
stamp="Measured by \`bash scripts/measure-front-door.sh\` at commit $commit on $(nproc) cores, a fresh clone, the crates already downloaded."
cd "$root"
awk -v table="$fragment" -v stamp="$stamp" '
    $0 == "<!-- cost:begin -->" { print; print table; print ""; print stamp; skip = 1; next }
    $0 == "<!-- cost:end -->" { skip = 0 }
    !skip { print }
' README.md >"$work/README.md"
cp "$work/README.md" README.md
echo "wrote README.md's cost table:"
echo "$fragment"
