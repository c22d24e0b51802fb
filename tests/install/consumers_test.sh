#!/usr/bin/env bash
# Install test (ctest Install.ConsumersMatchCli): builds two stores of the terragen shared scene,
# installs the build into a temporary prefix, checks the shared libraries' dependencies (no Embree,
# no assimp) and soname, builds and runs the three consumers of examples/ against that prefix, and
# requires their answers on 10,000 terrain receivers to equal `shadowtiles query --json` for mh,
# mmh and dagmh, from the store and (C, Python) from `shadowtiles serve` on loopback. Then runs the Python terrain example (PNG) and checks Python errors carry the
# library's message.   Usage: consumers_test.sh SOURCE_DIR BUILD_DIR
set -euo pipefail
trap 'echo "$(basename "$0"): failed at line $LINENO: $BASH_COMMAND" >&2' ERR
src=$1 build=$2
py=/usr/bin/python3  # Debian's interpreter with python3-numpy and python3-matplotlib
cli=$build/cli/shadowtiles
scene=$src/../shared/scenes/terragen/RealisticTerrain.ply
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
prefix=$tmp/prefix
if [[ "$(dpkg-query -W -f='${Status}' shadowtiles 2>/dev/null || true)" == *"install ok installed"* ]]; then
  echo "FAIL: the shadowtiles package is installed in /usr: the consumers could use it instead of the prefix"; exit 1
fi

echo "== stores"
"$cli" -q build "$scene" -o "$tmp/sun" --sun 135,20 -r 1024 --tile 256 -m mh,mmh,dagmh --heightfield '*' >/dev/null
"$cli" -q build "$scene" -o "$tmp/top" --light-dir 0,0,-1 -r 512 --tile 256 -m raw --heightfield '*' >/dev/null

echo "== install into $prefix"
cmake --install "$build" --prefix "$prefix" >/dev/null
libdir=$prefix/lib
for lib in "$libdir"/libshadowtiles.so.1 "$libdir"/libshadowtiles_client.so.0.1; do
  [ -e "$lib" ] || { echo "missing $lib"; exit 1; }
  if ldd "$lib" | grep -Ei 'embree|assimp'; then echo "FAIL: $lib links the builder's dependencies"; exit 1; fi
done
dynamic_section=$(objdump -p "$libdir/libshadowtiles.so.1")  # captured: grep -q on a pipe races SIGPIPE under pipefail
grep -q 'SONAME *libshadowtiles.so.1$' <<<"$dynamic_section"
exported=$(nm -D --defined-only "$libdir/libshadowtiles.so.1" | awk '$2 == "T" {print $3}' | grep -cv '^shadowtiles_' || true)
[ "$exported" -eq 0 ] || { echo "FAIL: libshadowtiles.so.1 exports $exported non-API functions"; exit 1; }
[ -f "$prefix/include/shadowtiles.h" ] && [ -f "$prefix/include/shadowtiles/client/shadow_map.hpp" ]
[ -f "$libdir/cmake/shadowtiles/shadowtilesConfig.cmake" ] && [ -f "$libdir/pkgconfig/shadowtiles.pc" ]
"$prefix/bin/shadowtiles" --version

echo "== consumers"
cmake -S "$src/examples/cpp-consumer" -B "$tmp/cpp" -G Ninja -DCMAKE_PREFIX_PATH="$prefix" \
  -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$tmp/cpp" >/dev/null
cp -r "$src/examples/c-consumer" "$tmp/c"
PKG_CONFIG_PATH=$libdir/pkgconfig make -s -C "$tmp/c"
export PYTHONPATH=$prefix/lib/python3/dist-packages:$src/examples/python

"$py" "$src/examples/python/make_points.py" "$tmp/top" 10000 "$tmp/points.txt"
mapfile -t points < <(awk '{printf "%s,%s,%s\n", $1, $2, $3}' "$tmp/points.txt")
for method in mh mmh dagmh; do
  echo "-- $method"
  "$cli" -q query "$tmp/sun" -m "$method" --json --point "${points[@]}" >"$tmp/cli_$method.json"
  "$tmp/c/c-consumer" "$tmp/sun" "$tmp/points.txt" "$method" >"$tmp/c_$method.txt" 2>/dev/null
  "$tmp/cpp/cpp-consumer" "$tmp/sun" "$tmp/points.txt" "$method" >"$tmp/cpp_$method.txt"
  "$py" "$src/examples/python/query_points.py" "$tmp/sun" "$tmp/points.txt" "$method" >"$tmp/py_$method.txt"
  "$py" "$src/tests/install/compare_answers.py" "$tmp/cli_$method.json" c="$tmp/c_$method.txt" \
    cpp="$tmp/cpp_$method.txt" python="$tmp/py_$method.txt"
