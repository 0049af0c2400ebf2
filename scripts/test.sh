#!/usr/bin/env bash
# The test command: installs missing packages, builds with warnings as errors, runs the whole suite
# under CTest (the `release` test preset: output on failure, 900 s per test), then the fuzz smoke.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
jobs=$(nproc 2>/dev/null || echo 2)
# The parsers' fuzz smoke: libFuzzer + ASan + UBSan (clang), 12 s per target from the seeds and
# tests/fuzz/regressions/ (scripts/fuzz.sh runs the long campaigns; tests/fuzz/CMakeLists.txt says
# why the sweep target is left to it). Its build runs beside the main build and the suite at the
# lowest priority (nice 19, in this shell's session, so the scheduler weighs it against them): it
# takes the CPU they leave idle (links, one-job tails, the tests' waits) and finishes alone after.
cmake -S . -B build-fuzz -DSHADOWLAB_FUZZ=ON -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ >/dev/null
set -m  # its own process group, stopped whole if this script stops first
nice -n 19 cmake --build build-fuzz -j"$jobs" --target fuzz_smoke </dev/null >build-fuzz/smoke-build.log 2>&1 &
fuzz_build=$!
set +m
trap 'kill -- -"$fuzz_build" 2>/dev/null || true' EXIT
scripts/build.sh -DSHADOWLAB_WERROR=ON
ctest --preset release -j"$jobs"
if ! wait "$fuzz_build"; then
  tail -n 40 build-fuzz/smoke-build.log >&2
  echo "scripts/test.sh: the fuzz smoke's build failed (build-fuzz/smoke-build.log)" >&2
  exit 1
fi
ctest --test-dir build-fuzz -L fuzz -LE fuzz_heavy -j"$jobs" --output-on-failure
