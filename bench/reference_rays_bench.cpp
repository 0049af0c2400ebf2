// The reference against bare Embree loops over the same scene and the same rays, at 1920x1080, on
// sphere_on_plane and the four-bunny scene (bench_scene.h: the bundled bunny and three copies,
// ~111k triangles). The goal: primary and shadow rays each <= 1.25x the bare loop.
//
//   BM_Ratios/<scene>  one thread (renderReference with threads = 1 runs on the calling thread,
//                      like the bare loops), in rounds that alternate the measurements so a load
//                      change on a shared machine hits all of them; process CPU time (the trace's
//                      ReferenceStats::traceCpuSeconds, the same clock around the bare loops), best
//                      of the rounds each:
//     ref_primary_ms   renderReference with the lights and projectors removed: camera rays only
//                      (the trace, so the BVH build and the frame allocation are left out), with
//                      the Compare channel set (ReferenceOptions::channels), as the reference cache
//                      (run, sweep, stability, tune) traces it
//     ref_shadow_ms    renderReference with the scene's light (1 spp, Compare), minus the above:
//                      everything shadow rays cost (hit point, normal and origin, facing test, the
//                      one closest-hit rtcIntersect8 per packet that also gives occluder_dist, the
//                      vis and occluder_dist writes)
//     bare_primary_ms  rtcIntersect8 over the same camera rays: the same 16 x 16 tiles of 4 x 2
//                      pixel packets, CameraRays::direction per lane (a division and a square root
//                      per ray in turn), nothing kept
//     bare_primary_packed_ms  the same loop with each packet's directions made as the reference
//                      makes them, in one go over its lanes (CameraRays::perspectiveDirection on 8
//                      doubles), in the bench's baseline (SSE2) compilation
//     primary_ratio_packed, primary_ratio_packed_baseline  ref_primary_ms and the baseline trace's
//                      against it: what the trace costs beyond a bare loop that makes its rays alike
//     bare_shadow_ms   rtcOccluded8 over the same shadow rays, bit for bit: origins P + N * offset
//                      rebuilt from the reference's own P, N, object_id, prim_id planes with its
//                      rule (shadowOriginOffset), the same directions and tfar, the same packets
//                      (one per 4 x 2 block, lanes without a shadow ray masked off)
//     primary_ratio    ref_primary_ms / bare_primary_ms   (goal <= 1.25)
//     shadow_ratio     ref_shadow_ms / bare_shadow_ms     (goal <= 1.25)
//     bare_shadow_closest_ms, shadow_ratio_closest  rtcIntersect8 (closest hit) over the same shadow
//                      rays: the bare price of occluder_dist, which an any-hit query cannot give
//     bare_shadow_setup_ms, shadow_ratio_embree  the bare loop without its Embree call (reading its
//                      stored packets, which do not fit in the cache, into RTCRay8): a loop making
//                      its rays in registers would not pay it; shadow_ratio_embree divides by
//                      bare_shadow_ms minus it, the strictest baseline
//     primary_ratio_all, shadow_ratio_all  the same with the All channel set (P, N, prim_id too), as
//                      `shadowlab reference` traces it (its picture needs them)
//     ref_primary_baseline_ms, ref_shadow_baseline_ms, primary_ratio_baseline, shadow_ratio_baseline
//                      the same as ref_* and *_ratio with the trace's baseline (SSE2) compilation
//                      (ReferenceSimd::Baseline); ref_* run ReferenceSimd::Auto, i.e. the AVX2
//                      compilation where the CPU has it (simd_avx2 = 1)
//   The bare loops trace a plain Embree scene (no filter functions, default flags). The reference's
//   scene is built with RTC_SCENE_FLAG_ROBUST (watertight edges, a correctness rule); the
//   *_ratio_robust counters divide by the same bare loops on a robust scene instead, i.e. they leave
//   out what robust mode costs.
//
//   BM_Full/<scene>    renderReference on all hardware threads (wall clock, as the command runs it):
//                      mrays_per_s, rays, build_ms.
//
//   BM_Soft/<scene>    a sized light's shadow rays against the hard light's, per ray, side by side:
//                      the scene at 480 x 270 with its first light hard and then sized (a sun of 2
//                      degrees; a sphere light of radius 0.4 where the light is a point or spot),
//                      64 light samples, one thread, Compare set, 5 rounds alternating, best CPU
//                      time of each (as BM_Ratios):
//     hard_ms_per_mray, soft_ms_per_mray  (trace - camera-only trace) / shadow rays, in ms per
//                      million shadow rays (the soft trace's rays: 64 per hit point facing the
//                      light, plus the hard ray toward the center that gives occluder_dist)
//     soft_ratio       soft_ms_per_mray / hard_ms_per_mray   (goal <= 1.1)
//     soft_ratio_baseline  the same with the baseline (SSE2) compilation
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <embree3/rtcore.h>
#include <experimental/simd>
#include <sys/resource.h>

