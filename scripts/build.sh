#!/usr/bin/env bash
# Configures and builds shadowlab into build/ (the `release` preset of CMakePresets.json). Used by
# main.sh and test.sh. Extra arguments go to the configure step, e.g. -DSHADOWLAB_WERROR=ON (what
# test.sh passes); like every cache variable, a value given once stays until given again.
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=$(nproc 2>/dev/null || echo 2)
cmake --preset release "$@" >/dev/null
cmake --build --preset release -j"$jobs"
