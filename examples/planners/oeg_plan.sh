#!/bin/sh
# An external planner for closed-loop runs (docs/planner-protocol.md) that wraps `oeg plan`: it plans on the
# map file the testbed wrote beside map.yaml, and writes the path as x,y lines.
#
#   oeg run SCENARIO --planner-command "sh examples/planners/oeg_plan.sh"
#
# Arguments (appended by the testbed): START_X START_Y GOAL_X GOAL_Y MAP_YAML LAYERS_JSON PATH_CSV.
# The `oeg` program is $OEG if set, else `oeg` on the PATH. Exit 3 says that there is no path.
set -eu
if [ "$#" -ne 7 ]; then
    echo "usage: $0 START_X START_Y GOAL_X GOAL_Y MAP_YAML LAYERS_JSON PATH_CSV" >&2
    exit 2
fi
start_x=$1 start_y=$2 goal_x=$3 goal_y=$4 map_yaml=$5 path_csv=$7
dir=$(dirname "$map_yaml")
out="$dir/oeg_plan"
# Never-observed cells are drivable while navigating; the inflation is the Pioneer 3-AT's circumscribed
# radius (0.346 m) and half a 0.05 m cell's diagonal, 0.381 m, as the built-in planner uses by default (the
# footprint meets cells' squares, the inflation is measured between their centres).
"${OEG:-oeg}" plan "$dir/map.oeg" --from "$start_x,$start_y" --to "$goal_x,$goal_y" --out "$out" \
    --set planner.unknown=drivable --set planner.inflation_radius_m=0.381 >/dev/null
if grep -q '"plan_found": false' "$out/plan.json"; then
    exit 3
fi
# path.csv of `oeg plan` is step,x_m,y_m: keep x and y.
echo "x_m,y_m" > "$path_csv"
tail -n +2 "$out/path.csv" | cut -d, -f2,3 >> "$path_csv"
