#!/usr/bin/env bash
# Load benchmark of `shadowtiles serve` on loopback (not a unit test; docs/architecture.md §10, issue 5).
# Builds a store, starts the server (default 2 threads), then measures, each bounded in time:
#   1. single-point GET /v1/shadow at random points of the scene's box   (wrk, Lua)
#   2. tile GET /v1/tiles/{method}/{z}/{x}/{y} over every tile position   (wrk, Lua)
#   3. binary POST /v1/shadow batches of 100k float32 points, per method in BATCH_METHODS: 12 on one
#      keep-alive connection of one curl process (2 warm-up, median of 10; curl's start-up excluded)
#   4. /healthz and a point query on new connections while max_connections - 2 slow clients
#      (trickled headers, stalled bodies) hold connections            (bench/slow_clients.py)
# and prints requests/s, p50/p99 latency and points/s. The server is always killed at the end.
# wrk and the server share the machine: on a 2-core box the figures are a lower bound.
#
# Usage: bench/server_load.sh [BUILD_DIR] [SCENE] [RESOLUTION] [TILE]
#   defaults: build  ../shared/scenes/bunny/stanford-bunny.obj  2048  512
# Env: DURATION (wrk seconds per run, default 10), ROUNDS (alternated rounds of every connection count,
#      default 3; the summary gives medians and their ratios), CONNECTIONS (wrk connection counts to run, default
#      "2 64": one per server thread, then as many keep-alive clients as max_connections: each has
#      its own I/O thread, query work shares the THREADS query slots), THREADS (server, default 2),
#      METHOD (GET rows, default raw), BATCH_METHODS (batch rows, default "raw mh dagmh"), UP (scene up
#      axis, default y), CHECK_P99_MS (when set: issue 18's load line, checked on the medians: at the
#      most connections every GET route keeps p99 under this many ms and at least the fewest
#      connections' req/s; a "keep-alive load:" line says which, and the script exits 1 if not).
set -euo pipefail
cd "$(dirname "$0")/.."
# shellcheck source=bench/serve_start.sh
source bench/serve_start.sh
BUILD_DIR=${1:-build}
SCENE=${2:-../shared/scenes/bunny/stanford-bunny.obj}
RESOLUTION=${3:-2048}
TILE=${4:-512}
DURATION=${DURATION:-10}
ROUNDS=${ROUNDS:-3}
CONNECTIONS=${CONNECTIONS:-2 64}
THREADS=${THREADS:-2}
METHOD=${METHOD:-raw}
BATCH_METHODS=${BATCH_METHODS:-raw mh dagmh}
UP=${UP:-y}
CHECK_P99_MS=${CHECK_P99_MS:-}
CLI="$BUILD_DIR/cli/shadowtiles"

require_load_tools "$CLI"

WORK=$(mktemp -d)
SERVER_PID=""
cleanup() {
  if [ -n "$SERVER_PID" ] && kill -0 "$SERVER_PID" 2> /dev/null; then
    kill -TERM "$SERVER_PID" 2> /dev/null || true
    for _ in $(seq 50); do kill -0 "$SERVER_PID" 2> /dev/null || break; sleep 0.1; done
    kill -KILL "$SERVER_PID" 2> /dev/null || true
  fi
  rm -rf "$WORK"
}
trap cleanup EXIT INT TERM

BUILD_METHODS=$(echo "$METHOD $BATCH_METHODS" | tr ' ' '\n' | awk 'NF && !seen[$0]++' | paste -sd, -)
echo "== building $SCENE at ${RESOLUTION}^2, tiles ${TILE}^2, methods $BUILD_METHODS"
"$CLI" build "$SCENE" --up "$UP" --resolution "$RESOLUTION" --tile "$TILE" --method "$BUILD_METHODS" \
  --out "$WORK/store" -q > /dev/null

start_serve "$CLI" "$WORK/store" "$WORK/serve.log" --threads "$THREADS" || exit 1
curl -sf "$BASE/v1/meta" > "$WORK/meta.json"
echo "== server on $BASE, $THREADS threads, $(nproc) cores (wrk shares them)"

