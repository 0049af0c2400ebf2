#!/usr/bin/env bash
# Fuzzes the parsers a user feeds (scene JSON with its OBJ, MTL and PNG files, EXR files, method files and
# --set strings, sweep files and --grid strings, tolerance files, results and metrics files, light
# path specs, technique files) with libFuzzer, AddressSanitizer and UndefinedBehaviorSanitizer (Debian's clang).
#
#   scripts/fuzz.sh TARGET SECONDS    fuzz one target (scene obj gltf image exr method sweep tolerances
#                                     results light_path technique) for SECONDS; `all` runs every target in turn
#   scripts/fuzz.sh --list            the targets
#
# Builds build-fuzz/ (SHADOWLAB_FUZZ_BUILD overrides; SHADOWLAB_FUZZ_NO_BUILD=1 skips the build, as
# the suite's smoke tests do). Seeds come from scenes/data, tests/bad_input and tests/golden, copied
# into build-fuzz/corpus/TARGET, where libFuzzer adds what it finds; tests/fuzz/shadowlab.dict holds
# the keys. A crash, leak, sanitizer report, uncaught exception (anything but an InputError) or an
# input slower than 30 s (the largest legal scene, a 16.7M-triangle sphere, takes ~5 s under ASan)
# stops the run with exit 1 and leaves the input in build-fuzz/findings/.
# Add each finding to tests/fuzz/regressions/TARGET/ (the smoke test replays them) once it is fixed.
set -euo pipefail
cd "$(dirname "$0")/.."
targets=(scene obj gltf image exr method sweep tolerances results light_path technique)
if [ "${1:-}" = "--list" ]; then printf '%s\n' "${targets[@]}"; exit 0; fi
if [ $# -ne 2 ]; then echo "usage: scripts/fuzz.sh TARGET|all SECONDS (scripts/fuzz.sh --list)" >&2; exit 2; fi
target=$1 seconds=$2
case "$seconds" in ''|*[!0-9]*) echo "scripts/fuzz.sh: error: SECONDS \"$seconds\"; expected a whole number" >&2; exit 2;; esac
build=${SHADOWLAB_FUZZ_BUILD:-build-fuzz}
if [ "$target" = all ]; then
  for t in "${targets[@]}"; do "$0" "$t" "$seconds"; done
  exit 0
fi
known=0; for t in "${targets[@]}"; do [ "$t" = "$target" ] && known=1; done
if [ $known -eq 0 ]; then echo "scripts/fuzz.sh: error: no target \"$target\"; expected one of: ${targets[*]} or all" >&2; exit 2; fi

if [ "${SHADOWLAB_FUZZ_NO_BUILD:-0}" != 1 ]; then
  cmake -S . -B "$build" -DSHADOWLAB_FUZZ=ON -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ >/dev/null
  cmake --build "$build" -j"$(nproc 2>/dev/null || echo 2)" --target "fuzz_$target"
fi

# The seed corpus: the project's own good and bad files of that kind.
corpus="$build/corpus/$target"
mkdir -p "$corpus" "$build/findings"
seed() { for f in "$@"; do [ -f "$f" ] && cp -n "$f" "$corpus/" 2>/dev/null || true; done; }
case "$target" in
  scene) seed scenes/data/*.json tests/bad_input/scene_*.json ;;
  obj) seed tests/bad_input/assets/*.obj tests/bad_input/assets/*.mtl
       printf 'mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nvn 0 0 1\nusemtl a\nf 1/1/1 2/2/1 3/3/1\n#--MTL--\nnewmtl a\nKd 0.5 0.5 0.5\nmap_d alpha.png\n' > "$corpus/seed_obj_mtl" ;;
  gltf) seed scenes/data/assets/*.glb
        # Real files nobody here wrote, where assimp-testmodels is installed (not in the repository).
        seed /usr/share/assimp/models/glTF2/BoxTextured-glTF-Embedded/BoxTextured.gltf \
             /usr/share/assimp/models/glTF2/RecursiveNodes/RecursiveNodes.gltf \
             /usr/share/assimp/models/glTF2/BoxWithInfinites-glTF-Binary/BoxWithInfinites.glb \
             /usr/share/assimp/models/glTF2/SchemaFailures/sceneWrongType.gltf ;;
  image) seed scenes/data/*.png ;;
  exr) seed tests/fuzz/seeds/exr/*.exr ;;
  method) seed tests/bad_input/method_*.json
          printf '{"filter": "pcf", "filter.size": 5, "map.size": 1024}\n#--SET--\nbias.slope=2\nfit=cascades\ncascades.count=3\n' > "$corpus/seed_method_set" ;;
  sweep) seed compare/report/default_sweep.json tests/golden/*.sweep.json tests/bad_input/sweep_*.json
         printf '{"scenes": ["grazing"], "grid": {"map.size": [256, 512]}}\n#--ARGS--\ngrid bias.slope=0,1,2\nset filter=pcf\ngrid scene:/camera/width=64\n' > "$corpus/seed_sweep_args" ;;
  tolerances) seed tests/golden/tolerances.json tests/bad_input/tolerances_*.json tests/bad_input/timing_*tolerances*.json ;;
  results) seed tests/golden/baseline.json tests/golden/stability_baseline.json tests/bad_input/results_*.json \
                tests/bad_input/metrics_*.json tests/bad_input/timing_renamed_results.json tests/bad_input/assets/metrics_ok.json ;;
  technique) seed examples/techniques/*.glsl ;;
  light_path) printf 'elevation_deg=60:10:11\nazimuth_deg=0:90:4\n' > "$corpus/seed_light_path" ;;
esac
if [ -d "tests/fuzz/regressions/$target" ]; then seed tests/fuzz/regressions/"$target"/*; fi

asan=detect_leaks=1:abort_on_error=1
# The targets that read images go through OpenImageIO, whose PNG reader leaks on corrupt files
# (tests/sanitizers/lsan.supp). A suppression matches the allocation's stack by library name, and
# the fast unwinder stops at libstdc++ before reaching OIIO's frames: unwind fully for these.
case "$target" in scene|obj|gltf|image) asan=$asan:fast_unwind_on_malloc=0 ;; esac
export ASAN_OPTIONS=${ASAN_OPTIONS:-$asan}
# Third-party leaks only (the file says which and why); ours are fixed, never suppressed.
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$PWD/tests/sanitizers/lsan.supp:print_suppressions=0}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
log="$build/fuzz_$target.log"
set +e
"$build/tests/fuzz/fuzz_$target" "$corpus" -dict=tests/fuzz/shadowlab.dict -max_total_time="$seconds" \
    -timeout=30 -rss_limit_mb=4096 -max_len=8192 -print_final_stats=1 -artifact_prefix="$build/findings/${target}_" \
    >"$log" 2>&1
rc=$?
set -e
stats=$(grep -E '^stat::(number_of_executed_units|peak_rss_mb)|cov: ' "$log" | tail -n 3 | tr '\n' ' ')
if [ $rc -ne 0 ]; then
  tail -n 40 "$log" >&2
  echo "fuzz $target: FAILED after a finding (exit $rc); input in $build/findings/, log $log" >&2
  exit 1
fi
echo "fuzz $target: ${seconds} s, no finding: $stats"
