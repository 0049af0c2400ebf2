// Shadow and camera pass GPU times (timestamps) per filter at 1920x1080 with a 2048^2 map, on
// the bunny (~28k triangles) and on four bunnies (~111k triangles). The iteration time is the
// GPU time of the two passes (manual time); readback and total CPU time are counters.
// The yardstick: a bare Vulkan program does ~24 ms (shadow) + ~45 ms (camera) for
// ~100k triangles on lavapipe; the goal is within 1.3x of that for filters none and hw2x2.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdio>
#include <map>
#include <memory>

#include "shadowlab/raster/raster.h"
#include "shadowlab/scenes/loader.h"

using namespace shadowlab;

namespace {

Rasterizer& rasterizer() {
  static Rasterizer r;  // lavapipe, no validation: timing the rasterizer, not the layer
  return r;
}

const Scene& scene(int copies) {
  static std::map<int, Scene> cache;
  auto it = cache.find(copies);
  if (it != cache.end()) return it->second;
  Scene s = loadScene(resolveScenePath("bunny"));
  s.camera.width = 1920;
  s.camera.height = 1080;
  if (copies > 1) {
    // Extra bunnies beside the first one, in view: ~28k triangles each.
    std::vector<Object> extra;
    glm::vec3 lo = s.boundsMin(), hi = s.boundsMax();
    float step = 0.35f * std::max(hi.x - lo.x, hi.z - lo.z);
    uint32_t nextId = 1000;
    for (const Object& o : s.objects) {
      if (o.triangles.size() < 10000) continue;  // the bunny, not the floor
      for (int c = 1; c < copies; ++c) {
        Object copy = o;
        copy.id = nextId++;
        copy.name = o.name + "_" + std::to_string(c);
        glm::vec3 offset((c % 2 ? 1.0f : -1.0f) * step * float((c + 1) / 2) * 0.5f, 0, -step * 0.3f * float(c));
        for (auto& p : copy.positions) p += offset;
        extra.push_back(copy);
      }
    }
    for (auto& o : extra) s.objects.push_back(std::move(o));
    s.hash = "bench-" + std::to_string(copies);
  }
  return cache.emplace(copies, std::move(s)).first->second;
}

void passes(benchmark::State& state, Filter filter, int copies) {
  const Scene& s = scene(copies);
  Method m;
  m.mapSize = 2048;
  m.filter = filter;
  m.filterSize = 5;
  RasterTimings t;
  rasterizer().render(s, m, "", &t);  // warm-up: pipelines, upload
  double shadow = 0, camera = 0, visibility = 0, readback = 0, total = 0;
  for (auto _ : state) {
    rasterizer().render(s, m, "", &t);
    state.SetIterationTime((t.shadowMs + t.cameraMs) * 1e-3);
    shadow += t.shadowMs, camera += t.cameraMs, visibility += t.visibilityMs, readback += t.readbackMs, total += t.totalMs;
  }
  double n = double(state.iterations());
  state.counters["shadow_ms"] = shadow / n;
  state.counters["camera_ms"] = camera / n;
  state.counters["visibility_ms"] = visibility / n;
  state.counters["readback_ms"] = readback / n;
  state.counters["total_ms"] = total / n;
  state.counters["triangles"] = double(s.triangleCount());
  state.SetLabel(rasterizer().deviceName());
}

}  // namespace

#define SHADOWLAB_PASSES(filter, name)                                                              \
  BENCHMARK_CAPTURE(passes, name##_bunny, filter, 1)->UseManualTime()->Unit(benchmark::kMillisecond); \
  BENCHMARK_CAPTURE(passes, name##_bunny_x4, filter, 4)->UseManualTime()->Unit(benchmark::kMillisecond);

SHADOWLAB_PASSES(Filter::None, none)
SHADOWLAB_PASSES(Filter::Hw2x2, hw2x2)
SHADOWLAB_PASSES(Filter::Bilinear4, bilinear4)
SHADOWLAB_PASSES(Filter::Pcf, pcf5)
SHADOWLAB_PASSES(Filter::Poisson, poisson16)

BENCHMARK_MAIN();
