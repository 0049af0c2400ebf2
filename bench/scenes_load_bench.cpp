// Scene loading cost: every renderer run pays it once per scene (and sweeps once per variant).
#include <cstdlib>
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

// The read alone of a reference cache entry (what a sweep's first row waits for): the file named by
// $SHADOWLAB_BENCH_EXR, else a 1080p frame of the Compare set's shape (hit, ids, vis, occluder
// distance: flat regions and a few edges, as a traced frame has).
void BM_ReadReferenceExr(benchmark::State& state) {
  std::string path;
  if (const char* env = std::getenv("SHADOWLAB_BENCH_EXR"); env && *env) {
    path = env;
  } else {
    shadowlab::Frame f;
    f.width = 1920;
    f.height = 1080;
    const int w = f.width;
    auto fill = [&](const char* name, auto value) {
      auto& plane = f.add(name);
      for (size_t i = 0; i < plane.size(); ++i) plane[i] = value(int(i % size_t(w)), int(i / size_t(w)));
    };
    auto inSphere = [](int x, int y) { return (x - 960) * (x - 960) + (y - 500) * (y - 500) < 300 * 300; };
    fill("hit", [](int, int y) { return y > 200 ? 1.0f : 0.0f; });
    fill("object_id", [&](int x, int y) { return y <= 200 ? 0.0f : inSphere(x, y) ? 2.0f : 1.0f; });
    fill("prim_id", [&](int x, int y) { return y <= 200 ? 0.0f : float((x / 37) * 31 + y / 41); });
    fill("light.sun.vis", [&](int x, int y) { return inSphere(x + 250, y - 150) && !inSphere(x, y) ? 0.0f : 1.0f; });
    fill("light.sun.occluder_dist",
         [&](int x, int y) { return inSphere(x + 250, y - 150) && !inSphere(x, y) ? 0.5f + float(x % 300) * 1e-3f : -1.0f; });
    path = "/tmp/shadowlab_scenes_bench_reference.exr";
    shadowlab::writeFrameExr(f, path);
  }
  for (auto _ : state) {
    shadowlab::Frame g = shadowlab::readFrameExr(path);
    benchmark::DoNotOptimize(g.data);
  }
}
BENCHMARK(BM_ReadReferenceExr)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
