#!/usr/bin/env bash
# Serving replicas behind nginx (issue 16), all on loopback: two `shadowtiles serve` replicas of one
# store behind nginx with config/nginx-replicas.conf. Checks: the second GET of an immutable tile URL
# is a cache hit with a byte-identical body and ETag; If-None-Match gives 304; both replicas answer
# /v1/shadow (X-Shadow-Replica); SIGKILL of one replica during a stream of GETs loses none.
# With --bench, also prints tile GETs/s through nginx (wrk), the cache hit ratio and the requests
# failed during a replica kill under wrk load. Exit 77 (skipped) without nginx, unless CI=true.
# Usage: nginx_replicas_test.sh SHADOWTILES_BINARY SOURCE_DIR [--bench]
set -uo pipefail
bin=$1
src=$2
bench=${3:-}
t=$(mktemp -d /tmp/st-nginx.XXXXXX)
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill "$p" 2>/dev/null; done
  wait 2>/dev/null
  rm -rf "$t"
}
trap cleanup EXIT
fail() { echo "FAIL: $*" >&2; for f in "$t"/*.log; do [ -f "$f" ] && { echo "== $f"; tail -5 "$f"; }; done >&2; exit 1; }
nginx_bin=$(command -v nginx || echo /usr/sbin/nginx)
if [ ! -x "$nginx_bin" ]; then
  [ "${CI:-}" = "true" ] && fail "nginx not installed (scripts/install-deps.sh installs it)"
  echo "SKIPPED: nginx not installed" >&2
  exit 77
fi

"$bin" build "$src/../shared/scenes/fzk_haus/fzk_haus.obj" --up y --sun 135,45 --resolution 2048 --tile 512 \
  --method mh,mmh --out "$t/store" >/dev/null 2>"$t/build.log" || fail "build"
free_port() { python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])'; }
pa=$(free_port); pb=$(free_port); pn=$(free_port)
start_replica() {  # name port
  echo "{\"replica_name\": \"$1\", \"reload_poll_s\": 0, \"threads\": 2}" > "$t/$1.json"
  "$bin" serve "$t/store" --config "$t/$1.json" --port "$2" >"$t/$1.log" 2>&1 &
  pids+=($!)
  eval "pid_$1=$!"
}
start_replica a "$pa"
start_replica b "$pb"
for port in "$pa" "$pb"; do
  for _ in $(seq 1 100); do curl -sf "http://127.0.0.1:$port/healthz" >/dev/null && break; sleep 0.1; done
  curl -sf "http://127.0.0.1:$port/healthz" >/dev/null || fail "replica on $port did not come up"
done
sed -e "s|@PREFIX@|$t|g" -e "s|@LISTEN@|127.0.0.1:$pn|g" -e "s|@REPLICA_A@|127.0.0.1:$pa|g" \
  -e "s|@REPLICA_B@|127.0.0.1:$pb|g" "$src/config/nginx-replicas.conf" > "$t/nginx.conf"
# As root, nginx's workers would run as nobody and could not write the cache under the test's
# private directory: keep them as the test's user.
[ "$(id -u)" -eq 0 ] && sed -i '1i user root;' "$t/nginx.conf"
# In the foreground (daemon off) as this script's child, so cleanup stops exactly this nginx.
"$nginx_bin" -p "$t" -c "$t/nginx.conf" -e "$t/error.log" -t -q || fail "nginx rejects the config"
"$nginx_bin" -p "$t" -c "$t/nginx.conf" -e "$t/error.log" -g 'daemon off;' &
pids+=($!)
proxy=http://127.0.0.1:$pn
for _ in $(seq 1 50); do curl -sf "$proxy/healthz" >/dev/null && break; sleep 0.1; done
curl -sf "$proxy/healthz" >/dev/null || fail "nginx did not come up on $pn"

build_id=$(curl -sf "$proxy/v1/meta" | python3 -c 'import json,sys; print(json.load(sys.stdin)["shadow"]["build_id"])') ||
  fail "no meta through nginx"
tile=""
for xy in 1/1 2/2 1/2 2/1 0/0 3/3 0/1 1/0; do
  url="/v1/builds/$build_id/tiles/mmh/2/$xy"
  [ "$(curl -s -o /dev/null -w '%{http_code}' "http://127.0.0.1:$pa$url")" = 200 ] && { tile=$url; break; }
done
[ -n "$tile" ] || fail "no stored tile found"
curl -s -D "$t/h1" -o "$t/b1" "$proxy$tile"
curl -s -D "$t/h2" -o "$t/b2" "$proxy$tile"
header() { grep -i "^$1:" "$2" | head -n 1 | cut -d' ' -f2- | tr -d '\r'; }
[ "$(header X-Cache-Status "$t/h1")" = MISS ] || fail "first GET not a MISS: $(header X-Cache-Status "$t/h1")"
[ "$(header X-Cache-Status "$t/h2")" = HIT ] || fail "second GET not a HIT: $(header X-Cache-Status "$t/h2")"
cmp -s "$t/b1" "$t/b2" || fail "cached body differs"
direct=$(curl -s "http://127.0.0.1:$pb$tile" | sha256sum)
[ "$(sha256sum < "$t/b2")" = "$direct" ] || fail "cached body differs from the replica's blob"
etag=$(header ETag "$t/h1")
[ -n "$etag" ] && [ "$etag" = "$(header ETag "$t/h2")" ] || fail "ETag missing or changed: '$etag'"
[ -n "$(header X-Shadow-Replica "$t/h2")" ] || fail "no X-Shadow-Replica on the cached answer"
code=$(curl -s -o /dev/null -w '%{http_code}' -H "If-None-Match: $etag" "$proxy$tile")
[ "$code" = 304 ] || fail "If-None-Match gave $code, expected 304"
echo "cache: MISS then HIT, same body and ETag $etag, If-None-Match -> 304"

# /v1/shadow is not cached: round robin reaches both replicas.
seen=""
for i in $(seq 1 20); do
  r=$(curl -s -D - -o /dev/null "$proxy/v1/shadow?x=6&y=0.1&z=-5&method=mmh" | grep -i '^X-Shadow-Replica:' | cut -d' ' -f2 | tr -d '\r')
  seen="$seen $r"
done
echo "$seen" | grep -qw a && echo "$seen" | grep -qw b || fail "/v1/shadow not answered by both replicas: $seen"
echo "both replicas answer /v1/shadow"

# Kill replica a in the middle of a stream of GETs: nginx retries on b, no GET is lost.
failed=0
total=0
for i in $(seq 1 300); do
  [ "$i" = 100 ] && kill -9 "$pid_a"
  code=$(curl -s -o /dev/null -w '%{http_code}' "$proxy/v1/shadow?x=6&y=0.1&z=-5&method=mmh")
  total=$((total + 1))
  [ "$code" = 200 ] || failed=$((failed + 1))
done
echo "replica kill: $failed of $total GETs failed"
[ "$failed" = 0 ] || fail "$failed GETs lost while a replica died"

if [ "$bench" = "--bench" ]; then
  # Figures for docs/scale-out.md: one run, so the ratios compare like with like on a noisy machine.
  wrk_summary() {  # label, wrk args...: requests/s and failed requests (non-2xx/3xx + socket errors)
    local label=$1 out rps bad
    shift
    out=$(wrk "$@")
    rps=$(grep -o 'Requests/sec: *[0-9.]*' <<<"$out" | grep -o '[0-9.]*$')
    bad=$(grep -o 'Non-2xx or 3xx responses: *[0-9]*' <<<"$out" | grep -o '[0-9]*$')
    errs=$(grep -o 'Socket errors: .*' <<<"$out" | grep -o '[0-9]\+' | awk '{s += $1} END {print s + 0}')
    echo "$label: ${rps:-?} requests/s, $(grep -o '[0-9]* requests in' <<<"$out" | grep -o '^[0-9]*') requests, ${bad:-0} non-2xx, ${errs:-0} socket errors"
  }
  start_replica a "$pa"
  for _ in $(seq 1 100); do curl -sf "http://127.0.0.1:$pa/healthz" >/dev/null && break; sleep 0.1; done
  sleep 6  # past fail_timeout: nginx takes replica a back
  : > "$t/access.log"; kill -USR1 "$(cat "$t/nginx.pid")"; sleep 0.5
  # Every stored tile URL of the map, fetched in turn (wrk script), so misses happen once each.
  urls=$(for x in 0 1 2 3; do for y in 0 1 2 3; do for m in mh mmh; do echo "/v1/builds/$build_id/tiles/$m/2/$x/$y"; done; done; done)
  { echo 'local paths = {'; for u in $urls; do echo "\"$u\","; done; echo '}'
    echo 'local i = 0'; echo 'request = function() i = i % #paths + 1; return wrk.format("GET", paths[i]) end'; } > "$t/tiles.lua"
  echo "wrk -t2 -c16 -d10s each; $(echo "$urls" | wc -l) tile URLs; /v1/shadow point queries"
  wrk_summary "tile GETs through nginx (2 replicas, cache)" -t2 -c16 -d10s -s "$t/tiles.lua" "$proxy"
  sleep 0.5
  hits=$(grep -c ' HIT ' "$t/access.log"); all=$(grep -c '/tiles/' "$t/access.log")
  echo "cache hit ratio (tile GETs): $hits / $all"
  wrk_summary "tile GETs straight to one replica" -t2 -c16 -d10s -s "$t/tiles.lua" "http://127.0.0.1:$pa"
  wrk_summary "/v1/shadow through nginx (2 replicas)" -t2 -c16 -d10s "$proxy/v1/shadow?x=6&y=0.1&z=-5&method=mmh"
  wrk_summary "/v1/shadow straight to one replica" -t2 -c16 -d10s "http://127.0.0.1:$pa/v1/shadow?x=6&y=0.1&z=-5&method=mmh"
  (sleep 3; kill -9 "$pid_b") &
  wrk_summary "/v1/shadow through nginx, replica b SIGKILLed at 3 s of 10" -t2 -c16 -d10s \
    "$proxy/v1/shadow?x=6&y=0.1&z=-5&method=mmh"
fi
echo "PASS: nginx replicas"
