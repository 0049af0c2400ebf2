// Ray rates of the reference at 1920x1080 on sphere_on_plane and bunny.
//
//   BM_Primary/<scene>   renderReference with the lights and projectors removed: camera rays only.
//   BM_Full/<scene>      renderReference as `shadowlab reference` runs it (1 spp).
//   BM_BareOccluded8/<scene>  a bare Embree loop: rtcOccluded8 over the same shadow rays (same
//                        origins, directions, tfar, 4x2 packets), no filter, no bookkeeping. The
//                        reference's shadow rate divided by this one is the overhead of everything
//                        the harness adds (filters, origin offset, facing test, distance pass).
//   BM_BareIntersect8/<scene> the same for the camera rays.
//
// Counters: primary_mrays_per_s, shadow_mrays_per_s, mrays_per_s (wall clock, best run), and
// *_per_cpu_s (rays per process CPU second: steadier on a shared machine). The shadow rate of the
// full render is shadow_rays / (full time - primary-only time), both measured here, because the
// two kinds of rays are traced interleaved packet by packet. Arg = threads (0: all).
#include <benchmark/benchmark.h>
#include <sys/resource.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <cstdio>
#include <map>
#include <utility>
#include <memory>
#include <thread>

#include <embree3/rtcore.h>

#include "shadowlab/reference/reference.h"
#include "shadowlab/scenes/loader.h"

