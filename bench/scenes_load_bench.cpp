// Scene loading cost: every renderer run pays it once per scene (and sweeps once per variant).
#include <benchmark/benchmark.h>

#include "shadowlab/scenes/frame.h"
#include "shadowlab/scenes/loader.h"

namespace {

void BM_LoadScene(benchmark::State& state, const char* name) {
  std::string path = shadowlab::resolveScenePath(name);
  size_t triangles = 0;
  for (auto _ : state) {
    shadowlab::Scene s = shadowlab::loadScene(path);
    triangles = s.triangleCount();
    benchmark::DoNotOptimize(s.hash);
  }
  state.counters["triangles"] = double(triangles);
  state.counters["Mtris/s"] =
      benchmark::Counter(double(triangles) * state.iterations() / 1e6, benchmark::Counter::kIsRate);
}
BENCHMARK_CAPTURE(BM_LoadScene, sphere_on_plane, "sphere_on_plane")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_LoadScene, bunny, "bunny")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_LoadScene, long_view, "long_view")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_LoadScene, projector, "projector")->Unit(benchmark::kMillisecond);

// A reference-sized frame (1080p, 12 channels) through EXR: the compare step reads these.
void BM_FrameExrRoundTrip(benchmark::State& state) {
  shadowlab::Frame f;
  f.width = 1920;
  f.height = 1080;
  for (const char* n : {"hit", "object_id", "prim_id", "P.x", "P.y", "P.z", "N.x", "N.y", "N.z", "light.sun.vis",
                        "light.sun.occluder_dist", "proj.p.coverage"}) {
    auto& plane = f.add(n);
    for (size_t i = 0; i < plane.size(); ++i) plane[i] = float(i % 977) * 0.25f;
  }
  std::string path = "/tmp/shadowlab_scenes_bench_frame.exr";
  for (auto _ : state) {
    shadowlab::writeFrameExr(f, path);
    shadowlab::Frame g = shadowlab::readFrameExr(path);
    benchmark::DoNotOptimize(g.data);
  }
}
BENCHMARK(BM_FrameExrRoundTrip)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
