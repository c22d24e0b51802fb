#!/usr/bin/env bash
# Mixed loopback load on `shadowtiles serve` (issue 18): wrk with valid requests plus a bounded
# hostile driver, for DURATION seconds. Checks, each able to fail the run (exit 1):
#   - no crash: the server is alive at the end and exits 0 on SIGTERM;
#   - no 5xx: wrk saw no non-2xx answer to its valid requests, and the server's own counts
#     (/metrics, every route and client) hold no 5xx;
#   - every hostile request (bench/mixed_load_driver.py) got a 4xx within its bound (none hang);
#   - sampled answers (point GETs and binary batches at fixed points, every method, asked during the
#     load) equal the local decoder's (`shadowtiles query STORE`) for the same points;
#   - RSS at the end within 10 % of RSS once the tile cache has filled (cache_bytes is small, so
#     the cache fills early and then evicts all through the run).
# Store: the bunny at 1024^2 in 128^2 tiles, raw + mh + dagmh (built first, a few seconds).
# Server: 2 threads, max_connections 64, cache_bytes 4 MiB, read/body timeouts 2 s.
#
# Usage: bench/mixed_load.sh [BUILD_DIR] [SCENE]      (defaults: build, ../shared/scenes/bunny/stanford-bunny.obj)
# Env: DURATION (seconds, default 60), CONNECTIONS (wrk keep-alive connections, default 32),
#      SUMMARY (write the driver's JSON summary there too).
# Prints one line starting "mixed load:" with the figures (scripts/reliability.sh reads it).
set -euo pipefail
cd "$(dirname "$0")/.."
# shellcheck source=bench/serve_start.sh
source bench/serve_start.sh
BUILD_DIR=${1:-build}
SCENE=${2:-../shared/scenes/bunny/stanford-bunny.obj}
DURATION=${DURATION:-60}
CONNECTIONS=${CONNECTIONS:-32}
CLI="$BUILD_DIR/cli/shadowtiles"

require_load_tools "$CLI"

WORK=$(mktemp -d)
SERVER_PID=""
WRK_PID=""
cleanup() {
  [ -n "$WRK_PID" ] && kill "$WRK_PID" 2> /dev/null || true
  if [ -n "$SERVER_PID" ] && kill -0 "$SERVER_PID" 2> /dev/null; then
    kill -KILL "$SERVER_PID" 2> /dev/null || true
  fi
  rm -rf "$WORK"
}
trap cleanup EXIT INT TERM

"$CLI" build "$SCENE" --up y --resolution 1024 --tile 128 --method raw,mh,dagmh --out "$WORK/store" -q > /dev/null
cat > "$WORK/serve.json" << 'EOF'
{"threads": 2, "max_connections": 64, "cache_bytes": 4194304, "read_timeout_s": 2, "body_timeout_s": 2,
 "write_timeout_s": 5, "reload_poll_s": 0}
EOF
start_serve "$CLI" "$WORK/store" "$WORK/serve.log" --config "$WORK/serve.json" || exit 1
curl -sf "$BASE/v1/meta" > "$WORK/meta.json"

# wrk's valid mix: point GETs (a tenth with a 3x3 PCF kernel), tile GETs, 8-point JSON batches,
# every stored method.
python3 - "$WORK" << 'EOF'
import json, sys
work = sys.argv[1]
s = json.load(open(f"{work}/meta.json"))["shadow"]
lo, hi = s["world_bounds"]["min"], s["world_bounds"]["max"]
methods = ", ".join(f'"{m}"' for m in s["methods"])
open(f"{work}/mixed.lua", "w").write(f"""
math.randomseed(3)
local methods = {{{methods}}}
local lo = {{{lo[0]!r}, {lo[1]!r}, {lo[2]!r}}}
local hi = {{{hi[0]!r}, {hi[1]!r}, {hi[2]!r}}}
local function coord(i) return lo[i] + math.random() * (hi[i] - lo[i]) end
request = function()
  local r = math.random()
  local m = methods[math.random(#methods)]
  if r < 0.55 then
    local pcf = math.random() < 0.1 and "&pcf=3" or ""
    return wrk.format("GET", string.format("/v1/shadow?x=%.9g&y=%.9g&z=%.9g&method=%s%s", coord(1), coord(2), coord(3), m, pcf))
  elseif r < 0.85 then
    return wrk.format("GET", string.format("/v1/tiles/%s/{s["tile_level"]}/%d/%d", m,
                      math.random(0, {s["tiles_per_side"] - 1}), math.random(0, {s["tiles_per_side"] - 1})))
  end
  local pts = {{}}
  for i = 1, 8 do pts[i] = string.format("[%.9g,%.9g,%.9g]", coord(1), coord(2), coord(3)) end
  return wrk.format("POST", "/v1/shadow", {{["Content-Type"] = "application/json"}},
                    string.format('{{"points":[%s],"method":"%s"}}', table.concat(pts, ","), m))
end
""")
EOF

