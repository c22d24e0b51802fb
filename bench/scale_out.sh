#!/usr/bin/env bash
# Figures of docs/scale-out.md, in one run so the ratios compare like with like on a shared machine:
#   1. shard balance: the planned max/mean work of N shards on every shared scene (--plan-shards);
#   2. one scene built on one machine, then as N shards (each after the other, same thread count),
#      then merged: measured per-shard work (thread-seconds) and wall max/mean, one-machine wall over
#      the N-machine wall (slowest shard + merge), merge MB/s of blobs and its peak RSS, store-diff;
#   3. per-texel cost and bytes, extrapolated to 64K², 256K² and 1M² on 1, 16 and 256 workers.
# Usage: bench/scale_out.sh SHADOWTILES [OUT_DIR]
#   env: SCENE (fzk_haus/fzk_haus.obj) UP (y) RES (16384) TILE (1024) METHODS (mmh,dagmh) SHARDS (4)
#        THREADS (2) PLANS (1: part 1 on every scene; 0: skip)
# Run it niced on a shared machine: nice -n 10 bench/scale_out.sh build/cli/shadowtiles
set -euo pipefail
bin=$(realpath "$1")
out=${2:-$(mktemp -d /tmp/st-scale.XXXXXX)}
here=$(cd "$(dirname "$0")/.." && pwd)
scenes=$here/../shared/scenes
scene=${SCENE:-fzk_haus/fzk_haus.obj}
up=${UP:-y}
res=${RES:-16384}
tile=${TILE:-1024}
methods=${METHODS:-mmh,dagmh}
shards=${SHARDS:-4}
threads=${THREADS:-2}
py=/usr/bin/python3
mkdir -p "$out"
common=(--sun 135,45 --resolution "$res" --tile "$tile")

if [ "${PLANS:-1}" = 1 ]; then
  echo "## Shard balance (planned work: builder/shard_plan.cpp, rays + triangle refs + a coarse depth map per tile), ${res}², tiles ${tile}, N = $shards"
  echo "| scene | tiles with triangles / all | max/mean work |"
  echo "|---|---|---|"
  while read -r name file sup; do
    "$bin" build "$scenes/$file" --up "$sup" "${common[@]}" --plan-shards "$shards" > "$out/plan_$name.json" 2>/dev/null
    "$py" -c "import json,sys; d=json.load(open(sys.argv[1])); t=d['tiles']
