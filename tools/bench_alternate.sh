#!/usr/bin/env bash
# Ray-query speed of two raylab builds, measured in alternating rounds on the same ray files, so
# that the machine's drift hits both alike (see docs/benchmarking.md). Prints, per ray set and
# thread count, each build's median over the rounds and the median of the per-round ratios
# (new / old) with their range.
#
#   tools/bench_alternate.sh OLD_RAYLAB NEW_RAYLAB ROUNDS OUT_DIR MESH=RAYS_DIR [MESH=RAYS_DIR ...] [-- BENCH_ARGS]
#
# RAYS_DIR holds the ray sets of MESH (`raylab bench MESH --generate RAYS_DIR`). BENCH_ARGS go to
# every `raylab bench` call (for example `--reps 5` or `--flat-limit 0`).
set -euo pipefail
old=$1 new=$2 rounds=$3 out=$4
shift 4
pairs=()
while [ $# -gt 0 ] && [ "$1" != "--" ]; do pairs+=("$1"); shift; done
[ "${1:-}" = "--" ] && shift
mkdir -p "$out"
for round in $(seq 1 "$rounds"); do
    for pair in "${pairs[@]}"; do
        mesh=${pair%%=*} rays=${pair#*=} name=$(basename "$rays")
        for which in old new; do
            binary=$old
            [ "$which" = new ] && binary=$new
            "$binary" bench "$mesh" --rays "$rays" "$@" --json "$out/$name-$which-$round.json" >/dev/null
        done
    done
done
python3 - "$out" <<'PY'
import glob, json, os, statistics, sys
out = sys.argv[1]
names = sorted({os.path.basename(f).rsplit('-', 2)[0] for f in glob.glob(f'{out}/*-old-*.json')})
for name in names:
    rounds = sorted(f.rsplit('-', 1)[1][:-5] for f in glob.glob(f'{out}/{name}-old-*.json'))
    load = lambda which, r: json.load(open(f'{out}/{name}-{which}-{r}.json'))['sets']
    first = load('old', rounds[0])
    for ray_set, queries in first.items():
        for query, by_threads in queries.items():
            for threads in by_threads:
                olds = [load('old', r)[ray_set][query][threads] for r in rounds]
                news = [load('new', r)[ray_set][query][threads] for r in rounds]
                ratios = [n / o for n, o in zip(news, olds)]
                print(f'{name:12} {ray_set:8} {query:9} {threads} thr  old {statistics.median(olds):6.2f}'
                      f'  new {statistics.median(news):6.2f} Mrays/s  new/old {statistics.median(ratios):.3f}'
                      f' [{min(ratios):.2f}–{max(ratios):.2f}], {len(rounds)} rounds')
PY
