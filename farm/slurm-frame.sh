#!/usr/bin/env bash
# One task of a Slurm job array: frame FIRST + $SLURM_ARRAY_TASK_ID of an animation (the scene
# file's camera keyframes), to PATTERN with the frame number in place of %04d.
# Submitted by farm/submit-slurm-frames.sh:
#   slurm-frame.sh FIRST PATTERN SCENE [raylab render options...]
#
# It checkpoints every CHECKPOINT_SECONDS (60); requeued after pre-emption it goes on from there.
set -euo pipefail
first=$1 pattern=$2 scene=$3
shift 3
frame=$((first + ${SLURM_ARRAY_TASK_ID:?run as a task of a Slurm job array}))
exec "${RAYLAB:-raylab}" render "$scene" --frames "$frame" -o "$pattern" \
    --threads "${SLURM_CPUS_PER_TASK:-1}" --checkpoint "${CHECKPOINT_SECONDS:-60}" "$@"
