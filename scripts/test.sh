#!/usr/bin/env bash
# The test command: installs missing packages, builds with warnings as errors, runs the whole suite
# under CTest (the `release` test preset: output on failure, 900 s per test), then the fuzz smoke.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
scripts/build.sh -DSHADOWLAB_WERROR=ON
jobs=$(nproc 2>/dev/null || echo 2)
ctest --preset release -j"$jobs"
# The parsers' fuzz smoke: libFuzzer + ASan + UBSan (clang), 12 s per target from the seeds and
# tests/fuzz/regressions/ (scripts/fuzz.sh runs the long campaigns; tests/fuzz/CMakeLists.txt says
# why the sweep target is left to it).
cmake -S . -B build-fuzz -DSHADOWLAB_FUZZ=ON -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ >/dev/null
cmake --build build-fuzz -j"$jobs" --target fuzz_smoke
ctest --test-dir build-fuzz -L fuzz -LE fuzz_heavy -j"$jobs" --output-on-failure
