#!/usr/bin/env bash
# Shard balance of docs/scale-out.md: for each shared scene, the plan for N shards (with each tile's
# work parts), then the N shards built one after another with per-tile CPU seconds (--tile-costs),
# each under the bench lock; prints planned and measured max/mean per scene. The per-tile files it
# leaves (OUT_DIR/NAME.plan.json, NAME.shardI.json) feed bench/tile_cost_fit.py.
# Usage: bench/shard_balance.sh SHADOWTILES [OUT_DIR]   env: RES (16384) TILE (1024) SHARDS (4) THREADS (2) BENCH_LOCK (a lock file: each shard build runs under flock)
#        SCENES ("name:file:up ...", default all seven shared scenes)
set -euo pipefail
bin=$(realpath "$1")
out=${2:-$(mktemp -d /tmp/st-balance.XXXXXX)}
here=$(cd "$(dirname "$0")/.." && pwd)
scenes=$here/../shared/scenes
res=${RES:-16384}; tile=${TILE:-1024}; n=${SHARDS:-4}; threads=${THREADS:-2}
mkdir -p "$out"
list=${SCENES:-"honolulu_airport:honolulu_airport/honolulu_airport_harbour.ply:z nefertiti:nefertiti/nefertiti.obj:y
terragen:terragen/RealisticTerrain.ter:z oahu:oahu/oahu_w158n21.ply:z dragon_res2:dragon_res2/dragon_vrip_res2.ply:y
fzk_haus:fzk_haus/fzk_haus.obj:y bunny:bunny/stanford-bunny.obj:y"}
echo "| scene | tiles with triangles | planned max/mean | measured CPU max/mean (s per share) |"
echo "|---|---|---|---|"
for spec in $list; do
  name=${spec%%:*}; rest=${spec#*:}; file=${rest%%:*}; up=${rest#*:}
  args=("$scenes/$file" --up "$up" --sun 135,45 --resolution "$res" --tile "$tile" --method mmh,dagmh)
  "$bin" build "${args[@]}" --plan-shards "$n" --tile-costs > "$out/$name.plan.json" 2>/dev/null
  for ((i = 0; i < n; i++)); do
    rm -rf "$out/store"
    ${BENCH_LOCK:+flock "$BENCH_LOCK"} "$bin" build "${args[@]}" -j "$threads" --json --tile-costs --shard "$i/$n" \
      --out "$out/store" > "$out/$name.shard$i.json" 2> "$out/$name.shard$i.log"
  done
  rm -rf "$out/store"
  python3 - "$out" "$name" "$n" <<'PY'
import json, sys
out, name, n = sys.argv[1], sys.argv[2], int(sys.argv[3])
plan = json.load(open(f"{out}/{name}.plan.json"))
cpu = [sum(c["cpu_seconds"] for c in json.load(open(f"{out}/{name}.shard{i}.json"))["tile_costs"]) for i in range(n)]
print(f"| {name} | {plan['tiles']['with_triangles']} | {plan['imbalance']:.3f} | "
      f"{max(cpu) / (sum(cpu) / n):.3f} ({', '.join(f'{c:.1f}' for c in cpu)}) |")
PY
done
echo "(per-tile CPU seconds: bench/tile_cost_fit.py NAME=$out/NAME.plan.json,$out/NAME.shard0.json,... )"
