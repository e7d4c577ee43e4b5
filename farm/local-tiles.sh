#!/usr/bin/env bash
# The same split on one machine without a scheduler: TILES tiles, JOBS at a time (xargs -P),
# then the merge.
#
#   farm/local-tiles.sh TILES JOBS OUTPUT SCENE [raylab render options...]
#
# Each tile renders with THREADS threads (default 1). Set RAYLAB to the raylab binary.
set -euo pipefail
[ $# -ge 4 ] || { echo "usage: $0 TILES JOBS OUTPUT SCENE [raylab render options...]" >&2; exit 2; }
tiles=$1 jobs=$2 output=$3 scene=$4
shift 4
raylab=${RAYLAB:-raylab}
parts=$output.parts
mkdir -p "$parts"
seq 0 $((tiles - 1)) | xargs -P "$jobs" -I{} \
    "$raylab" render "$scene" --tile "{}/$tiles" -o "$parts/tile_{}.exr" \
    --threads "${THREADS:-1}" "$@"
files=()
for ((i = 0; i < tiles; i++)); do files+=("$parts/tile_$i.exr"); done
"$raylab" merge "${files[@]}" -o "$output"