# Lua scripts for wrk: varied points inside the scene's world box, varied tile positions.
python3 - "$WORK" "$METHOD" << 'EOF'
import json, sys
work, method = sys.argv[1], sys.argv[2]
meta = json.load(open(f"{work}/meta.json"))
s = meta["shadow"]
lo, hi = s["world_bounds"]["min"], s["world_bounds"]["max"]
open(f"{work}/points.lua", "w").write(f"""
math.randomseed(42)
local lo = {{{lo[0]!r}, {lo[1]!r}, {lo[2]!r}}}
local hi = {{{hi[0]!r}, {hi[1]!r}, {hi[2]!r}}}
request = function()
  local x = lo[1] + math.random() * (hi[1] - lo[1])
  local y = lo[2] + math.random() * (hi[2] - lo[2])
  local z = lo[3] + math.random() * (hi[3] - lo[3])
  return wrk.format("GET", string.format("/v1/shadow?x=%.9g&y=%.9g&z=%.9g&method={method}", x, y, z))
end
""")
n, z = s["tiles_per_side"], s["tile_level"]
open(f"{work}/tiles.lua", "w").write(f"""
math.randomseed(7)
request = function()
  return wrk.format("GET", string.format("/v1/tiles/{method}/{z}/%d/%d", math.random(0, {n - 1}), math.random(0, {n - 1})))
end
""")
# 100k points in the box, little-endian float32 x, y, z.
import random, struct
random.seed(1)
with open(f"{work}/batch.bin", "wb") as f:
    for _ in range(100000):
        f.write(struct.pack("<3f", *(random.uniform(lo[i], hi[i]) for i in range(3))))
EOF

run_wrk() {  # name script connections round
  local out
  out=$(wrk -t2 -c"$3" -d"${DURATION}s" --latency -s "$2" "$BASE")
  local rps p50 p99 errors
  rps=$(echo "$out" | awk '/Requests\/sec/ {print $2}')
  p50=$(echo "$out" | awk '$1 == "50%" {print $2}')
  p99=$(echo "$out" | awk '$1 == "99%" {print $2}')
  errors=$(echo "$out" | awk '/Non-2xx|Socket errors/ {print}' | tr '\n' ' ')
  printf "%-28s %10s req/s   p50 %-9s p99 %-9s %s\n" "$1" "$rps" "$p50" "$p99" "${errors:-no errors}"
  printf "%s\t%s\t%s\t%s\t%s\n" "$4" "$1" "$3" "$rps" "$p99" >> "$WORK/wrk_rows"
}

# Rounds alternate the connection counts (2, 64, 2, 64, ...) so that a shared machine's drift falls
# on both sides of each ratio; the summary divides medians over the rounds.
for round in $(seq "$ROUNDS"); do
  for c in $CONNECTIONS; do
    echo "== round $round/$ROUNDS: wrk -t2 -c$c -d${DURATION}s"
    run_wrk "GET /v1/shadow (point)" "$WORK/points.lua" "$c" "$round"
    run_wrk "GET /v1/tiles (blob)" "$WORK/tiles.lua" "$c" "$round"
  done
done
python3 - "$WORK/wrk_rows" "$CHECK_P99_MS" "$WORK/load_line_failed" << 'EOF'
import collections, statistics, sys
rows = collections.defaultdict(list)  # (route, connections) -> [(rps, p99 text)]
for line in open(sys.argv[1]):
    _, route, connections, rps, p99 = line.rstrip("\n").split("\t")
    rows[route, int(connections)].append((float(rps), p99))
def ms(text):  # wrk prints 812.00us, 1.23ms, 2.10s
    for unit, scale in (("us", 1e-3), ("ms", 1.0), ("s", 1e3)):
        if text.endswith(unit):
            return float(text[: -len(unit)]) * scale
    return float("nan")
