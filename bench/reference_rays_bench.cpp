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
// Counters: primary_mrays_per_s, shadow_mrays_per_s, mrays_per_s. The shadow rate of the full
// render is shadow_rays / (full time - primary-only time), both measured here, because the two
// kinds of rays are traced interleaved packet by packet.
#include <benchmark/benchmark.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <cstdio>
#include <map>
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
    slot = std::make_unique<Scene>(loadScene(resolveScenePath(name), {{"/camera/width", kWidth}, {"/camera/height", kHeight}}));
  }
  return *slot;
}

double primarySeconds(const std::string& name) {
  static std::map<std::string, double> best;
  auto found = best.find(name);
  if (found != best.end()) return found->second;
  Scene scene = scene1080(name);
  scene.lights.clear();
  scene.projectors.clear();
  double seconds = 1e30;
  for (int i = 0; i < 5; ++i) {
    ReferenceStats stats;
    renderReference(scene, {}, &stats);
    seconds = std::min(seconds, stats.seconds);
  }
  return best[name] = seconds;
}

void BM_Primary(benchmark::State& state, const std::string& name) {
  Scene scene = scene1080(name);
  scene.lights.clear();
  scene.projectors.clear();
  ReferenceStats stats;
  for (auto _ : state) {
    Frame frame = renderReference(scene, {}, &stats);
    state.SetIterationTime(stats.seconds);
    benchmark::DoNotOptimize(frame.data.data());
  }
  state.counters["primary_mrays_per_s"] = stats.primaryRays / stats.seconds * 1e-6;
  state.counters["build_ms"] = stats.buildSeconds * 1e3;
}

void BM_Full(benchmark::State& state, const std::string& name) {
  const Scene& scene = scene1080(name);
  const double primaryOnly = primarySeconds(name);
  ReferenceStats stats;
  double best = 1e30;
  for (auto _ : state) {
    Frame frame = renderReference(scene, {}, &stats);
    state.SetIterationTime(stats.seconds);
    best = std::min(best, stats.seconds);
    benchmark::DoNotOptimize(frame.data.data());
  }
  state.counters["mrays_per_s"] = stats.mraysPerS();
  state.counters["primary_rays"] = double(stats.primaryRays);
  state.counters["shadow_rays"] = double(stats.shadowRays);
  state.counters["shadow_mrays_per_s"] = stats.shadowRays / std::max(1e-9, best - primaryOnly) * 1e-6;
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
      auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                            12, object.positions.size()));
      auto* i = static_cast<unsigned*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                               12, object.triangles.size()));
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
  const unsigned threads = std::max(1u, std::thread::hardware_concurrency());
  double total = 0;
  for (auto _ : state) {
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
    state.SetIterationTime(seconds);
  }
  state.counters["shadow_mrays_per_s"] = double(count) * state.iterations() / total * 1e-6;
  state.counters["shadow_rays"] = double(count);
}

void BM_BareIntersect8(benchmark::State& state, const std::string& name) {
  BareScene bare(scene1080(name));
  const Camera& camera = scene1080(name).camera;
  const unsigned threads = std::max(1u, std::thread::hardware_concurrency());
  const int blockRows = kHeight / 2;
  double total = 0;
  for (auto _ : state) {
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
    state.SetIterationTime(seconds);
  }
  state.counters["primary_mrays_per_s"] = double(kWidth) * kHeight * state.iterations() / total * 1e-6;
}

}  // namespace

int main(int argc, char** argv) {
  for (const char* name : {"sphere_on_plane", "bunny"}) {
    const std::string scene = name;
    benchmark::RegisterBenchmark(("BM_Primary/" + scene).c_str(), BM_Primary, scene)->UseManualTime()->Unit(benchmark::kMillisecond);
    benchmark::RegisterBenchmark(("BM_Full/" + scene).c_str(), BM_Full, scene)->UseManualTime()->Unit(benchmark::kMillisecond);
    benchmark::RegisterBenchmark(("BM_BareIntersect8/" + scene).c_str(), BM_BareIntersect8, scene)->UseManualTime()->Unit(benchmark::kMillisecond);
    benchmark::RegisterBenchmark(("BM_BareOccluded8/" + scene).c_str(), BM_BareOccluded8, scene)->UseManualTime()->Unit(benchmark::kMillisecond);
  }
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
