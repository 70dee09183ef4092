#!/usr/bin/env bash
# Submits an lmanim shot to Slurm: a warm job that fills the shared
# light-mesh cache, then a job array of render chunks that starts once it
# has succeeded (farm/slurm/lmanim-array.sbatch).
#
#   submit.sh [--wait] SCENE FIRST-LAST CHUNK OUTPUT_PATTERN CACHE_DIR
#
# OUTPUT_PATTERN has a run of '#' for the frame number; CACHE_DIR and the
# output must be on a filesystem every node sees. METHOD (lmm1), SETTINGS
# (a RON file) and LMANIM (the executable, default `lmanim` on the PATH)
# come from the environment. --wait returns when the last chunk is done,
# with the array's exit status.
set -euo pipefail
wait=()
if [ "${1:-}" = --wait ]; then wait=(--wait); shift; fi
if [ $# -ne 5 ]; then
    sed -n '2,13p' "$0" >&2
    exit 2
fi
export SCENE=$(realpath "$1") OUT=$(realpath -m "$4") CACHE=$(realpath -m "$5")
export FIRST=${2%-*} LAST=${2#*-} CHUNK=$3
export METHOD=${METHOD:-lmm1} SETTINGS=${SETTINGS:-} LMANIM=${LMANIM:-lmanim}
if ! [[ $FIRST =~ ^[0-9]+$ && $LAST =~ ^[0-9]+$ && $CHUNK =~ ^[1-9][0-9]*$ ]] || [ "$LAST" -lt "$FIRST" ]; then
    echo "submit.sh: frames are FIRST-LAST and the chunk a positive count, not '$2' and '$3'" >&2
    exit 2
fi
settings=()
if [ -n "$SETTINGS" ]; then settings=(--settings "$(realpath "$SETTINGS")"); fi
here=$(dirname "$(realpath "$0")")
warm=$(sbatch --parsable --job-name=lmanim-warm --cpus-per-task=1 --output=lmanim-warm-%j.log \
    --wrap "$(printf '%q ' "$LMANIM" warm "$SCENE" --frames "$FIRST-$LAST" --method "$METHOD" --cache "$CACHE" --quiet "${settings[@]}")")
tasks=$(( (LAST - FIRST) / CHUNK ))
render=$(sbatch --parsable "${wait[@]}" --array="0-$tasks" --dependency="afterok:$warm" \
    --export=ALL "$here/lmanim-array.sbatch")
echo "warm job $warm, render array $render (tasks 0-$tasks)"
