#!/usr/bin/env bash
# Renders SCENE on a Slurm cluster as TILES tiles, one task of a job array each, then merges them
# into OUTPUT in a job that waits for the whole array (afterok):
#
#   farm/submit-slurm.sh [--wait] TILES OUTPUT SCENE [raylab render options...]
#
# e.g. farm/submit-slurm.sh 16 cbox.exr scenes/cornell-mitsuba.toml --spp 1024
#
# The tiles and the jobs' logs go to OUTPUT.parts/. --wait returns when the merge has ended,
# with its exit status. Set RAYLAB to the raylab binary (default: raylab on the PATH),
# CPUS_PER_TASK for the threads of each tile (default 1), CHECKPOINT_SECONDS (default 60), and
# any sbatch option through SBATCH_* variables (SBATCH_PARTITION, SBATCH_TIMELIMIT, ...). A
# --threads or --checkpoint among the raylab options overrides the script's.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
wait=()
if [ "${1:-}" = --wait ]; then
    wait=(--wait)
    shift
fi
[ $# -ge 3 ] || { echo "usage: $0 [--wait] TILES OUTPUT SCENE [raylab render options...]" >&2; exit 2; }
tiles=$1 output=$2 scene=$3
shift 3
[[ $tiles =~ ^[0-9]+$ && $tiles -ge 1 ]] || { echo "$0: TILES must be a number of tiles, not '$tiles'" >&2; exit 2; }
parts=$output.parts
mkdir -p "$parts"
# sbatch reads % in --output as its own pattern: %% is a literal one.
logs=${parts//%/%%}
array=$(sbatch --parsable --job-name=raylab-tiles --array="0-$((tiles - 1))" \
    --cpus-per-task="${CPUS_PER_TASK:-1}" --requeue --open-mode=append \
    --output="$logs/tile_%a.log" \
    "$here/slurm-tile.sh" "$tiles" "$parts" "$scene" "$@")
array=${array%%;*}
echo "tiles: job array $array ($tiles tasks)"
merge=$(sbatch --parsable --job-name=raylab-merge --dependency="afterok:$array" \
    --kill-on-invalid-dep=yes --output="$logs/merge.log" "${wait[@]}" \
    "$here/slurm-merge.sh" "$tiles" "$parts" "$output")
echo "merge: job ${merge%%;*} -> $output"
