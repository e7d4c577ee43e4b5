#!/usr/bin/env bash
# The job that runs after every tile of the array: PARTS/tile_0.exr ... tile_{TILES-1}.exr
# assembled into OUTPUT (bit for bit the single render).
# Submitted by farm/submit-slurm.sh:   slurm-merge.sh TILES PARTS OUTPUT
set -euo pipefail
tiles=$1 parts=$2 output=$3
files=()
for ((i = 0; i < tiles; i++)); do files+=("$parts/tile_$i.exr"); done
exec "${RAYLAB:-raylab}" merge "${files[@]}" -o "$output"
