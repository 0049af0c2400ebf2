#!/usr/bin/env bash
# The test command: installs missing packages, builds with warnings as errors, runs the whole suite
# under CTest (the `release` test preset: output on failure, 900 s per test).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
scripts/build.sh -DSHADOWLAB_WERROR=ON
jobs=$(nproc 2>/dev/null || echo 2)
ctest --preset release -j"$jobs"
