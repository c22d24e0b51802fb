#!/usr/bin/env bash
# The query matrix of issue 15 (config/bench-queries.json: every shared scene at 4096^2 and 16384^2,
# every method): one `shadowtiles bench` run per scene into out/bench-queries/<scene>/, then the
# "Queries" section of BENCHMARKS.md (bench/query_report.py, every scene measured so far).
#
#   bash bench/run_queries.sh [scene,scene,...]     # default: every scene of the config
#   CONFIG=config/bench-queries-surfaces.json bash bench/run_queries.sh
#       the open scenes under the surfaces contract, into out/bench-queries-surfaces/ and the
#       "queries-surfaces" section
#
# A scene whose results.json exists is not re-run (delete its folder to redo it). Set BENCH_LOCK to a
# lock file to run each scene under `flock` (a shared machine: no two benchmarks time at once).
# Every ratio in the section (2 threads / 1 thread, store / Embree) is of one scene's run.
set -euo pipefail
cd "$(dirname "$0")/.."
cli=${SHADOWTILES:-build/cli/shadowtiles}  # a copy keeps one binary for the whole matrix while you rebuild
[ -x "$cli" ] || { echo "build first: $cli is missing" >&2; exit 1; }
config=${CONFIG:-config/bench-queries.json}
name=$(basename "$config" .json)   # bench-queries or bench-queries-surfaces
block=${name#bench-}               # queries or queries-surfaces
scenes=${1:-$(python3 -c "import json; print(','.join(s['name'] for s in json.load(open('$config'))['scenes']))")}
IFS=, read -ra list <<< "$scenes"
for scene in "${list[@]}"; do
  out=out/$name/$scene
  [ -f "$out/results.json" ] && { echo "$scene: kept $out/results.json"; continue; }
  cmd=("$cli" bench --config "$config" --scenes "$scene" --out "$out.partial")
  rm -rf "$out.partial"
  if [ -n "${BENCH_LOCK:-}" ]; then flock "$BENCH_LOCK" "${cmd[@]}"; else "${cmd[@]}"; fi
  rm -rf "$out" && mv "$out.partial" "$out"
done
python3 bench/query_report.py out/"$name"/*/results.json --md BENCHMARKS.md --block "$block"