#include "bench_scene.h"
#include "shadowlab/reference/reference.h"
#include "shadowlab/scenes/loader.h"

namespace {

using namespace shadowlab;

constexpr int kWidth = 1920;
constexpr int kHeight = 1080;
constexpr int kTile = 16;  // the reference's tile and packet layout (reference.cpp)
constexpr int kRounds = 7;

const Scene& benchSceneNamed(const std::string& name) {
  if (name == "bunny4") return bench::benchScene(4);
  static std::map<std::string, std::unique_ptr<Scene>> cache;
  auto& slot = cache[name];
  if (!slot) {
    slot = std::make_unique<Scene>(
        loadScene(resolveScenePath(name), {{"/camera/width", kWidth}, {"/camera/height", kHeight}}));
  }
  return *slot;
}

// Process CPU seconds (user + system): what ReferenceStats::traceCpuSeconds measures. On a machine
// other work shares, much steadier than wall time, and the same clock for both sides of a ratio.
double processCpuSeconds() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return double(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
         1e-6 * double(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}

// Calls f(px, py, active) for every 4 x 2 packet in the reference's order: 16 x 16 tiles row by row,
// blocks row by row within a tile.
template <class F>
void forEachPacket(int width, int height, F&& f) {
  for (int y0 = 0; y0 < height; y0 += kTile)
    for (int x0 = 0; x0 < width; x0 += kTile) {
      const int x1 = std::min(width, x0 + kTile), y1 = std::min(height, y0 + kTile);
      for (int by = y0; by < y1; by += 2)
        for (int bx = x0; bx < x1; bx += 4) {
          int px[8], py[8];
          bool active[8];
          for (int lane = 0; lane < 8; ++lane) {
            px[lane] = bx + lane % 4;
            py[lane] = by + lane / 4;
            active[lane] = px[lane] < x1 && py[lane] < y1;
          }
          f(px, py, active);
        }
    }
}

// One shadow packet, ready for rtcOccluded8.
struct ShadowPacket {
  alignas(32) int valid[8];
  float org[3][8], dir[3][8], tfar[8];
};

// A stored packet as Embree's ray packet: what every bare shadow loop below does first.
inline void fillRay8(const ShadowPacket& packet, RTCRay8& ray, int valid[8]) {
  for (int lane = 0; lane < 8; ++lane) {
    valid[lane] = packet.valid[lane];
    ray.org_x[lane] = packet.org[0][lane];
    ray.org_y[lane] = packet.org[1][lane];
    ray.org_z[lane] = packet.org[2][lane];
    ray.dir_x[lane] = packet.dir[0][lane];
    ray.dir_y[lane] = packet.dir[1][lane];
    ray.dir_z[lane] = packet.dir[2][lane];
    ray.tnear[lane] = 0;
    ray.tfar[lane] = packet.tfar[lane];
    ray.mask[lane] = ~0u;
    ray.time[lane] = 0;
    ray.id[lane] = lane;
    ray.flags[lane] = 0;
  }
}

// A plain Embree scene of the same triangles: no filter functions; robust only when asked.
struct BareScene {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  BareScene(const Scene& s, bool robust) {
    device = rtcNewDevice(nullptr);
    scene = rtcNewScene(device);
    if (robust) rtcSetSceneFlags(scene, RTC_SCENE_FLAG_ROBUST);
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
  }
  ~BareScene() {
    rtcReleaseScene(scene);
    rtcReleaseDevice(device);
  }
  BareScene(const BareScene&) = delete;
  BareScene& operator=(const BareScene&) = delete;
};

// The reference's shadow rays, rebuilt from its frame with its rules (reference/README.md): a ray per
// hit pixel whose camera-facing normal faces the light, from P + N * shadowOriginOffset toward the
// light. The bench scenes have one directional light and no projector, which is all this rebuilds.
std::vector<ShadowPacket> shadowPackets(const Scene& scene, const Frame& frame) {
  if (scene.lights.size() != 1 || scene.lights[0].type != LightType::Directional || !scene.projectors.empty())
    throw std::runtime_error("reference_rays_bench: expected one directional light and no projector");
  std::map<uint32_t, const Object*> byId;
  for (const Object& o : scene.objects) byId[o.id] = &o;
  const glm::vec3 toLight = glm::normalize(-scene.lights[0].direction);
  const float *hit = frame.get("hit").data(), *objectId = frame.get("object_id").data(),
              *primId = frame.get("prim_id").data();
  const float* p[3] = {frame.get("P.x").data(), frame.get("P.y").data(), frame.get("P.z").data()};
  const float* n[3] = {frame.get("N.x").data(), frame.get("N.y").data(), frame.get("N.z").data()};
  std::vector<ShadowPacket> packets;
  forEachPacket(frame.width, frame.height, [&](const int* px, const int* py, const bool* active) {
    ShadowPacket packet{};
    int count = 0;
    for (int lane = 0; lane < 8; ++lane) {
      packet.valid[lane] = 0;
      for (int a = 0; a < 3; ++a) packet.dir[a][lane] = toLight[a];
      packet.tfar[lane] = 0.0f;
      const size_t i = size_t(py[lane]) * frame.width + px[lane];
      if (!active[lane] || hit[i] == 0.0f) continue;
      const glm::vec3 position(p[0][i], p[1][i], p[2][i]), normal(n[0][i], n[1][i], n[2][i]);
      if (!(glm::dot(normal, toLight) > 0.0f)) continue;
      const Object& object = *byId.at(uint32_t(objectId[i]));
      const glm::uvec3& tri = object.triangles.at(size_t(primId[i]));
      const float offset =
          shadowOriginOffset(position, object.positions[tri.x], object.positions[tri.y], object.positions[tri.z]);
      const glm::vec3 origin = position + normal * offset;
      for (int a = 0; a < 3; ++a) packet.org[a][lane] = origin[a];
      packet.tfar[lane] = INFINITY;
      packet.valid[lane] = -1;
      ++count;
    }
    if (count) packets.push_back(packet);
  });
  return packets;
}

// A camera packet's fields other than its directions: every ray from the camera over [0, inf).
inline void fillCameraRays(const Camera& camera, const bool* active, RTCRayHit8& rh, int valid[8]) {
  for (int lane = 0; lane < 8; ++lane) {
    valid[lane] = active[lane] ? -1 : 0;
    rh.ray.org_x[lane] = camera.position.x;
    rh.ray.org_y[lane] = camera.position.y;
    rh.ray.org_z[lane] = camera.position.z;
    rh.ray.tnear[lane] = 0;
    rh.ray.tfar[lane] = INFINITY;
    rh.ray.mask[lane] = ~0u;
    rh.ray.time[lane] = 0;
    rh.ray.id[lane] = lane;
    rh.ray.flags[lane] = 0;
    rh.hit.geomID[lane] = RTC_INVALID_GEOMETRY_ID;
  }
}

// rtcIntersect8 over the camera's packets, their directions filled by setDirections(rays, px, py,
// active, rh).
template <class SetDirections>
double bareCameraLoop(const Camera& camera, RTCScene scene, SetDirections&& setDirections) {
  const double start = processCpuSeconds();
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  const CameraRays rays(camera);
  forEachPacket(camera.width, camera.height, [&](const int* px, const int* py, const bool* active) {
    RTCRayHit8 rh;
    alignas(32) int valid[8];
    setDirections(rays, px, py, active, rh);
    fillCameraRays(camera, active, rh, valid);
    rtcIntersect8(valid, scene, &context, &rh);
    benchmark::DoNotOptimize(rh.hit.geomID[0]);
  });
  return processCpuSeconds() - start;
}

double bareIntersect(const Camera& camera, RTCScene scene) {
  return bareCameraLoop(camera, scene, [](const CameraRays& rays, const int* px, const int* py, const bool* active,
                                          RTCRayHit8& rh) {
    for (int lane = 0; lane < 8; ++lane) {
      const glm::vec3 d = active[lane] ? rays.direction(px[lane] + 0.5f, py[lane] + 0.5f) : glm::vec3(0, 0, 1);
      rh.ray.dir_x[lane] = d.x;
      rh.ray.dir_y[lane] = d.y;
      rh.ray.dir_z[lane] = d.z;
    }
  });
}

// bareIntersect with each packet's directions made as the reference makes them: in one go over
// its 8 lanes (CameraRays::perspectiveDirection), here in the baseline (SSE2) compilation.
double bareIntersectPacked(const Camera& camera, RTCScene scene) {
  return bareCameraLoop(camera, scene, [](const CameraRays& rays, const int* px, const int* py, const bool*,
                                          RTCRayHit8& rh) {
    namespace stdx = std::experimental;
    using DoubleN = stdx::fixed_size_simd<double, 8>;
    using FloatN = stdx::fixed_size_simd<float, 8>;
    const DoubleN x([&](auto lane) { return double(float(px[lane]) + 0.5f); });
    const DoubleN y([&](auto lane) { return double(float(py[lane]) + 0.5f); });
    DoubleN d[3];
    rays.perspectiveDirection(x, y, d);
    stdx::static_simd_cast<FloatN>(d[0]).copy_to(rh.ray.dir_x, stdx::element_aligned);
    stdx::static_simd_cast<FloatN>(d[1]).copy_to(rh.ray.dir_y, stdx::element_aligned);
    stdx::static_simd_cast<FloatN>(d[2]).copy_to(rh.ray.dir_z, stdx::element_aligned);
  });
}

// rtcIntersect8 (closest hit) over the same shadow rays: what a bare loop that also needs the
// occluder's distance (occluder_dist) pays.
double bareClosest(const std::vector<ShadowPacket>& packets, RTCScene scene) {
  const double start = processCpuSeconds();
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  for (const ShadowPacket& packet : packets) {
    RTCRayHit8 rh;
    alignas(32) int valid[8];
    fillRay8(packet, rh.ray, valid);
    for (int lane = 0; lane < 8; ++lane) rh.hit.geomID[lane] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect8(valid, scene, &context, &rh);
    benchmark::DoNotOptimize(rh.hit.geomID[0]);
  }
  return processCpuSeconds() - start;
}

// bareOccluded's loop without the Embree call: what reading the stored packets (one per 4 x 2
// block, from memory: they do not fit in the cache) and filling RTCRay8 costs the bare loop. A loop
// that made its rays from hits in registers would not pay it, so bare_shadow_ms minus this is the
// strictest bare baseline (shadow_ratio_embree).
double bareShadowSetup(const std::vector<ShadowPacket>& packets) {
  const double start = processCpuSeconds();
  for (const ShadowPacket& packet : packets) {
    RTCRay8 ray;
    alignas(32) int valid[8];
    fillRay8(packet, ray, valid);
    benchmark::DoNotOptimize(valid);
    benchmark::DoNotOptimize(ray);
    benchmark::ClobberMemory();
  }
  return processCpuSeconds() - start;
}

double bareOccluded(const std::vector<ShadowPacket>& packets, RTCScene scene) {
  const double start = processCpuSeconds();
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  for (const ShadowPacket& packet : packets) {
    RTCRay8 ray;
    alignas(32) int valid[8];
    fillRay8(packet, ray, valid);
    rtcOccluded8(valid, scene, &context, &ray);
    benchmark::DoNotOptimize(ray.tfar[0]);
  }
  return processCpuSeconds() - start;
}

void BM_Ratios(benchmark::State& state, const std::string& name) {
  const Scene& scene = benchSceneNamed(name);
  Scene cameraOnly = scene;
  cameraOnly.lights.clear();
  cameraOnly.projectors.clear();
  ReferenceOptions options;
  options.threads = 1;
  options.channels = ReferenceChannels::Compare;  // what the reference cache traces
  ReferenceOptions baselineOptions = options;
  baselineOptions.simd = ReferenceSimd::Baseline;
  ReferenceOptions allOptions = options;
  allOptions.channels = ReferenceChannels::All;  // what `shadowlab reference` traces (the picture needs P, N)
  BareScene bare(scene, false), bareRobust(scene, true);
  ReferenceStats fullStats;
  const std::vector<ShadowPacket> packets = shadowPackets(scene, renderReference(scene, allOptions, &fullStats));
  size_t bareShadowRays = 0;
  for (const ShadowPacket& packet : packets)
    for (int lane = 0; lane < 8; ++lane) bareShadowRays += packet.valid[lane] ? 1 : 0;

  double refPrimary = 1e30, refFull = 1e30, allPrimary = 1e30, allFull = 1e30, barePrimary = 1e30, bareShadow = 1e30,
         barePrimaryRobust = 1e30, bareShadowRobust = 1e30, bareClosestHit = 1e30, bareSetup = 1e30,
         baselinePrimary = 1e30, baselineFull = 1e30, barePacked = 1e30;
  for (auto _ : state) {
    double total = 0;
    for (int round = 0; round < kRounds; ++round) {
      ReferenceStats stats;
      benchmark::DoNotOptimize(renderReference(cameraOnly, options, &stats).data.data());
      refPrimary = std::min(refPrimary, stats.traceCpuSeconds);
      benchmark::DoNotOptimize(renderReference(scene, options, &stats).data.data());
      refFull = std::min(refFull, stats.traceCpuSeconds);
      const double compareFull = stats.traceCpuSeconds;
      benchmark::DoNotOptimize(renderReference(cameraOnly, allOptions, &stats).data.data());
      allPrimary = std::min(allPrimary, stats.traceCpuSeconds);
      benchmark::DoNotOptimize(renderReference(scene, allOptions, &stats).data.data());
      allFull = std::min(allFull, stats.traceCpuSeconds);
      benchmark::DoNotOptimize(renderReference(cameraOnly, baselineOptions, &stats).data.data());
      baselinePrimary = std::min(baselinePrimary, stats.traceCpuSeconds);
      benchmark::DoNotOptimize(renderReference(scene, baselineOptions, &stats).data.data());
      baselineFull = std::min(baselineFull, stats.traceCpuSeconds);
      const double seconds[4] = {bareIntersect(scene.camera, bare.scene), bareOccluded(packets, bare.scene),
                                 bareIntersect(scene.camera, bareRobust.scene),
                                 bareOccluded(packets, bareRobust.scene)};
      barePrimary = std::min(barePrimary, seconds[0]);
      barePacked = std::min(barePacked, bareIntersectPacked(scene.camera, bare.scene));
      bareShadow = std::min(bareShadow, seconds[1]);
      bareClosestHit = std::min(bareClosestHit, bareClosest(packets, bare.scene));
      bareSetup = std::min(bareSetup, bareShadowSetup(packets));
      barePrimaryRobust = std::min(barePrimaryRobust, seconds[2]);
      bareShadowRobust = std::min(bareShadowRobust, seconds[3]);
      total += compareFull;
    }
    state.SetIterationTime(total);
  }
  const double refShadow = refFull - refPrimary;
  state.counters["primary_ratio"] = refPrimary / barePrimary;
  state.counters["bare_primary_packed_ms"] = barePacked * 1e3;
  state.counters["primary_ratio_packed"] = refPrimary / barePacked;
  state.counters["primary_ratio_packed_baseline"] = baselinePrimary / barePacked;
  state.counters["shadow_ratio"] = refShadow / bareShadow;
  state.counters["shadow_ratio_closest"] = refShadow / bareClosestHit;
  state.counters["bare_shadow_closest_ms"] = bareClosestHit * 1e3;
  state.counters["shadow_ratio_embree"] = refShadow / (bareShadow - bareSetup);
  state.counters["bare_shadow_setup_ms"] = bareSetup * 1e3;
  state.counters["primary_ratio_robust"] = refPrimary / barePrimaryRobust;
  state.counters["shadow_ratio_robust"] = refShadow / bareShadowRobust;
  state.counters["ref_primary_baseline_ms"] = baselinePrimary * 1e3;
  state.counters["ref_shadow_baseline_ms"] = (baselineFull - baselinePrimary) * 1e3;
  state.counters["primary_ratio_baseline"] = baselinePrimary / barePrimary;
  state.counters["shadow_ratio_baseline"] = (baselineFull - baselinePrimary) / bareShadow;
  state.counters["simd_avx2"] = referenceHasAvx2() ? 1.0 : 0.0;
  state.counters["primary_ratio_all"] = allPrimary / barePrimary;
  state.counters["shadow_ratio_all"] = (allFull - allPrimary) / bareShadow;
  state.counters["ref_primary_ms"] = refPrimary * 1e3;
  state.counters["ref_shadow_ms"] = refShadow * 1e3;
  state.counters["bare_primary_ms"] = barePrimary * 1e3;
  state.counters["bare_shadow_ms"] = bareShadow * 1e3;
  state.counters["camera_rays"] = double(fullStats.primaryRays);
  // The same count as bare_shadow_rays: the reference traces each shadow ray once.
  state.counters["ref_shadow_rays"] = double(fullStats.shadowRays);
  state.counters["bare_shadow_rays"] = double(bareShadowRays);
}

void BM_Full(benchmark::State& state, const std::string& name) {
  const Scene& scene = benchSceneNamed(name);
  ReferenceOptions options;
  options.threads = 0;
  ReferenceStats stats;
  double best = 1e30;
  for (auto _ : state) {
    Frame frame = renderReference(scene, options, &stats);
    state.SetIterationTime(stats.traceSeconds);
    best = std::min(best, stats.traceSeconds);
    benchmark::DoNotOptimize(frame.data.data());
  }
  state.counters["mrays_per_s"] = (stats.primaryRays + stats.shadowRays) / best * 1e-6;
  state.counters["rays"] = double(stats.primaryRays + stats.shadowRays);
  state.counters["build_ms"] = stats.buildSeconds * 1e3;
}

// The scene for BM_Soft: the bench scene (or a bundled one) at 480 x 270, its first light hard or
// sized.
Scene softBenchScene(const std::string& name, bool sized) {
  Scene scene = benchSceneNamed(name);
  scene.camera.width = 480;
  scene.camera.height = 270;
  Light& light = scene.lights.front();
  light.angularDiameterDeg = 0.0f;
  light.radius = 0.0f;
  if (sized) {
    if (light.type == LightType::Directional) {
      light.angularDiameterDeg = 2.0f;
    } else {
      light.radius = 0.4f;
    }
  }
  return scene;
}

void BM_Soft(benchmark::State& state, const std::string& name) {
  const Scene hard = softBenchScene(name, false), soft = softBenchScene(name, true);
  Scene cameraOnly = hard;
  cameraOnly.lights.clear();
  cameraOnly.projectors.clear();
  ReferenceOptions options;
  options.threads = 1;
  options.channels = ReferenceChannels::Compare;
  options.lightSamples = 64;
  ReferenceOptions baselineOptions = options;
  baselineOptions.simd = ReferenceSimd::Baseline;
  double primary = 1e30, hardFull = 1e30, softFull = 1e30, basePrimary = 1e30, baseHard = 1e30, baseSoft = 1e30;
  ReferenceStats hardStats, softStats;
  for (auto _ : state) {
    double total = 0;
    for (int round = 0; round < 5; ++round) {
      ReferenceStats stats;
      benchmark::DoNotOptimize(renderReference(cameraOnly, options, &stats).data.data());
      primary = std::min(primary, stats.traceCpuSeconds);
      benchmark::DoNotOptimize(renderReference(hard, options, &hardStats).data.data());
      hardFull = std::min(hardFull, hardStats.traceCpuSeconds);
      benchmark::DoNotOptimize(renderReference(soft, options, &softStats).data.data());
      softFull = std::min(softFull, softStats.traceCpuSeconds);
      total += softStats.traceCpuSeconds;
      benchmark::DoNotOptimize(renderReference(cameraOnly, baselineOptions, &stats).data.data());
      basePrimary = std::min(basePrimary, stats.traceCpuSeconds);
      benchmark::DoNotOptimize(renderReference(hard, baselineOptions, &stats).data.data());
      baseHard = std::min(baseHard, stats.traceCpuSeconds);
      benchmark::DoNotOptimize(renderReference(soft, baselineOptions, &stats).data.data());
      baseSoft = std::min(baseSoft, stats.traceCpuSeconds);
    }
    state.SetIterationTime(total);
  }
  const double hardRays = double(hardStats.shadowRays), softRays = double(softStats.shadowRays);
  const double hardPerRay = (hardFull - primary) / hardRays * 1e9, softPerRay = (softFull - primary) / softRays * 1e9;
  state.counters["hard_shadow_rays"] = hardRays;
  state.counters["soft_shadow_rays"] = softRays;
  state.counters["hard_ms_per_mray"] = hardPerRay;
  state.counters["soft_ms_per_mray"] = softPerRay;
  state.counters["soft_ratio"] = softPerRay / hardPerRay;
  state.counters["soft_ratio_baseline"] = ((baseSoft - basePrimary) / softRays) / ((baseHard - basePrimary) / hardRays);
  state.counters["simd_avx2"] = referenceHasAvx2() ? 1.0 : 0.0;
}

}  // namespace

int main(int argc, char** argv) {
  for (const char* name : {"sphere_on_plane", "bunny4"}) {
    const std::string scene = name;
    benchmark::RegisterBenchmark(("BM_Ratios/" + scene).c_str(), BM_Ratios, scene)
        ->Iterations(1)
        ->UseManualTime()
        ->Unit(benchmark::kMillisecond);
    benchmark::RegisterBenchmark(("BM_Full/" + scene).c_str(), BM_Full, scene)
        ->UseManualTime()
        ->Unit(benchmark::kMillisecond);
  }
  for (const char* name : {"sphere_on_plane", "bunny4", "soft_post"}) {
    const std::string scene = name;
    benchmark::RegisterBenchmark(("BM_Soft/" + scene).c_str(), BM_Soft, scene)
        ->Iterations(1)
        ->UseManualTime()
        ->Unit(benchmark::kMillisecond);
  }
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