namespace {

using namespace shadowlab;

constexpr int kWidth = 1920;
constexpr int kHeight = 1080;

const Scene& scene1080(const std::string& name) {
  static std::map<std::string, std::unique_ptr<Scene>> cache;
  auto& slot = cache[name];
  if (!slot) {
    slot = std::make_unique<Scene>(
        loadScene(resolveScenePath(name), {{"/camera/width", kWidth}, {"/camera/height", kHeight}}));
  }
  return *slot;
}

// Process CPU time (all threads, user + system): per-CPU-second rates are much less disturbed
// than wall-clock rates when other work shares the machine.
double processCpuSeconds() {
  rusage usage;
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_utime.tv_sec + usage.ru_utime.tv_usec * 1e-6 + usage.ru_stime.tv_sec + usage.ru_stime.tv_usec * 1e-6;
}

struct Timing {
  double wall = 1e30;  // trace seconds (ReferenceStats::traceSeconds), best of the runs
  double cpu = 1e30;   // process CPU seconds of the whole renderReference call, best of the runs
};

Timing primaryBaseline(const std::string& name, int threads) {
  static std::map<std::pair<std::string, int>, Timing> cache;
  auto found = cache.find({name, threads});
  if (found != cache.end()) return found->second;
  Scene scene = scene1080(name);
  scene.lights.clear();
  scene.projectors.clear();
  ReferenceOptions options;
  options.threads = threads;
  Timing best;
  for (int i = 0; i < 5; ++i) {
    ReferenceStats stats;
    const double cpu0 = processCpuSeconds();
    renderReference(scene, options, &stats);
    best.cpu = std::min(best.cpu, processCpuSeconds() - cpu0);
    best.wall = std::min(best.wall, stats.traceSeconds);
  }
  return cache[{name, threads}] = best;
}

void BM_Primary(benchmark::State& state, const std::string& name) {
  const Timing baseline = primaryBaseline(name, int(state.range(0)));
  Scene scene = scene1080(name);
  scene.lights.clear();
  scene.projectors.clear();
  ReferenceStats stats;
  ReferenceOptions options;
  options.threads = int(state.range(0));
  for (auto _ : state) {
    Frame frame = renderReference(scene, options, &stats);
    state.SetIterationTime(stats.traceSeconds);
    benchmark::DoNotOptimize(frame.data.data());
  }
  state.counters["primary_mrays_per_s"] = stats.primaryRays / baseline.wall * 1e-6;
  state.counters["primary_mrays_per_cpu_s"] = stats.primaryRays / baseline.cpu * 1e-6;
  state.counters["build_ms"] = stats.buildSeconds * 1e3;
}

void BM_Full(benchmark::State& state, const std::string& name) {
  const Scene& scene = scene1080(name);
  ReferenceOptions options;
  options.threads = int(state.range(0));
  const Timing primaryOnly = primaryBaseline(name, options.threads);
  ReferenceStats stats;
  Timing best;
  for (auto _ : state) {
    const double cpu0 = processCpuSeconds();
    Frame frame = renderReference(scene, options, &stats);
    best.cpu = std::min(best.cpu, processCpuSeconds() - cpu0);
    state.SetIterationTime(stats.traceSeconds);
    best.wall = std::min(best.wall, stats.traceSeconds);
    benchmark::DoNotOptimize(frame.data.data());
  }
  state.counters["mrays_per_s"] = (stats.primaryRays + stats.shadowRays) / best.wall * 1e-6;
  state.counters["primary_rays"] = double(stats.primaryRays);
  state.counters["shadow_rays"] = double(stats.shadowRays);
  state.counters["shadow_mrays_per_s"] = stats.shadowRays / std::max(1e-9, best.wall - primaryOnly.wall) * 1e-6;
  state.counters["shadow_mrays_per_cpu_s"] = stats.shadowRays / std::max(1e-9, best.cpu - primaryOnly.cpu) * 1e-6;
  state.counters["build_ms"] = stats.buildSeconds * 1e3;
}

// The bare loops: one Embree scene of plain triangle geometries, no filters, no robust flag.
struct BareScene {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  std::vector<float> ox, oy, oz, dx, dy, dz, tfar;  // shadow rays, in 4x2 packet order
  explicit BareScene(const Scene& s) {
    device = rtcNewDevice(nullptr);
    scene = rtcNewScene(device);
    rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_HIGH);
    for (const Object& object : s.objects) {
      RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
      auto* v = static_cast<float*>(
          rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 12, object.positions.size()));
      auto* i = static_cast<unsigned*>(
          rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 12, object.triangles.size()));
      std::memcpy(v, object.positions.data(), object.positions.size() * 12);
      std::memcpy(i, object.triangles.data(), object.triangles.size() * 12);
      rtcCommitGeometry(g);
      rtcAttachGeometry(scene, g);
      rtcReleaseGeometry(g);
    }
    rtcCommitScene(scene);
    // The shadow rays the reference traces for the first (directional) light: from each hit point
    // (offset 1e-4 along the normal facing the light) toward the light.
    const Light& light = s.lights.at(0);
    for (int by = 0; by < kHeight; by += 2)
      for (int bx = 0; bx < kWidth; bx += 4) {
        RTCRayHit8 rh;
        alignas(32) int valid[8];
        for (int lane = 0; lane < 8; ++lane) {
          valid[lane] = -1;
          glm::vec3 d = s.camera.rayDirection(bx + lane % 4 + 0.5f, by + lane / 4 + 0.5f);
          rh.ray.org_x[lane] = s.camera.position.x;
          rh.ray.org_y[lane] = s.camera.position.y;
          rh.ray.org_z[lane] = s.camera.position.z;
          rh.ray.dir_x[lane] = d.x;
          rh.ray.dir_y[lane] = d.y;
          rh.ray.dir_z[lane] = d.z;
          rh.ray.tnear[lane] = 0;
          rh.ray.tfar[lane] = INFINITY;
          rh.ray.mask[lane] = ~0u;
          rh.ray.time[lane] = 0;
          rh.ray.flags[lane] = 0;
          rh.hit.geomID[lane] = RTC_INVALID_GEOMETRY_ID;
        }
        RTCIntersectContext context;
        rtcInitIntersectContext(&context);
        rtcIntersect8(valid, scene, &context, &rh);
        for (int lane = 0; lane < 8; ++lane) {
          if (rh.hit.geomID[lane] == RTC_INVALID_GEOMETRY_ID) continue;
          glm::vec3 n = glm::normalize(glm::vec3(rh.hit.Ng_x[lane], rh.hit.Ng_y[lane], rh.hit.Ng_z[lane]));
          glm::vec3 toLight = light.type == LightType::Directional ? -light.direction : glm::normalize(light.position);
          if (glm::dot(n, toLight) < 0) n = -n;
          glm::vec3 p = glm::vec3(rh.ray.org_x[lane], rh.ray.org_y[lane], rh.ray.org_z[lane]) +
                        rh.ray.tfar[lane] * glm::vec3(rh.ray.dir_x[lane], rh.ray.dir_y[lane], rh.ray.dir_z[lane]) +
                        1e-4f * n;
          ox.push_back(p.x);
          oy.push_back(p.y);
          oz.push_back(p.z);
          dx.push_back(toLight.x);
          dy.push_back(toLight.y);
          dz.push_back(toLight.z);
          tfar.push_back(INFINITY);
        }
      }
  }
  ~BareScene() {
    rtcReleaseScene(scene);
    rtcReleaseDevice(device);
  }
};

