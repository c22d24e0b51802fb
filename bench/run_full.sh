#!/usr/bin/env bash
# Full benchmark: every shared scene at 4K and 16K through `shadowtiles bench` (ground truth, error,
# lookups/s for every method), then sizes-only builds of the MH family at 64K^2 (bench/build_sizes.py:
# the bench's raw reference would need 34 GB decoded there), then BENCHMARKS.md and its charts.
# About 25 min + 80 min + 30 min on 2 shared cores. Both steps resume: delete out/bench-standard or
# out/sizes-64k.json to redo them.
set -euo pipefail
cd "$(dirname "$0")/.."
cli=build/cli/shadowtiles
[ -x "$cli" ] || bash scripts/build.sh
if [ ! -f out/bench-standard/results.json ]; then
  "$cli" bench --config config/bench-standard.json --out out/bench-standard
fi
python3 bench/build_sizes.py --config config/bench-standard.json --resolution 65536 --methods mh,mmh,dagmh \
  --out out/sizes-64k.json --work out/build-sizes-store
# 256K only where a build fits in an hour on 2 cores (nefertiti 24 min, oahu 5 min; bunny's 64K took 42).
python3 bench/build_sizes.py --config config/bench-standard.json --resolution 262144 --methods mh,mmh,dagmh \
  --scenes nefertiti,oahu --out out/sizes-256k.json --work out/build-sizes-store
python3 bench/make_report.py out/bench-standard/results.json --sizes out/sizes-64k.json out/sizes-256k.json \
  --md BENCHMARKS.md --charts docs/bench
