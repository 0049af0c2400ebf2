// Technique files side by side with the built-in filters (raster/METHODS.md "Your own technique"):
// lookup/builtin_pcf5 and lookup/file_pcf5 are the lookup pass (lookup_gpu_ms) of filter=pcf
// filter.size=5 and of examples/techniques/pcf.glsl with technique.size=5, alternated in one process
// on sphere_on_plane at 1920x1080 with a 2048^2 map (the iteration time is lookup_gpu_ms; the
// ratio is the file's cost against the built-in's). compile/* is the run-time compile of each
// example with glslang (wall time, the in-memory cache bypassed by a fresh file content each time).
#include <benchmark/benchmark.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "shadowlab/raster/raster.h"
#include "shadowlab/scenes/loader.h"
#include "shadowlab/scenes/technique.h"

using namespace shadowlab;

namespace {

const std::string kExamples = std::string(SHADOWLAB_SOURCE_DIR) + "/examples/techniques/";

Rasterizer& rasterizer() {
  static Rasterizer r;
  return r;
}

const Scene& scene() {
  static const Scene s = [] {
    Scene scene = loadScene(resolveScenePath("sphere_on_plane"));
    scene.camera.width = 1920;
    scene.camera.height = 1080;
    return scene;
  }();
  return s;
}

void lookup(benchmark::State& state, bool file) {
  Method m;
  m.mapSize = 2048;
  if (file) {
    m.technique = kExamples + "pcf.glsl";
    m.techniqueParams["size"] = 5;
  } else {
    m.filter = Filter::Pcf;
    m.filterSize = 5;
  }
  const EvidenceSelector none = [](const uint8_t*, int, int, EvidenceRequest&) {};
  RasterTimings t;
  for (int i = 0; i < 2; ++i) rasterizer().recycle(rasterizer().render(scene(), m, "", &t, nullptr, &none));
  double sum = 0;
  for (auto _ : state) {
    rasterizer().recycle(rasterizer().render(scene(), m, "", &t, nullptr, &none));
    state.SetIterationTime(t.lookupGpuMs * 1e-3);
    sum += t.lookupGpuMs;
  }
  state.counters["lookup_gpu_ms"] = sum / double(state.iterations());
  state.SetLabel(rasterizer().deviceName());
}

// The compile of one example: a fresh copy with a changed comment each iteration, so the content
// hash (the cache key) is new and glslang runs every time; render() then compiles it.
void compile(benchmark::State& state, const char* example) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "shadowlab_technique_bench";
  std::filesystem::create_directories(dir);
  std::ifstream in(kExamples + example);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  Method m;
  static int n = 0;  // across repetitions too: every content is new
  for (auto _ : state) {
    const std::string path = (dir / example).string();
    std::ofstream(path) << text << "// " << n++ << "\n";
    m.technique = path;
    const auto t0 = std::chrono::steady_clock::now();
    precompileTechnique(m);
    state.SetIterationTime(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
}

}  // namespace

BENCHMARK_CAPTURE(lookup, builtin_pcf5, false)->UseManualTime()->Unit(benchmark::kMillisecond)->Iterations(12);
BENCHMARK_CAPTURE(lookup, file_pcf5, true)->UseManualTime()->Unit(benchmark::kMillisecond)->Iterations(12);
BENCHMARK_CAPTURE(lookup, builtin_pcf5_again, false)->UseManualTime()->Unit(benchmark::kMillisecond)->Iterations(12);
BENCHMARK_CAPTURE(lookup, file_pcf5_again, true)->UseManualTime()->Unit(benchmark::kMillisecond)->Iterations(12);
BENCHMARK_CAPTURE(compile, pcf, "pcf.glsl")->UseManualTime()->Unit(benchmark::kMillisecond)->Iterations(5);
BENCHMARK_CAPTURE(compile, poisson_ign, "poisson_ign.glsl")
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond)
    ->Iterations(5);
BENCHMARK_CAPTURE(compile, pcss, "pcss.glsl")->UseManualTime()->Unit(benchmark::kMillisecond)->Iterations(5);
BENCHMARK_MAIN();
