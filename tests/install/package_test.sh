#!/usr/bin/env bash
# Package test (ctest Package.DebInstallsAndPurges): builds the .deb with CPack, installs it with
# `apt-get install ./shadowtiles_*.deb`, checks the CLI's --version, the systemd unit and the
# libraries, then purges it so nothing of it stays in /usr (the consumers test builds against a
# temporary prefix afterwards). Needs root (CI runs as root).   Usage: package_test.sh BUILD_DIR
set -euo pipefail
trap 'echo "$(basename "$0"): failed at line $LINENO: $BASH_COMMAND" >&2' ERR
build=$1
[ "$(id -u)" -eq 0 ] || { echo "package test: needs root to install the .deb (CI runs as root)"; exit 1; }
# Outputs are captured before grep: under pipefail, `producer | grep -q` fails when grep exits first
# and the producer dies of SIGPIPE (CI lost that race on the Description check).
if [[ "$(dpkg-query -W -f='${Status}' shadowtiles 2>/dev/null || true)" == *"install ok installed"* ]]; then
  echo "package test: a shadowtiles package is already installed; refusing to replace it"; exit 1
fi
rm -rf "$build/packages"
(cd "$build" && cpack -G DEB >/dev/null)
deb=$(ls "$build"/packages/shadowtiles_*.deb)
echo "built $(basename "$deb") ($(du -k "$deb" | cut -f1) KiB)"
description=$(dpkg-deb -f "$deb" Description)
grep -q "Linux only" <<<"$description"
trap 'DEBIAN_FRONTEND=noninteractive apt-get purge -y -qq shadowtiles >/dev/null 2>&1 || true' EXIT
(cd "$(dirname "$deb")" && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "./$(basename "$deb")" >/dev/null)

version=$(/usr/bin/shadowtiles --version)
echo "installed: $version"
grep -q "^shadowtiles [0-9]" <<<"$version"
unit=/usr/lib/systemd/system/shadowtiles-serve@.service
[ -f "$unit" ] || unit=/lib/systemd/system/shadowtiles-serve@.service
grep -q '^ExecStart=/usr/bin/shadowtiles serve --config /etc/shadowtiles/%i.json$' "$unit"
getent passwd shadowtiles >/dev/null
[ -d /etc/shadowtiles ]
linker_cache=$(ldconfig -p)
grep -q 'libshadowtiles.so.1 ' <<<"$linker_cache"
# The Python module finds the packaged library by itself (Debian's interpreter, no PYTHONPATH).
(cd / && env -u PYTHONPATH /usr/bin/python3 -c 'import shadowtiles; print("python module: libshadowtiles", shadowtiles.library_version())')
if command -v systemd-analyze >/dev/null; then systemd-analyze verify "$unit" 2>&1 | grep -v 'shadowtiles-serve@' || true; fi

DEBIAN_FRONTEND=noninteractive apt-get purge -y -qq shadowtiles >/dev/null
trap - EXIT
if [ -e /usr/bin/shadowtiles ] || [ -e "$unit" ] || grep -q libshadowtiles <<<"$(ldconfig -p)"; then
  echo "package test: files remain after purge"; exit 1
fi
echo "package test: ok (installed, checked, purged)"
