#!/usr/bin/env bash
# What a closed loop costs: a scene navigated in closed loop against the same scene driven as scripted along
# the same way, in one run of this script, alternating REPEATS runs of each.
#
#   bash eval/benches/closed_loop.sh [REPEATS]
#
# Prints the median wall time of each (`timing.json`'s total_wall_time_s), their ratio, and the closed loop's
# planner share (planner_wall_time_s over the total): replanning must not dominate.
set -euo pipefail
cd "$(dirname "$0")/../.."
repeats=${1:-3}
cargo build --release -q
oeg=./target/release/oeg
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
# scenarios/nav_around_wall.toml in closed loop, and the same scene driven as scripted along the way round the
# wall that the closed loop takes (its drive replaced, its navigation removed).
sed -e 's|^urdf = "robots/|urdf = "'"$PWD"'/scenarios/robots/|' scenarios/nav_around_wall.toml >"$tmp/nav.toml"
sed -e '/^\[navigation\]/,/^$/d' -e '/^\[expectations\]/,$d' \
    -e 's/^waypoints_xy_m = \[\[0.0, 0.0\]\]/waypoints_xy_m = [[0.0, 0.0], [2.0, 0.0], [4.3, -2.1], [7.0, -2.1], [9.0, 0.0]]/' \
    -e 's/^duration_s = .*/duration_s = 28.0/' "$tmp/nav.toml" >"$tmp/scripted.toml"
field() { grep -o "\"$1\": [0-9.e+-]*" "$2" | awk '{print $2}'; }
median() { sort -g | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}'; }
: >"$tmp/scripted"
: >"$tmp/closed"
: >"$tmp/planner"
for _ in $(seq "$repeats"); do
  "$oeg" run "$tmp/scripted.toml" --out "$tmp/a" >/dev/null || true
  field total_wall_time_s "$tmp/a/timing.json" >>"$tmp/scripted"
  "$oeg" run "$tmp/nav.toml" --out "$tmp/b" >/dev/null || true
  field total_wall_time_s "$tmp/b/timing.json" >>"$tmp/closed"
  field planner_wall_time_s "$tmp/b/timing.json" >>"$tmp/planner"
done
s=$(median <"$tmp/scripted")
c=$(median <"$tmp/closed")
p=$(median <"$tmp/planner")
nav_time=$(field time_s "$tmp/b/navigation.json" | head -1)
echo "scripted drive (28 s simulated):      $s s"
echo "closed loop ($nav_time s simulated):  $c s"
awk -v s="$s" -v c="$c" -v p="$p" 'BEGIN {
  printf "closed loop / scripted:             %.2f\n", c / s
  printf "planner:                            %.3f s, %.1f %% of the closed loop\n", p, 100 * p / c
}'
