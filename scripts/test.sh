#!/usr/bin/env bash
# The whole test suite: installs what is needed, builds (Release), runs every test with ctest.
# Needs ../shared/scenes beside the repository (the project's shared test scenes).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh
ctest --test-dir build --output-on-failure -j 2 --timeout 900