echo "== mixed load on $BASE for ${DURATION}s: wrk -t2 -c$CONNECTIONS (valid requests) + hostile driver; $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg)"
wrk -t2 -c"$CONNECTIONS" -d"${DURATION}s" --timeout 5s -s "$WORK/mixed.lua" "$BASE" > "$WORK/wrk.out" 2>&1 &
WRK_PID=$!
failed=0
python3 bench/mixed_load_driver.py --port "$PORT" --pid "$SERVER_PID" --store "$WORK/store" --cli "$CLI" \
  --duration "$DURATION" --json "$WORK/summary.json" > "$WORK/driver.out" 2>&1 || failed=1
wait "$WRK_PID" || failed=1
WRK_PID=""

wrk_requests=$(awk '/requests in/ {print $1}' "$WORK/wrk.out")
wrk_rps=$(awk '/Requests\/sec/ {print $2}' "$WORK/wrk.out")
wrk_non2xx=$(awk '/Non-2xx or 3xx responses/ {print $NF}' "$WORK/wrk.out")
wrk_socket_errors=$(awk '/Socket errors/ {sub(/.*Socket errors: /, ""); print}' "$WORK/wrk.out")
[ -n "${wrk_non2xx}" ] && failed=1
# wrk's timeouts are answers slower than 5 s: a failure; connect/read/write errors too.
[ -n "${wrk_socket_errors}" ] && failed=1
[ -n "$wrk_requests" ] || { failed=1; wrk_requests=0; }

alive=yes
if kill -0 "$SERVER_PID" 2> /dev/null; then
  server_5xx=$(curl -sf "$BASE/metrics" | awk -F'[{}]' '/^shadowtiles_http_requests_total/ && $2 ~ /status="5/ {split($3, a, " "); n += a[2]} END {print n + 0}')
  [ "$server_5xx" -eq 0 ] || failed=1
  kill -TERM "$SERVER_PID"
  exit_code=0
  wait "$SERVER_PID" || exit_code=$?
  [ "$exit_code" -eq 0 ] || failed=1
else
  alive=no
  server_5xx="?"
  exit_code="crashed"
  failed=1
fi
SERVER_PID=""
grep -q "handler failed" "$WORK/serve.log" && failed=1

cat "$WORK/driver.out"
echo "wrk: ${wrk_requests} valid requests (${wrk_rps} req/s), non-2xx ${wrk_non2xx:-0}, socket errors ${wrk_socket_errors:-none}"
echo "server: alive at the end ${alive}, exit on SIGTERM ${exit_code}, 5xx answers (all clients) ${server_5xx}"
[ -n "${SUMMARY:-}" ] && cp "$WORK/summary.json" "$SUMMARY"
[ "$failed" -eq 0 ] && result=pass || result=FAIL
python3 - "$WORK/summary.json" "$result" "$DURATION" "$wrk_requests" "$wrk_rps" "${wrk_non2xx:-0}" "$server_5xx" "$exit_code" << 'EOF' || true
import json, sys
result, duration, wrk_requests, wrk_rps, non2xx, server_5xx, exit_code = sys.argv[2:]
d = json.load(open(sys.argv[1]))
print(f"mixed load: {result}, {duration} s: wrk {wrk_requests} valid requests ({wrk_rps} req/s, {non2xx} non-2xx), "
      f"{d['hostile_requests']} hostile requests of {len(d['hostile_by_kind'])} kinds ({len(d['failures'])} failures), "
      f"5xx {server_5xx}, {d['compared']} sampled answers equal to the decoder's ({d['differ']} differ), "
      f"RSS {d['rss_filled_kib'] / 1024:.1f} MiB once the cache filled -> {d['rss_end_kib'] / 1024:.1f} MiB at the end "
      f"({d['rss_change'] * 100:+.1f} %, peak {d['rss_peak_kib'] / 1024:.1f} MiB), exit on SIGTERM {exit_code}")
EOF
if [ "$failed" -ne 0 ]; then
  echo "mixed load: FAIL (see above)" >&2
  sed -n '/Running/,$p' "$WORK/wrk.out" >&2
  tail -20 "$WORK/serve.log" >&2
  exit 1
fi