rounds = max(len(v) for v in rows.values())
print(f"== medians over {rounds} alternated rounds (ratio: of the fewest connections' median)")
line_parts, line_held = [], True  # CHECK_P99_MS: the most connections' medians of every route
for route in dict.fromkeys(route for route, _ in rows):
    counts = sorted(c for r, c in rows if r == route)
    base = statistics.median(rps for rps, _ in rows[route, counts[0]])
    for c in counts:
        rate = statistics.median(rps for rps, _ in rows[route, c])
        p99s = [ms(p) for _, p in rows[route, c]]
        print(f"{route:<28} {c:>3} connections  median {rate:>9.0f} req/s"
              f"  ({rate / base:.2f})  p99 median {statistics.median(p99s):.2f} ms,"
              f" worst {max(p99s):.2f} ms")
    if sys.argv[2]:  # c is the most connections here
        line_held &= rate / base >= 1.0 and statistics.median(p99s) < float(sys.argv[2])
        line_parts.append(f"{route.split(' (')[0]} {c}/{counts[0]} connections req/s {rate / base:.2f},"
                          f" p99 {statistics.median(p99s):.2f} ms")
if sys.argv[2]:
    print(f"keep-alive load: {'; '.join(line_parts)} (medians of {rounds} rounds;"
          f" line: p99 < {float(sys.argv[2]):g} ms and ratio >= 1): {'pass' if line_held else 'FAIL'}")
    if not line_held:
        open(sys.argv[3], "w").close()
EOF

echo "== binary batches of 100k points (POST application/octet-stream), 12 per method on one keep-alive connection"
for batch_method in $BATCH_METHODS; do
  urls=()
  for _ in $(seq 12); do urls+=(-o /dev/null "$BASE/v1/shadow?method=$batch_method"); done
  # "Expect:" off: time the server, not curl's 100-continue round trip. curl posts the body to every URL.
  curl -sf -w "%{time_total} %{size_download}\n" -H "Expect:" -H "Content-Type: application/octet-stream" \
    --data-binary "@$WORK/batch.bin" "${urls[@]}" > "$WORK/batch_times"
  python3 - "$WORK/batch_times" "$batch_method" << 'EOF'
import statistics, sys
rows = [line.split() for line in open(sys.argv[1])]
if len(rows) != 12 or any(int(float(size)) != 400000 for _, size in rows):
    sys.exit(f"batch answers missing or of the wrong size: {rows}")
times = sorted(float(t) for t, _ in rows[2:])  # the first two open the connection and decode tiles
print(f"{'POST /v1/shadow 100k ' + sys.argv[2]:<28} median {statistics.median(times) * 1e3:.1f} ms  best {times[0] * 1e3:.1f} ms"
      f"   {100000 / statistics.median(times) / 1e6:.2f} M points/s (median), {100000 / times[0] / 1e6:.2f} best")
EOF
done
MAX_CONNECTIONS=$("$CLI" serve "$WORK/store" --threads "$THREADS" --print-config 2> /dev/null |
  python3 -c 'import json, sys; print(json.load(sys.stdin)["max_connections"])')
POINT=$(python3 -c 'import json, sys; b = json.load(open(sys.argv[1]))["shadow"]["world_bounds"]; print("/v1/shadow?x=%.9g&y=%.9g&z=%.9g" % tuple((lo + hi) / 2 for lo, hi in zip(b["min"], b["max"])))' "$WORK/meta.json")
echo "== slow clients: $((MAX_CONNECTIONS - 2)) of max_connections $MAX_CONNECTIONS held (half trickle headers, half stall bodies)"
python3 bench/slow_clients.py 127.0.0.1 "$PORT" $((MAX_CONNECTIONS - 2)) 50 "$POINT"
curl -sf "$BASE/metrics" | grep -E '^shadowtiles_(points_answered_total|tile_cache_(hits|misses)_total|rejections_total)' || true
if [ -e "$WORK/load_line_failed" ]; then
  echo "the keep-alive load line (CHECK_P99_MS=$CHECK_P99_MS) does not hold" >&2
  exit 1
fi
