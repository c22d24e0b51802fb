#!/usr/bin/env bash
# Benchmark (not a test) of the inspector's /v1/render on a big store (issue 17): the zoom-0 tile of
# every layer, cold (first request after the server opened the store: previews read from LMDB and
# decoded) and warm (previews cached), with the server's RSS before and after (VmRSS, VmHWM from
# /proc). Budget: zoom 0 of a 65536^2 store under 200 ms and under 64 MiB extra RSS.
#
# Usage: bench/render_zoom0.sh STORE [BUILD_DIR]
#   STORE: e.g. built with
#     nice -n 10 build/cli/shadowtiles build ../shared/scenes/oahu/oahu_w158n21.ply --sun 135,45 \
#         --resolution 65536 --tile 4096 --method mh,mmh --out out/oahu64k.store
# Prints one line per request and a summary. The server is stopped (by its PID) at the end.
set -euo pipefail
STORE=$1
BUILD_DIR=${2:-build}
CLI="$BUILD_DIR/cli/shadowtiles"
work=$(mktemp -d)
"$CLI" serve "$STORE" --port 0 > "$work/out" 2> "$work/log" &
pid=$!
trap 'kill $pid 2>/dev/null || true; wait $pid 2>/dev/null || true; rm -rf "$work"' EXIT
url=""
for _ in $(seq 200); do
  url=$(sed -n 's/^listening on \(http:[^ ]*\).*/\1/p' "$work/out" | head -1)
  [ -n "$url" ] && curl -sf "$url/healthz" > /dev/null 2>&1 && break
  url=""; sleep 0.1
done
[ -n "$url" ] || { cat "$work/log"; exit 1; }
rss() { awk -v k="$1:" '$1 == k {print $2}' /proc/$pid/status; }
methods=$(curl -s "$url/v1/meta" | python3 -c 'import json,sys; print(" ".join(json.load(sys.stdin)["shadow"]["methods"]))')
resolution=$(curl -s "$url/v1/meta" | python3 -c 'import json,sys; print(json.load(sys.stdin)["shadow"]["resolution"])')
first=${methods%% *}
second=$(echo "$methods" | awk '{print $NF}')
rss0=$(rss VmRSS)
echo "store $STORE: ${resolution}^2, methods $methods; server RSS after open ${rss0} kB"
worst=0
for pass in cold warm; do
  for q in "value" "depth" "coverage" "bytes" "diff&against=$second"; do
    for m in $methods; do
      t=$(curl -s -D "$work/headers" -o "$work/tile.png" -w '%{time_total}' "$url/v1/render/$m/0/0/0.png?layer=$q")
      src=$(tr -d '\r' < "$work/headers" | awk -F': ' 'tolower($1)=="x-shadowtiles-source"{s=$2} tolower($1)=="server-timing"{t=$2} END{print s "  " t}')
      ms=$(python3 -c "print(f'{$t*1000:.1f}')")
      [ "$pass" = cold ] && worst=$(python3 -c "print(max($worst, $ms))")
      printf '%-5s %-6s %-22s %8s ms (curl)  %7d bytes  %s\n' "$pass" "$m" "$q" "$ms" "$(stat -c %s "$work/tile.png")" "$src"
    done
  done
done
rss1=$(rss VmRSS); hwm=$(rss VmHWM)
echo "summary: slowest cold zoom-0 render ${worst} ms; RSS ${rss0} -> ${rss1} kB (+$(( (rss1 - rss0) / 1024 )) MiB), peak ${hwm} kB (+$(( (hwm - rss0) / 1024 )) MiB over the opened store)"
