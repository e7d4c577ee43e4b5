#!/bin/bash
# One sitting of raylab against Mitsuba 3 on the three comparison scenes (BENCHMARKS.md, "Path
# tracing against Mitsuba 3"): for each scene, three alternating rounds of
# Mitsuba `multijitter` (its `mi.render` after a warm-up render) and raylab `sobol` and
# `multijitter` (the whole process), 64 spp, the machine's threads; then the RMSE of each
# render against a long Mitsuba reference, and raylab's at seeds 2 and 3. raylab writes PFM:
# Mitsuba's timed call writes no file, and EXR's ZIP compression alone costs raylab about 9 ms
# of a 256² render's wall time.
#
# usage: tools/mitsuba/sitting.sh PYTHON REFS [SCENE...]
#   SCENE   gltf, materials, cbox, envmap (default: the first three)
#   PYTHON  a Python with mitsuba and numpy (e.g. mi/bin/python; export DRJIT_LIBLLVM_PATH
#           for the llvm variant, e.g. /usr/lib/x86_64-linux-gnu/libLLVM-19.so)
#   REFS    a folder holding the references, made once (2,048 spp each, a few minutes):
#             PYTHON tools/mitsuba/cbox_reference.py --sampler multijitter --spp 256 \
#                 --passes 8 --seed 100 --out REFS/cbox.exr --npy          # -> REFS/cbox.npy
#             PYTHON tools/mitsuba/materials_reference.py SCENE --size 256 256 --spp 256 \
#                 --passes 8 --sampler multijitter --seed 100 --out REFS/NAME.npy
#           for SCENE = crates/raylab/tests/data/mitsuba-materials/materials.toml (materials),
#           crates/raylab/tests/data/mitsuba-gltf/boxes.toml (gltf) and
#           crates/raylab/tests/data/mitsuba-envmap/envmap.toml (envmap; its sun's reflections
#           need more: --spp 1024 --passes 16, about five minutes)
# Build raylab first (cargo build --release -p raylab-cli) and keep the machine otherwise idle.
set -eu
PY=$1
REFS=$2
shift 2
SCENES=${*:-gltf materials cbox}
cd "$(dirname "$0")/../.."
R=target/release/raylab
[ -x "$R" ] || { echo "sitting.sh: $R not found: cargo build --release -p raylab-cli first" >&2; exit 1; }
OUT=$(mktemp -d)
trap 'rm -rf "$OUT"' EXIT
date
for name in $SCENES; do
  case $name in
    gltf) S=crates/raylab/tests/data/mitsuba-gltf/boxes.toml; SIZE="--size 256x256";;
    materials) S=crates/raylab/tests/data/mitsuba-materials/materials.toml; SIZE="--size 256x256";;
    cbox) S=scenes/cornell-mitsuba.toml; SIZE="";;
    envmap) S=crates/raylab/tests/data/mitsuba-envmap/envmap.toml; SIZE="--size 256x256";;
    *) echo "sitting.sh: unknown scene $name" >&2; exit 2;;
  esac
  echo "== $S, 64 spp"
  for r in 1 2 3; do
    echo -n "round $r mitsuba multijitter: "
    if [ $name = cbox ]; then
      "$PY" tools/mitsuba/cbox_reference.py --sampler multijitter --warmup --seed 1 \
        --out "$OUT/m_$name.exr" --npy 2>&1 | grep "wall time"
    else
      "$PY" tools/mitsuba/materials_reference.py "$S" --size 256 256 --spp 64 \
        --sampler multijitter --warmup --seed 1 --out "$OUT/m_$name.npy" 2>&1 | grep -i "wall time"
    fi
    for sampler in sobol multijitter; do
      /usr/bin/time -f "round $r raylab $sampler: %e s (user %U)" \
        $R render "$S" $SIZE --spp 64 --sampler $sampler -o "$OUT/${sampler}_$name.pfm" 2>&1 | tail -1
    done
  done
  for f in "$OUT/m_$name.npy" "$OUT/sobol_$name.pfm" "$OUT/multijitter_$name.pfm"; do
    echo -n "$(basename "$f"): "
    "$PY" tools/mitsuba/cbox_compare.py "$f" "$REFS/$name.npy" | grep -E "RMSE \(all|relative mean" | tr "\n" " "; echo
  done
  for seed in 2 3; do
    for sampler in sobol multijitter; do
      $R render "$S" $SIZE --spp 64 --seed $seed --sampler $sampler -o "$OUT/x.pfm" >/dev/null 2>&1
      echo -n "seed $seed $sampler: "
      "$PY" tools/mitsuba/cbox_compare.py "$OUT/x.pfm" "$REFS/$name.npy" | grep -E "RMSE \(all|relative mean" | tr "\n" " "; echo
    done
  done
done
date
