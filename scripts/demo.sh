#!/usr/bin/env bash
# The main job on the bundled default scene: installs what is needed, builds shadowtiles, bakes the
# sun's shadows of Debian's RealisticTerrain (assimp-testmodels) into a store, shows what the store
# holds, checks every texel of every method against its interval (lossless), and answers queries for
# points sampled on the terrain, beside the ray-traced ground truth.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh
scene=/usr/share/assimp/models/TER/RealisticTerrain.ter
store=out/terrain.store
mkdir -p out
./build/cli/shadowtiles build "$scene" --out "$store" --sun 135,30 --resolution 8192 --tile 2048 \
  --heightfield '*' --method raw,mh,mmh --overwrite
./build/cli/shadowtiles inspect "$store"
./build/cli/shadowtiles verify "$store" -q
for method in raw mh mmh; do
  ./build/cli/shadowtiles query "$store" --method "$method" --ground-truth "$scene" --sample 10 -q | tail -1
done
