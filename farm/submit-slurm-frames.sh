#!/usr/bin/env bash
# Renders frames FIRST to LAST of an animation on a Slurm cluster, one array task per frame:
#
#   farm/submit-slurm-frames.sh [--wait] FIRST LAST PATTERN SCENE [raylab render options...]
#
# e.g. farm/submit-slurm-frames.sh 1 240 out/frame_%04d.exr scenes/flythrough.toml --spp 256
#
# PATTERN names each frame's file (%04d: the frame number). Array task I renders frame FIRST+I
# (tasks count from 0, so that long animations stay within Slurm's MaxArraySize); the tasks'
# logs go beside the frames (frames_JOB_I.log). --wait returns when every frame has ended, with
# the array's status. RAYLAB, CPUS_PER_TASK and CHECKPOINT_SECONDS as for submit-slurm.sh; a
# --threads or --checkpoint among the options overrides the script's.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
wait=()
if [ "${1:-}" = --wait ]; then
    wait=(--wait)
    shift
fi
[ $# -ge 4 ] || { echo "usage: $0 [--wait] FIRST LAST PATTERN SCENE [raylab render options...]" >&2; exit 2; }
first=$1 last=$2 pattern=$3 scene=$4
shift 4
[[ $first =~ ^[0-9]+$ && $last =~ ^[0-9]+$ && $first -le $last ]] ||
    { echo "$0: FIRST and LAST must be frame numbers with FIRST <= LAST, not '$first' and '$last'" >&2; exit 2; }
logs=$(dirname "$pattern")
mkdir -p "$logs"
# sbatch reads % in --output as its own pattern: %% is a literal one.
array=$(sbatch --parsable --job-name=raylab-frames --array="0-$((last - first))" \
    --cpus-per-task="${CPUS_PER_TASK:-1}" --requeue --open-mode=append \
    --output="${logs//%/%%}/frames_%A_%a.log" "${wait[@]}" \
    "$here/slurm-frame.sh" "$first" "$pattern" "$scene" "$@")
echo "frames $first to $last: job array ${array%%;*}"
