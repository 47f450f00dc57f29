#!/usr/bin/env bash
# Compares this crate's map building with OctoMap's on the same real rays, in one run.
#
#   bash oeg/benches/compare_octomap.sh [FILE.graph] [REPEATS]
#
# Needs OctoMap's graph2tree (Debian: apt-get install octomap-tools) and the shared data set (default
# ../shared/data/3dtk_frames.graph beside the project). For each resolution it alternates REPEATS runs of
# `graph2tree` (its own "time to insert scans", i.e. insertPointCloud for every scan) and of the
# `map_graph` example (Map::integrate for every scan, single thread), and prints the medians and their ratio.
set -euo pipefail
cd "$(dirname "$0")/../.."
input=${1:-../shared/data/3dtk_frames.graph}
repeats=${2:-5}
if [ ! -f "$input" ]; then
  echo "skipped: $input is absent (the shared data set lives beside the project)"
  exit 0
fi
if ! command -v graph2tree >/dev/null; then
  echo "skipped: graph2tree not found (apt-get install octomap-tools)"
  exit 0
fi
cargo build --release -q -p oeg --example map_graph
median() { sort -g | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}'; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
printf '%-8s %14s %14s %8s\n' "res [m]" "OctoMap [s]" "OEG [s]" "ratio"
for res in 0.05 0.1 0.2; do
  : > "$tmp/octomap"
  : > "$tmp/oeg"
  for _ in $(seq "$repeats"); do
    graph2tree -i "$input" -res "$res" -o "$tmp/out.bt" 2>&1 | awk '/time to insert scans/ {print $5}' >> "$tmp/octomap"
    RAYON_NUM_THREADS=1 ./target/release/examples/map_graph "$input" "$res" | sed -E 's/.* ([0-9.]+) s, .*/\1/' >> "$tmp/oeg"
  done
  o=$(median < "$tmp/octomap")
  m=$(median < "$tmp/oeg")
  printf '%-8s %14.4f %14.4f %7.1fx\n' "$res" "$o" "$m" "$(echo "$o / $m" | bc -l)"
done