print(f\"| {sys.argv[2]} | {t['with_triangles']} / {t['total']} | {d['imbalance']:.3f} |\")" "$out/plan_$name.json" "$name"
  done <<SCENES
bunny bunny/stanford-bunny.obj y
nefertiti nefertiti/nefertiti.obj y
terragen terragen/RealisticTerrain.ter z
fzk_haus fzk_haus/fzk_haus.obj y
oahu oahu/oahu_w158n21.ply z
dragon_res2 dragon_res2/dragon_vrip_res2.ply y
honolulu_airport honolulu_airport/honolulu_airport_harbour.ply z
SCENES
  echo
fi

args=("$scenes/$scene" --up "$up" "${common[@]}" --method "$methods" -j "$threads" --json)
rm -rf "$out/single" "$out"/shard* "$out/merged"
"$bin" build "${args[@]}" --out "$out/single" > "$out/single.json" 2>"$out/single.log"
# The same build at half the resolution: how bytes and work grow per doubling of the side.
half=("$scenes/$scene" --up "$up" --sun 135,45 --resolution $((res / 2)) --tile "$tile" --method "$methods" -j "$threads" --json)
rm -rf "$out/half"
"$bin" build "${half[@]}" --out "$out/half" > "$out/half.json" 2>"$out/half.log"
rm -rf "$out/half"
for ((i = 0; i < shards; i++)); do
  "$bin" build "${args[@]}" --out "$out/shard$i" --shard "$i/$shards" > "$out/shard$i.json" 2>"$out/shard$i.log"
done
shard_dirs=()
for ((i = 0; i < shards; i++)); do shard_dirs+=("$out/shard$i"); done
/usr/bin/time -f "%M" -o "$out/merge.rss" "$bin" merge "${shard_dirs[@]}" --out "$out/merged" --json > "$out/merge.json" 2>"$out/merge.log"
"$bin" store-diff "$out/merged" "$out/single" > "$out/diff.txt"

"$py" - "$out" "$shards" "$scene" "$res" "$tile" "$methods" "$threads" <<'PY'
import json, sys
out, n, scene, res, tile, methods, threads = sys.argv[1], int(sys.argv[2]), *sys.argv[3:]
res, tile = int(res), int(tile)
load = lambda p: json.load(open(f"{out}/{p}"))
single = load("single.json")
shard = [load(f"shard{i}.json") for i in range(n)]
merge = load("merge.json")
rss_kib = int(open(f"{out}/merge.rss").read().split()[-1])

def work(s):  # thread-seconds of the tile pipeline: what a shard's machine spends
    sec = s["seconds"]
    return sum(v for k, v in sec.items() if k.endswith("_thread_sum"))
walls = [s["seconds"]["total"] for s in shard]
works = [work(s) for s in shard]
mean = lambda xs: sum(xs) / len(xs)
merge_wall = merge["seconds"]["total"]
blob_mb = merge["merge"]["blob_bytes_copied"] / 1e6
single_wall = single["seconds"]["total"]
n_wall = max(walls) + merge_wall
print(f"## {scene} {res}², tiles {tile}, {methods}, {threads} threads per build, N = {n}")
print(f"| figure | value |\n|---|---|")
print(f"| shard work (thread-s) max/mean | {max(works)/mean(works):.3f} ({', '.join(f'{w:.1f}' for w in works)}) |")
print(f"| shard wall max/mean | {max(walls)/mean(walls):.3f} ({', '.join(f'{w:.1f}' for w in walls)} s) |")
print(f"| one-machine wall | {single_wall:.1f} s |")
print(f"| N-machine wall (slowest shard + merge) | {n_wall:.1f} s = {max(walls):.1f} + {merge_wall:.2f} |")
print(f"| one-machine / N-machine wall | {single_wall/n_wall:.2f} (ideal {n}) |")
print(f"| sum of shard walls / one-machine wall | {sum(walls)/single_wall:.3f} (sharding overhead; < 1 is noise) |")
print(f"| merge: blobs copied | {blob_mb:.1f} MB at {merge['merge']['blob_mb_per_second']:.0f} MB/s |")
print(f"| merge: seconds | {', '.join(f'{k} {v:.3f}' for k, v in merge['seconds'].items())} |")
print(f"| merge peak RSS | {rss_kib/1024:.0f} MiB |")
print(f"| merged == one-machine (store-diff) | {open(f'{out}/diff.txt').read().strip()} |")

# Extrapolation from the one-machine builds at res/2 and res: work and bytes each follow a power
# of the map side fitted on those two points (work grows with the rays, about side²; bytes grow
# slower, since hierarchies collapse smooth regions: about side^e with e fitted here).
import math
half = load("half.json")
w1, w0 = work(single), work(half)
b1, b0 = sum(single["bytes_by_method"].values()), sum(half["bytes_by_method"].values())
ew, eb = math.log2(w1 / w0), math.log2(b1 / b0)
mbps = merge["merge"]["blob_mb_per_second"]
print()
print(f"## Extrapolated from {scene} at {res//2}² and {res}²: work ~ side^{ew:.2f}, blobs ~ side^{eb:.2f}, merge at {mbps:.0f} MB/s")
print(f"(measured: {w0:.1f} -> {w1:.1f} thread-s, {b0/1e6:.1f} -> {b1/1e6:.1f} MB of blobs)")
print("| map | blobs | thread-hours | N=1 | N=16 | N=256 | merge alone | merge is the bottleneck beyond |")
print("|---|---|---|---|---|---|---|---|")
def fmt(s):
    return f"{s/3600:.1f} h" if s >= 3600 else (f"{s/60:.1f} min" if s >= 60 else f"{s:.0f} s")
for side in (65536, 262144, 1048576):
    f = side / res
    cpu = w1 * f ** ew
    b = b1 * f ** eb
    m = b / 1e6 / mbps
    t = int(threads)
    walls = [cpu / t] + [cpu / (t * workers) + m for workers in (16, 256)]
    print(f"| {side//1024}K² | {b/1e9:.2f} GB | {cpu/3600:.1f} | {' | '.join(fmt(x) for x in walls)} | {fmt(m)} | N = {cpu/(t*m):.0f} |")
print(f"(N workers of {threads} threads each, as measured here; N > 1 adds the merge, which runs after the slowest shard.)")
PY
