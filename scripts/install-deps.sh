#!/usr/bin/env bash
# Installs every Debian package shadowtiles needs to build, test and run (Debian 12, as root).
set -euo pipefail
packages=(
  cmake ninja-build g++ pkg-config
  libembree-dev            # ray casting (Embree 3)
  libassimp-dev            # scene loading: OBJ, PLY, glTF/GLB, FBX, DAE, IFC, TER...
  assimp-testmodels        # the bundled default scene (a terrain) and test models
  liblmdb-dev lmdb-utils   # the out-of-core tile store
  libzstd-dev libxxhash-dev
  libcli11-dev libspdlog-dev libfmt-dev nlohmann-json3-dev libcpp-httplib-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libpng-dev               # PNG frames of `shadowtiles render`
  python3-matplotlib       # charts of the benchmark report (bench/make_report.py), examples/python
  python3-numpy            # the Python module (python/shadowtiles, ctypes over the C API) and examples
  dpkg-dev file            # cpack -G DEB: dpkg-shlibdeps and ELF detection (tests/install/package_test.sh)
  wrk curl                 # HTTP load benchmark (bench/server_load.sh)
  libjs-leaflet            # the inspector page's map (served by `shadowtiles serve` from /usr/share/javascript/leaflet)
  chromium nodejs          # the inspector's real-browser test (tests/browser), headless
  slurmctld slurmd slurm-client munge  # scale-out: the Slurm integration test (tests/slurm_array_test.sh)
  nginx                    # serving replicas behind a caching proxy (config/nginx-replicas.conf)
  clang libclang-rt-14-dev # libFuzzer + ASan/UBSan runtimes for the fuzz targets (scripts/fuzz.sh)
)
# npm for playwright-core (tests/browser/package.json); a node distribution that ships npm itself
# (NodeSource) conflicts with Debian's npm package.
command -v npm > /dev/null 2>&1 || packages+=(npm)
# --list: print the package names (one place defines them; .ci/run installs from it).
if [ "${1:-}" = "--list" ]; then
  printf '%s\n' "${packages[@]}"
  exit 0
fi
missing=()
for p in "${packages[@]}"; do
  [[ "$(dpkg-query -W -f='${Status}' "$p" 2>/dev/null || true)" == *"install ok installed"* ]] || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  SUDO=""
  [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
# playwright-core, pinned by tests/browser/package-lock.json; it drives /usr/bin/chromium and never
# downloads a browser.
browser_dir="$(cd "$(dirname "$0")/.." && pwd)/tests/browser"
if [ ! -f "$browser_dir/node_modules/playwright-core/package.json" ]; then
  (cd "$browser_dir" && PLAYWRIGHT_SKIP_BROWSER_DOWNLOAD=1 npm ci --no-audit --no-fund --loglevel=error)
fi
