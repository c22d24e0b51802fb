#!/usr/bin/env bash
# The whole test suite: installs what is needed, builds (Release), runs every test with ctest.
# Needs ../shared/scenes beside the repository (the project's shared test scenes).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh
# Long variants (label `long`: every scene at high resolution) run with `ctest --test-dir build -L long`.
ctest --test-dir build --output-on-failure -j 2 --timeout 900 -LE long
