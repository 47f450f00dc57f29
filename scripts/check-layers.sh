#!/usr/bin/env bash
# The architecture's layering (ARCHITECTURE.md), checked: the map crate `oeg` knows nothing of the simulation or
# the evaluation, nor the files' crate `oeg-files` of any of them; Rapier's types (rapier3d, parry3d) appear in
# `sim` only; the map crate's modules are private (its API is the list of re-exports in oeg/src/lib.rs); no job of
# `oeg_eval` (eval/src/jobs/) imports another.
set -euo pipefail
cd "$(dirname "$0")/.."
status=0
deps=$(cargo tree -p oeg -e normal --prefix none --format '{p}' | awk '{print $1}' | sort -u)
for forbidden in sim oeg-eval rapier3d parry3d; do
    if grep -qx "$forbidden" <<<"$deps"; then
        echo "layering: oeg depends on $forbidden" >&2
        status=1
    fi
done
if hits=$(grep -rnE '\b(rapier3d|parry3d)::' --include='*.rs' oeg eval src tests fuzz); then
    echo "layering: Rapier types outside sim:" >&2
    echo "$hits" >&2
    status=1
fi
# The files' crate sits under the map: it knows nothing of the map, the simulation or the evaluation.
files_deps=$(cargo tree -p oeg-files -e normal --prefix none --format '{p}' | awk '{print $1}' | sort -u)
for forbidden in oeg sim oeg-eval rapier3d parry3d; do
    if grep -qx "$forbidden" <<<"$files_deps"; then
        echo "layering: oeg-files depends on $forbidden" >&2
        status=1
    fi
done
for package in oeg-eval oeg-testbed oeg-fuzz; do
    direct=$(cargo tree -p "$package" -e normal --depth 1 --prefix none --format '{p}' | awk '{print $1}')
    if grep -qxE 'rapier3d|parry3d' <<<"$direct"; then
        echo "layering: $package depends on Rapier directly" >&2
        status=1
    fi
done
if hits=$(grep -nE '^\s*pub mod ' oeg/src/lib.rs); then
    echo "layering: the map crate's modules are private; re-export the items instead:" >&2
    echo "$hits" >&2
    status=1
fi
# A job is a file or folder directly under eval/src/jobs/; it may use the shared wings, never another job.
jobs_dir=eval/src/jobs
for entry in "$jobs_dir"/*; do
    job=$(basename "$entry" .rs)
    [ "$job" = mod ] && continue
    for other in "$jobs_dir"/*; do
        name=$(basename "$other" .rs)
        [ "$name" = mod ] || [ "$name" = "$job" ] && continue
        # From a job's file `super::` is the jobs folder; from a job's folder it is `super::super::`.
        if [ -d "$entry" ]; then up='super::super'; else up='super'; fi
        if hits=$(grep -rnHE "(crate::jobs|$up)::$name\b" "$entry" | grep -vE "^[^:]*:[0-9]+:\s*//"); then
            echo "layering: the job $job imports the job $name:" >&2
            echo "$hits" >&2
            status=1
        fi
    done
done
[ "$status" -eq 0 ] && echo "layering: oeg stands alone with private modules; Rapier stays in sim; no job imports another"
exit "$status"
