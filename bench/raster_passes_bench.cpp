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

#include "bench_scene.h"
#include "shadowlab/raster/raster.h"

using namespace shadowlab;
using shadowlab::bench::benchScene;

namespace {

Rasterizer& rasterizer() {
  static Rasterizer r;  // lavapipe, no validation: timing the rasterizer, not the layer
  return r;
}

void passes(benchmark::State& state, Filter filter, int copies) {
  const Scene& s = benchScene(copies);
  Method m;
  m.mapSize = 2048;
  m.filter = filter;
  m.filterSize = 5;
  RasterTimings t;
  rasterizer().render(s, m, "", &t);  // warm-up: pipelines, upload
  double shadow = 0, camera = 0, visibility = 0, readback = 0, total = 0;
  for (auto _ : state) {
    rasterizer().render(s, m, "", &t);
    state.SetIterationTime((t.shadowGpuMs + t.cameraGpuMs) * 1e-3);
    shadow += t.shadowGpuMs, camera += t.cameraGpuMs, visibility += t.visibilityGpuMs, readback += t.readbackMs,
        total += t.renderWallMs;
  }
  double n = double(state.iterations());
  state.counters["shadow_gpu_ms"] = shadow / n;
  state.counters["camera_gpu_ms"] = camera / n;
  state.counters["visibility_gpu_ms"] = visibility / n;
  state.counters["readback_ms"] = readback / n;
  state.counters["render_wall_ms"] = total / n;
  state.counters["triangles"] = double(s.triangleCount());
  state.SetLabel(rasterizer().deviceName());
}

}  // namespace

#define SHADOWLAB_PASSES(filter, name)                                                                \
  BENCHMARK_CAPTURE(passes, name##_bunny, filter, 1)->UseManualTime()->Unit(benchmark::kMillisecond); \
  BENCHMARK_CAPTURE(passes, name##_bunny_x4, filter, 4)->UseManualTime()->Unit(benchmark::kMillisecond);

SHADOWLAB_PASSES(Filter::None, none)
SHADOWLAB_PASSES(Filter::Hw2x2, hw2x2)
SHADOWLAB_PASSES(Filter::Bilinear4, bilinear4)
SHADOWLAB_PASSES(Filter::Pcf, pcf5)
SHADOWLAB_PASSES(Filter::Poisson, poisson16)
// The filterable maps: their moments pass (blur 2) is part of the shadow time.
SHADOWLAB_PASSES(Filter::Vsm, vsm)
SHADOWLAB_PASSES(Filter::Evsm2, evsm2)
SHADOWLAB_PASSES(Filter::Evsm4, evsm4)
SHADOWLAB_PASSES(Filter::Msm, msm)

BENCHMARK_MAIN();
