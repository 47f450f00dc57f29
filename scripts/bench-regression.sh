#!/usr/bin/env bash
# The map's speed and memory against a pinned baseline build, measured in one run: the example
# `oeg/examples/map_graph.rs` is built at BASELINE (in a scratch worktree, its own target folder) and at the
# working tree, and both map the shared real scans at 0.05, 0.1 and 0.2 m, one thread, alternating
# baseline / this tree, REPEATS times each. It prints the medians, the ratio per resolution, the memory (the
# map with its per-scan scratch, as the first version counted it, and this tree's map alone), this tree's
# `static` and `robust` presets against its paper model, this tree's paper and robust models on two threads,
# and the machine's ceiling for two threads: two one-thread processes of this tree's paper model at once, the
# speed-up no threading of the same work can beat on this machine (`2 x alone / the slower of the two`: the
# second core's share, memory and cache contention). Run it after every change to the map (the machines are noisy, so CI does not; ratios within one run
# are what count).
#
#   bash scripts/bench-regression.sh                   # baseline c75d7d4 (the first map), 5 repeats
#   bash scripts/bench-regression.sh bf33cf9 9         # another baseline, 9 repeats
#   OEG_SHARED_DATA=/path/to/data bash scripts/bench-regression.sh
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
baseline=${1:-c75d7d4}
repeats=${2:-5}
data=${OEG_SHARED_DATA:-$root/../shared/data}/3dtk_frames.graph
if [ ! -f "$data" ]; then
    echo "skipped: $data is absent (the shared data set lives beside the project, or set OEG_SHARED_DATA)"
    exit 0
fi
work=$(mktemp -d)
cleanup() {
    git -C "$root" worktree remove --force "$work/baseline" 2>/dev/null || true
    rm -rf "$work"
}
trap cleanup EXIT
git -C "$root" worktree add --quiet --detach "$work/baseline" "$baseline"
echo "building map_graph at $baseline and at this tree ($(git -C "$root" rev-parse --short HEAD)) ..."
(cd "$work/baseline" && CARGO_TARGET_DIR="$work/target" cargo build --quiet --release -p oeg --example map_graph)
cargo build --quiet --release -p oeg --example map_graph
base_bin="$work/target/release/examples/map_graph"
head_bin="$root/target/release/examples/map_graph"

# run BIN RESOLUTION [PRESET [THREADS]]: "seconds bytes map_bytes" of one integration (the example's own line:
# "... N bytes, S s, ...[; map M bytes, ...]"; the first version has no map figure of its own: "-").
run() {
    RAYON_NUM_THREADS=${4:-1} "$1" "$data" "$2" ${3:+"$3"} |
        sed -E -e 's/.* ([0-9]+) bytes, ([0-9.]+) s, .*; map ([0-9]+) bytes.*/\2 \1 \3/' \
            -e 's/.* ([0-9]+) bytes, ([0-9.]+) s, [^;]*$/\2 \1 -/'
}
median() { sort -g | awk '{ v[NR] = $1 } END { print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2 }'; }

printf '\n| resolution | %s: paper | this tree: paper | ratio (this / %s) | %s: map and scratch | this tree: map and scratch | this tree: map | this tree: static | static / paper | this tree: robust | robust / paper | this tree: paper, 2 threads | speed-up | this tree: robust, 2 threads | speed-up | this tree: paper, two 1-thread processes at once | ceiling |\n' \
    "$baseline" "$baseline" "$baseline"
echo '|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|'
for resolution in 0.05 0.1 0.2; do
    : >"$work/base" && : >"$work/head" && : >"$work/static" && : >"$work/robust" && : >"$work/two" && : >"$work/robust2" && : >"$work/pair"
    for _ in $(seq "$repeats"); do
        run "$base_bin" "$resolution" >>"$work/base"
        run "$head_bin" "$resolution" paper >>"$work/head"
        run "$head_bin" "$resolution" static >>"$work/static"
        run "$head_bin" "$resolution" robust >>"$work/robust"
        run "$head_bin" "$resolution" paper 2 >>"$work/two"
        run "$head_bin" "$resolution" robust 2 >>"$work/robust2"
        # The ceiling: the same work twice, by two processes at once; the slower one's time.
        run "$head_bin" "$resolution" paper >"$work/pair-a" &
        run "$head_bin" "$resolution" paper >"$work/pair-b"
        wait
        cut -d' ' -f1 "$work/pair-a" "$work/pair-b" | sort -g | tail -1 >>"$work/pair"
    done
    b=$(cut -d' ' -f1 "$work/base" | median)
    h=$(cut -d' ' -f1 "$work/head" | median)
    st=$(cut -d' ' -f1 "$work/static" | median)
    r=$(cut -d' ' -f1 "$work/robust" | median)
    t=$(cut -d' ' -f1 "$work/two" | median)
    r2=$(cut -d' ' -f1 "$work/robust2" | median)
    p2=$(median <"$work/pair")
    bm=$(head -1 "$work/base" | cut -d' ' -f2)
    hm=$(head -1 "$work/head" | cut -d' ' -f2)
    hmap=$(head -1 "$work/head" | cut -d' ' -f3)
    awk -v res="$resolution" -v b="$b" -v h="$h" -v st="$st" -v r="$r" -v t="$t" -v r2="$r2" -v p2="$p2" -v bm="$bm" -v hm="$hm" -v hmap="$hmap" 'BEGIN {
        printf "| %s m | %.4f s | %.4f s | %.2fx | %.2f MB | %.2f MB | %s | %.4f s | %.2fx | %.4f s | %.2fx | %.4f s | %.2fx | %.4f s | %.2fx | %.4f s | %.2fx |\n",
            res, b, h, h / b, bm / 1e6, hm / 1e6, (hmap == "-" ? "-" : sprintf("%.2f MB", hmap / 1e6)), st, st / h, r, r / h, t, h / t, r2, r / r2, p2, 2 * h / p2
    }'
done
echo
echo "Medians of $repeats alternating runs each, one thread unless stated, $(nproc) cores, $(basename "$data"); ratio > 1: this tree is slower. Ceiling: \`2 x\` this tree's paper time alone over the slower of two one-thread processes mapping the same scans at once, the most any two-thread speed-up of this work can reach on this machine."
