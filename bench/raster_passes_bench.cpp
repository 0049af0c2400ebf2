// Shadow and camera pass GPU times (timestamps) per filter at 1920x1080 with a 2048^2 map, on
// the bunny (~28k triangles) and on four bunnies (~111k triangles). The iteration time is the
// GPU time of the two passes (manual time); readback and total CPU time are counters.
// The quoted yardstick: a bare Vulkan program does ~24 ms (shadow) + ~45 ms (camera) for
// ~100k triangles on lavapipe; the goal is within 1.3x of that for filters none and hw2x2.
// lookup/*: the lookup pass alone (lookup_gpu_ms), per filter and bias specialization.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdio>
#include <ctime>
#include <map>
#include <memory>
#include <vector>

#include "bench_scene.h"
#include "shadowlab/raster/raster.h"
#include "shadowlab/scenes/loader.h"

using namespace shadowlab;
using shadowlab::bench::benchScene;

namespace {

Rasterizer& rasterizer() {
  // lavapipe, no validation: timing the rasterizer, not the layer; every iteration draws its maps.
  static Rasterizer r([] {
    RasterDeviceOptions o;
    o.keepShadowMaps = false;
    return o;
  }());
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

// The lookup pass alone (pass 4: the method's visibility, 1 byte per pixel), as evidence on demand
// runs it per configuration, on sphere_on_plane at 1920x1080 with a 2048^2 map: the iteration time
// is lookup_gpu_ms. `edit` switches a bias on (1 the receiver plane, 2 the normal offset; 3: pcf 5), so the cost
// of each specialization shows beside the default's.
void lookup(benchmark::State& state, Filter filter, int edit) {
  static const Scene s = [] {
    Scene scene = loadScene(resolveScenePath("sphere_on_plane"));
    scene.camera.width = 1920;
    scene.camera.height = 1080;
    return scene;
  }();
  Method m;
  m.mapSize = 2048;
  m.filter = filter;
  m.biasReceiverPlane = edit == 1;
  m.biasNormal = edit == 2 ? 1.0f : 0.0f;
  if (edit == 3) m.filterSize = 5;
  const EvidenceSelector none = [](const uint8_t*, int, int, EvidenceRequest&) {};
  RasterTimings t;
  for (int i = 0; i < 2; ++i)  // warm-up: pipelines, upload, the group's planes
    rasterizer().recycle(rasterizer().render(s, m, "", &t, nullptr, &none));
  std::vector<double> ms, cpu;
  auto cpuMs = [] {
    timespec ts{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return double(ts.tv_sec) * 1e3 + double(ts.tv_nsec) * 1e-6;
  };
  for (auto _ : state) {
    const double c0 = cpuMs();
    rasterizer().recycle(rasterizer().render(s, m, "", &t, nullptr, &none));
    cpu.push_back(cpuMs() - c0);
    state.SetIterationTime(t.lookupGpuMs * 1e-3);
    ms.push_back(t.lookupGpuMs);
  }
  auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.empty() ? 0.0 : v[v.size() / 2];
  };
  state.counters["lookup_gpu_ms"] = median(ms);
  // The process's CPU time per frame (every thread, llvmpipe's included: shadow, lookup, evidence,
  // readback): less sensitive than the GPU timestamps to other processes on a shared machine.
  state.counters["frame_cpu_ms"] = median(cpu);
  state.counters["partial"] = t.partialEvidence;
  state.SetLabel(rasterizer().deviceName());
}

}  // namespace

BENCHMARK_CAPTURE(lookup, none_sphere, Filter::None, 0)->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(lookup, hw2x2_sphere, Filter::Hw2x2, 0)->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(lookup, none_sphere_receiver_plane, Filter::None, 1)->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(lookup, none_sphere_normal_offset, Filter::None, 2)->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(lookup, pcf3_sphere, Filter::Pcf, 0)->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(lookup, pcf5_sphere, Filter::Pcf, 3)->UseManualTime()->Unit(benchmark::kMillisecond);

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
