# Sourced by the load benchmarks (bench/server_load.sh, bench/mixed_load.sh).
#   require_load_tools CLI
# Exits 2 with what to install or build when wrk, curl, python3 or the CLI is missing.
require_load_tools() {
  local tool
  for tool in wrk curl python3; do
    command -v "$tool" > /dev/null || { echo "needs $tool (apt-get install -y wrk curl python3)" >&2; exit 2; }
  done
  [ -x "$1" ] || { echo "no $1: build first (bash scripts/build.sh)" >&2; exit 2; }
}

# Starts `shadowtiles serve` on a free loopback port and waits until it answers /healthz.
#   start_serve CLI STORE LOG [serve options...]
# Sets SERVER_PID, PORT and BASE (http://127.0.0.1:PORT). On failure prints the server log (if it
# exited) or a message and returns 1; stopping the server stays with the caller's cleanup.
start_serve() {
  local cli=$1 store=$2 log=$3
  shift 3
  "$cli" serve "$store" --port 0 -q "$@" > "$log" 2>&1 &
  SERVER_PID=$!
  PORT=""
  for _ in $(seq 100); do
    PORT=$(sed -n 's/^listening on http:\/\/[^:]*:\([0-9]*\)$/\1/p' "$log" | head -1)
    [ -n "$PORT" ] && break
    kill -0 "$SERVER_PID" 2> /dev/null || { cat "$log" >&2; return 1; }
    sleep 0.1
  done
  [ -n "$PORT" ] || { echo "server did not start" >&2; return 1; }
  BASE="http://127.0.0.1:$PORT"
  for _ in $(seq 100); do curl -sf "$BASE/healthz" > /dev/null && return 0; sleep 0.1; done
  echo "server at $BASE never answered /healthz" >&2
  return 1
}
