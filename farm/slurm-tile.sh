#!/usr/bin/env bash
# One task of a Slurm job array: tile $SLURM_ARRAY_TASK_ID of TILES, into PARTS/tile_I.exr.
# Submitted by farm/submit-slurm.sh:   slurm-tile.sh TILES PARTS SCENE [raylab render options...]
#
# It checkpoints every CHECKPOINT_SECONDS (60). A task pre-empted with SIGTERM writes its
# checkpoint and exits; requeued, this same command finds the checkpoint and goes on from it.
set -euo pipefail
tiles=$1 parts=$2 scene=$3
shift 3
i=${SLURM_ARRAY_TASK_ID:?run as a task of a Slurm job array}
exec "${RAYLAB:-raylab}" render "$scene" --tile "$i/$tiles" -o "$parts/tile_$i.exr" \
    --threads "${SLURM_CPUS_PER_TASK:-1}" --checkpoint "${CHECKPOINT_SECONDS:-60}" "$@"
