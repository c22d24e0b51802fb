#!/usr/bin/env bash
# The inspector's real-browser test (ctest `browser_inspector`, label `browser`): builds a store of
# the shared fzk_haus scene, starts `shadowtiles serve` on a loopback ephemeral port, asks the CLI
# for ground-truth-labelled sample points, then drives Debian's chromium headless with
# playwright-core (inspector_test.mjs). Screenshots go to ARTIFACT_DIR. The server is stopped by PID.
# Usage: run_inspector_test.sh SHADOWTILES_CLI ARTIFACT_DIR [DOCS_SCREENSHOT]
set -euo pipefail
cli="$1"
artifacts="$2"
docs_shot="${3:-}"
here="$(cd "$(dirname "$0")" && pwd)"
scene="$here/../../../shared/scenes/fzk_haus/fzk_haus.obj"
for need in /usr/bin/chromium node "$here/node_modules/playwright-core/package.json" /usr/share/javascript/leaflet/leaflet.js; do
  if [ ! -e "$need" ] && ! command -v "$need" > /dev/null; then
    echo "missing $need: run scripts/install-deps.sh (chromium, libjs-leaflet, nodejs, npm ci in tests/browser)" >&2
    exit 1
  fi
done
[ -f "$scene" ] || { echo "missing shared scene $scene" >&2; exit 1; }
mkdir -p "$artifacts"
work="$(mktemp -d)"
server_pid=""
cleanup() {
  if [ -n "$server_pid" ]; then kill "$server_pid" 2> /dev/null || true; wait "$server_pid" 2> /dev/null || true; fi
  rm -rf "$work"
}
trap cleanup EXIT

"$cli" build "$scene" --up y --sun 135,45 --resolution 2048 --tile 256 --method raw,mh,mmh,dagmh,cpvs,sst \
  --out "$work/haus.store" > "$work/build.log" 2>&1 || { cat "$work/build.log"; exit 1; }
"$cli" query "$work/haus.store" --ground-truth "$scene" --sample 60 --json > "$work/points.json" 2> /dev/null

"$cli" serve "$work/haus.store" --port 0 > "$work/serve.out" 2> "$work/serve.log" &
server_pid=$!
url=""
for _ in $(seq 100); do
  url=$(sed -n 's/^listening on \(http:[^ ]*\).*/\1/p' "$work/serve.out" | head -1)
  [ -n "$url" ] && curl -sf "$url/healthz" > /dev/null 2>&1 && break
  url=""
  sleep 0.1
done
[ -n "$url" ] || { echo "server did not start"; cat "$work/serve.log"; exit 1; }
echo "server at $url"
node "$here/inspector_test.mjs" "$url" "$artifacts" "$work/points.json" $docs_shot
