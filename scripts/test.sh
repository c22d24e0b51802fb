#!/usr/bin/env bash
# The whole test suite: installs what is needed, builds (Release), runs every test with ctest.
# Needs ../shared/scenes beside the repository (the project's shared test scenes).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
# -Werror on the project's own code (SHADOWTILES_WERROR): a new warning fails CI.
bash scripts/build.sh -DSHADOWTILES_WERROR=ON
# Long variants (label `long`: every scene at high resolution) run with `ctest --test-dir build -L long`.
ctest --test-dir build --output-on-failure -j 2 --timeout 900 -LE long
# Fuzzing, CI mode: every libFuzzer target (fuzz/) 100,000 executions under ASan + UBSan, after
# replaying the committed crash inputs; its own clang build in build-fuzz/. The long mode (10^6 per
# target) is the ctest test fuzz_long (label `long`).
bash scripts/fuzz.sh --ci