done

echo "== from a server URL (the C API streams tiles over HTTP)"
"$cli" -q serve "$tmp/sun" --port 0 >"$tmp/serve.out" 2>"$tmp/serve.err" &
serve_pid=$!
trap 'kill $serve_pid 2>/dev/null; wait $serve_pid 2>/dev/null; rm -rf "$tmp"' EXIT
for _ in $(seq 100); do grep -q "listening on" "$tmp/serve.out" && break; sleep 0.1; done
url=$(sed -n 's/^listening on //p' "$tmp/serve.out")
[ -n "$url" ] || { echo "FAIL: the server did not start"; cat "$tmp/serve.err"; exit 1; }
"$tmp/c/c-consumer" "$url" "$tmp/points.txt" mh >"$tmp/c_url_mh.txt" 2>/dev/null
"$py" "$src/examples/python/query_points.py" "$url" "$tmp/points.txt" dagmh >"$tmp/py_url_dagmh.txt"
kill $serve_pid; wait $serve_pid || true
trap 'rm -rf "$tmp"' EXIT
"$py" "$src/tests/install/compare_answers.py" "$tmp/cli_mh.json" c_url="$tmp/c_url_mh.txt"
"$py" "$src/tests/install/compare_answers.py" "$tmp/cli_dagmh.json" python_url="$tmp/py_url_dagmh.txt"

echo "== python example and errors"
"$py" "$src/examples/python/terrain_shadow.py" "$tmp/sun" "$tmp/top" "$tmp/terrain.png" >"$tmp/summary.json"
"$py" - "$tmp" <<'PY'
import json, sys
import numpy as np
import shadowtiles
tmp = sys.argv[1]
s = json.load(open(tmp + "/summary.json"))
assert 0.05 < s["shadowed_fraction"] < 0.95, s["shadowed_fraction"]
assert open(tmp + "/terrain.png", "rb").read(8) == b"\x89PNG\r\n\x1a\n"
try:
    shadowtiles.open(tmp + "/no-such-store")
    raise SystemExit("opening a missing store did not raise")
except shadowtiles.Error as e:
    assert e.code == "not_found" and "no-such-store" in str(e), (e.code, str(e))
with shadowtiles.open(tmp + "/sun") as m:
    # The lit-only batch path (ShadowMap::query_batch: sorted, shared walks) answers as the CLI does.
    points = np.loadtxt(tmp + "/points.txt")
    for method in ("mh", "mmh", "dagmh"):
        cli = np.array([row["lit"] for row in json.load(open(tmp + "/cli_%s.json" % method))])
        lit, none = m.query(points, method, values=False)
        assert none is None and (lit == cli).all(), (method, int((lit != cli).sum()))
        fractions = m.pcf(points, 1, method)
        assert (fractions == cli).all(), method
    try:
        m.query(np.zeros((2, 3)), "cpvs")
        raise SystemExit("a method the build lacks did not raise")
    except shadowtiles.Error as e:
        assert e.code in ("unsupported", "invalid_input") and "cpvs" in str(e), (e.code, str(e))
    try:
        m.query(np.array([[np.nan, 0, 0]]))
        raise SystemExit("a NaN point did not raise")
    except shadowtiles.Error as e:
        assert "finite" in str(e), str(e)
    # The GIL is released during a batch: another Python thread runs while the call is in C. With a
    # long switch interval a thread holding the GIL keeps it for the whole call (PyDLL: 0 ticks).
    import threading
    sys.setswitchinterval(1.0)
    ticks, stop, started = [0], threading.Event(), threading.Event()
    def tick():
        started.set()
        while not stop.is_set():
            ticks[0] += 1
    many = np.repeat(np.random.default_rng(3).uniform(m.meta["scene"]["bounds_min"], m.meta["scene"]["bounds_max"],
                                                      size=(1000, 3)), 2000, axis=0)
    ticker = threading.Thread(target=tick)
    ticker.start()
    started.wait()
    before = ticks[0]
    m.query(many, "dagmh", threads=1)
    during = ticks[0] - before
    stop.set()
    ticker.join()
    sys.setswitchinterval(0.005)
    assert during > 0, "no Python thread ran during a 2M-point query: the GIL was held"
    t = m.tile("mh", 1, 1)
    assert t.shape == (m.tile_size, m.tile_size) and t.dtype == np.float32
print("python example: %.1f%% of the terrain in shadow; errors carry the library's messages"
      % (100 * s["shadowed_fraction"]))
PY
echo "install test: ok"