void BM_BareOccluded8(benchmark::State& state, const std::string& name) {
  BareScene bare(scene1080(name));
  const size_t count = bare.ox.size();
  const size_t packets = (count + 7) / 8;
  const unsigned threads =
      state.range(0) > 0 ? unsigned(state.range(0)) : std::max(1u, std::thread::hardware_concurrency());
  double total = 0, cpuTotal = 0;
  for (auto _ : state) {
    const double cpu0 = processCpuSeconds();
    auto start = std::chrono::steady_clock::now();
    std::vector<std::thread> workers;
    for (unsigned t = 0; t < threads; ++t)
      workers.emplace_back([&, t] {
        RTCIntersectContext context;
        rtcInitIntersectContext(&context);
        context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
        // Interleaved chunks of 64 packets, like tiles.
        for (size_t chunk = t; chunk * 64 < packets; chunk += threads)
          for (size_t p = chunk * 64; p < std::min(packets, (chunk + 1) * 64); ++p) {
            RTCRay8 ray;
            alignas(32) int valid[8];
            for (int lane = 0; lane < 8; ++lane) {
              const size_t i = p * 8 + lane;
              valid[lane] = i < count ? -1 : 0;
              const size_t k = i < count ? i : 0;
              ray.org_x[lane] = bare.ox[k];
              ray.org_y[lane] = bare.oy[k];
              ray.org_z[lane] = bare.oz[k];
              ray.dir_x[lane] = bare.dx[k];
              ray.dir_y[lane] = bare.dy[k];
              ray.dir_z[lane] = bare.dz[k];
              ray.tnear[lane] = 0;
              ray.tfar[lane] = bare.tfar[k];
              ray.mask[lane] = ~0u;
              ray.time[lane] = 0;
              ray.id[lane] = lane;
              ray.flags[lane] = 0;
            }
            rtcOccluded8(valid, bare.scene, &context, &ray);
            benchmark::DoNotOptimize(ray.tfar[0]);
          }
      });
    for (auto& w : workers) w.join();
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    total += seconds;
    cpuTotal += processCpuSeconds() - cpu0;
    state.SetIterationTime(seconds);
  }
  state.counters["shadow_mrays_per_s"] = double(count) * state.iterations() / total * 1e-6;
  state.counters["shadow_mrays_per_cpu_s"] = double(count) * state.iterations() / cpuTotal * 1e-6;
  state.counters["shadow_rays"] = double(count);
}

void BM_BareIntersect8(benchmark::State& state, const std::string& name) {
  BareScene bare(scene1080(name));
  const Camera& camera = scene1080(name).camera;
  const unsigned threads =
      state.range(0) > 0 ? unsigned(state.range(0)) : std::max(1u, std::thread::hardware_concurrency());
  const int blockRows = kHeight / 2;
  double total = 0, cpuTotal = 0;
  for (auto _ : state) {
    const double cpu0 = processCpuSeconds();
    auto start = std::chrono::steady_clock::now();
    std::vector<std::thread> workers;
    for (unsigned t = 0; t < threads; ++t)
      workers.emplace_back([&, t] {
        RTCIntersectContext context;
        rtcInitIntersectContext(&context);
        context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
        for (int row = int(t); row < blockRows; row += int(threads))
          for (int bx = 0; bx < kWidth; bx += 4) {
            RTCRayHit8 rh;
            alignas(32) int valid[8];
            for (int lane = 0; lane < 8; ++lane) {
              valid[lane] = -1;
              glm::vec3 d = camera.rayDirection(bx + lane % 4 + 0.5f, row * 2 + lane / 4 + 0.5f);
              rh.ray.org_x[lane] = camera.position.x;
              rh.ray.org_y[lane] = camera.position.y;
              rh.ray.org_z[lane] = camera.position.z;
              rh.ray.dir_x[lane] = d.x;
              rh.ray.dir_y[lane] = d.y;
              rh.ray.dir_z[lane] = d.z;
              rh.ray.tnear[lane] = 0;
              rh.ray.tfar[lane] = INFINITY;
              rh.ray.mask[lane] = ~0u;
              rh.ray.time[lane] = 0;
              rh.ray.id[lane] = lane;
              rh.ray.flags[lane] = 0;
              rh.hit.geomID[lane] = RTC_INVALID_GEOMETRY_ID;
            }
            rtcIntersect8(valid, bare.scene, &context, &rh);
            benchmark::DoNotOptimize(rh.hit.geomID[0]);
          }
      });
    for (auto& w : workers) w.join();
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    total += seconds;
    cpuTotal += processCpuSeconds() - cpu0;
    state.SetIterationTime(seconds);
  }
  state.counters["primary_mrays_per_s"] = double(kWidth) * kHeight * state.iterations() / total * 1e-6;
  state.counters["primary_mrays_per_cpu_s"] = double(kWidth) * kHeight * state.iterations() / cpuTotal * 1e-6;
}

}  // namespace

int main(int argc, char** argv) {
  for (const char* name : {"sphere_on_plane", "bunny"}) {
    const std::string scene = name;
    // Arg: threads (0 = all hardware threads; 1 = single thread, for per-core rates that a busy
    // machine disturbs less).
    for (auto* b : {benchmark::RegisterBenchmark(("BM_Primary/" + scene).c_str(), BM_Primary, scene),
                    benchmark::RegisterBenchmark(("BM_Full/" + scene).c_str(), BM_Full, scene),
                    benchmark::RegisterBenchmark(("BM_BareIntersect8/" + scene).c_str(), BM_BareIntersect8, scene),
                    benchmark::RegisterBenchmark(("BM_BareOccluded8/" + scene).c_str(), BM_BareOccluded8, scene)})
      b->Arg(0)->Arg(1)->UseManualTime()->Unit(benchmark::kMillisecond);
  }
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
