#!/usr/bin/env bash
# The whole test suite under AddressSanitizer + UndefinedBehaviorSanitizer: configures and builds the
# `asan-ubsan` preset into build-asan/ (RelWithDebInfo, -fsanitize=address,undefined), runs every
# test with `ctest --preset asan-ubsan`, then prints every sanitizer report and fails if there is one.
# The sanitizer options live in that test preset (CMakePresets.json), not here, so a bare
# `ctest --preset asan-ubsan` behaves the same. Extra arguments go to ctest (e.g. -R gate_).
#
# Only our code is instrumented. The tests also start /bin/sh, python3 (charts.py) and chromium;
# they are not built with sanitizers, so they ignore ASAN_OPTIONS/UBSAN_OPTIONS they inherit.
# UBSan's vptr check is off in raster/src/technique_compiler.cpp alone (raster/GlslangSanitize.cmake:
# Debian's glslang has no RTTI to check against); ctest technique_ubsan_links_glslang guards that
# link in every build, in about 20 s.
# Slow: the build takes 15-25 minutes on 2 cores, the suite several times the Release suite's time.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
jobs=${SHADOWLAB_JOBS:-$(nproc 2>/dev/null || echo 2)}
cmake --preset asan-ubsan >/dev/null
cmake --build --preset asan-ubsan -j"$jobs"
rm -f build-asan/sanitizer-report.*
rc=0
ctest --preset asan-ubsan -j"$jobs" "$@" || rc=$?
shopt -s nullglob
reports=(build-asan/sanitizer-report.*)
for r in "${reports[@]}"; do
  echo "==== $r"
  cat "$r"
done
if [ ${#reports[@]} -gt 0 ]; then
  echo "sanitize: ${#reports[@]} ASan/LSan report(s) above (build-asan/sanitizer-report.<pid>)" >&2
  [ "$rc" -ne 0 ] || rc=1
fi
[ "$rc" -eq 0 ] && echo "sanitize: every test passed, no sanitizer report"
exit "$rc"
