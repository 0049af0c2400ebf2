// renderReference: the Embree ground truth. See reference/README.md for the channels, the
// shadow-ray origin method and the sample pattern.
#include "shadowlab/reference/reference.h"

#include <algorithm>
#include <atomic>
#include <mutex>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <set>

#include <sys/resource.h>
#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <xmmintrin.h>

#include "embree_scene.h"
#include "picture_shading.h"
#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/io.h"

namespace shadowlab {
namespace {

using namespace reference_detail;

static_assert(sizeof(glm::vec3) == 3 * sizeof(float), "positions are copied to Embree as packed float3");
static_assert(sizeof(glm::uvec3) == 3 * sizeof(unsigned), "triangles are copied to Embree as packed uint3");

constexpr int kTileSize = 16;   // pixels per tile side: the unit of parallel work
constexpr int kBlockWidth = 4;  // a camera packet is a 4 x 2 pixel block
constexpr int kBlockHeight = 2;
static_assert(kBlockWidth * kBlockHeight == kLanes, "one camera packet per block");
constexpr float kInf = std::numeric_limits<float>::infinity();

// Shadow-ray origins move off the surface by this many units of the largest coordinate magnitude
// among the hit point and its triangle's vertices: 2^-17, i.e. 128 times float's half-ulp (2^-24).
// Embree's robust triangle test works on vertex coordinates relative to the ray origin, so its
// rounding (and the rounding of the barycentric hit point) scale with those magnitudes; 128x
// keeps the origin on the light's side of the own triangle and of every coplanar neighbour: the
// own plane lies behind the origin, at t = -offset / cos(angle to the normal), which Embree's
// rounding (a few ulps of those magnitudes) cannot bring to t > 0. No filter rule by identity is
// needed, so opaque geometry is traced without a filter callback.
constexpr float kOriginOffsetScale = 1.0f / 131072.0f;

struct LaneHit {
  bool hit = false;
  unsigned geom = 0;
  unsigned prim = 0;
  float objectId = 0.0f;     // Object::id of the geometry, as the object_id channel stores it
  glm::vec3 position{0.0f};  // world, on the triangle (barycentric interpolation in double)
  glm::vec3 normal{0.0f};    // unit geometric normal facing the camera
  float offset = 0.0f;       // world distance shadow origins move along `normal`
  glm::vec3 origin{0.0f};    // shadow-ray origin: position + normal * offset
};

struct PreparedLight {
  const Light* light = nullptr;
  glm::vec3 toLight{0.0f};    // directional: unit, -direction
  double cosHalfCone = -1.0;  // spot: lit where cos(angle to the axis) >= this
};

struct PreparedProjector {
  const Projector* projector = nullptr;
  glm::dmat4 texFromWorld{1.0};
};

struct ProjectorSample {
  float coverage = 0.0f;
  float u = 0.0f, v = 0.0f;
  glm::vec3 rgb{0.0f};
};

// The spp > 1 pattern, in pixel units relative to the pixel's top-left corner. A square count
// is the k x k grid of cell centers; any other count is the Hammersley set ((i + 0.5) / N,
// radical inverse of i, centred in its 2^ceil(log2 N) strata): one sample per column and per
// dyadic row stratum. Both are fixed (no random jitter), so results are reproducible.
std::vector<glm::vec2> samplePattern(int spp) {
  std::vector<glm::vec2> pattern;
  const int k = int(std::lround(std::sqrt(double(spp))));
  if (k * k == spp) {
    for (int b = 0; b < k; ++b)
      for (int a = 0; a < k; ++a) pattern.emplace_back((a + 0.5f) / k, (b + 0.5f) / k);
    return pattern;
  }
  int levels = 0;
  while ((1 << levels) < spp) ++levels;
  const double rowShift = 0.5 / double(1 << levels);
  for (int i = 0; i < spp; ++i) {
    double inverse = 0.0, weight = 0.5;
    for (unsigned bits = unsigned(i); bits; bits >>= 1, weight *= 0.5)
      if (bits & 1u) inverse += weight;
    pattern.emplace_back(float((i + 0.5) / spp), float(inverse + rowShift));
  }
  return pattern;
}

// shadowOriginOffset, inlined into the trace.
inline float maxAbs(const glm::vec3& p) { return std::max(std::fabs(p.x), std::max(std::fabs(p.y), std::fabs(p.z))); }
inline float originOffset(const glm::vec3& position, const glm::vec3& p0, const glm::vec3& p1, const glm::vec3& p2) {
  return kOriginOffsetScale * std::max(std::max(maxAbs(position), maxAbs(p0)), std::max(maxAbs(p1), maxAbs(p2)));
}

class Tracer {
 public:
  Tracer(const Scene& scene, const EmbreeScene& embree, const float* objectIds)
      : scene_(scene), embree_(embree), rays_(scene.camera), objectIds_(objectIds) {}

  // Camera rays through (px + dx, py + dy) for the active lanes.
  // Without `surface` only hit, geom, prim and objectId are filled: no shadow ray or All channel
  // needs the rest (position, normal, offset and origin are meaningful only where hit).
  void tracePrimary(const int* px, const int* py, const bool* active, float dx, float dy, bool surface, LaneHit* hits) {
    RTCRayHit8 rayHit;
    alignas(32) int valid[kLanes];
    const glm::vec3 org = scene_.camera.position;
    for (int lane = 0; lane < kLanes; ++lane) {
      valid[lane] = active[lane] ? -1 : 0;
      const glm::vec3 dir = active[lane] ? rays_.direction(px[lane] + dx, py[lane] + dy) : glm::vec3(0, 0, 1);
      rayHit.ray.org_x[lane] = org.x;
      rayHit.ray.org_y[lane] = org.y;
      rayHit.ray.org_z[lane] = org.z;
      rayHit.ray.dir_x[lane] = dir.x;
      rayHit.ray.dir_y[lane] = dir.y;
      rayHit.ray.dir_z[lane] = dir.z;
      rayHit.ray.tnear[lane] = 0.0f;
      rayHit.ray.tfar[lane] = kInf;
      rayHit.ray.time[lane] = 0.0f;
      rayHit.ray.mask[lane] = ~0u;
      rayHit.ray.id[lane] = unsigned(lane);
      rayHit.ray.flags[lane] = 0;
      rayHit.hit.geomID[lane] = RTC_INVALID_GEOMETRY_ID;
      rayHit.hit.primID[lane] = RTC_INVALID_GEOMETRY_ID;
      primaryRays += active[lane] ? 1 : 0;
    }
    TraceContext context(RayKind::Camera);
    rtcIntersect8(valid, embree_.handle(), &context.rtc, &rayHit);
    for (int lane = 0; lane < kLanes; ++lane) {
      LaneHit& h = hits[lane];
      h.hit = active[lane] && rayHit.hit.geomID[lane] != RTC_INVALID_GEOMETRY_ID;
      if (!h.hit) continue;
      h.geom = rayHit.hit.geomID[lane];
      h.prim = rayHit.hit.primID[lane];
      h.objectId = objectIds_[h.geom];
      if (!surface) continue;
      const TriangleData& triangle = embree_.geometry(h.geom).triangles[h.prim];
      const double u = rayHit.hit.u[lane], v = rayHit.hit.v[lane];
      h.position = glm::vec3((1.0 - u - v) * glm::dvec3(triangle.p[0]) + u * glm::dvec3(triangle.p[1]) +
                             v * glm::dvec3(triangle.p[2]));
      glm::vec3 normal = triangle.normal;
      if (normal == glm::vec3(0.0f)) {
        normal = glm::normalize(glm::vec3(rayHit.hit.Ng_x[lane], rayHit.hit.Ng_y[lane], rayHit.hit.Ng_z[lane]));
      }
      const glm::vec3 dir(rayHit.ray.dir_x[lane], rayHit.ray.dir_y[lane], rayHit.ray.dir_z[lane]);
      h.normal = glm::dot(normal, dir) > 0.0f ? -normal : normal;
      // shadowOriginOffset, with the vertices' part taken from the triangle's table.
      h.offset = kOriginOffsetScale * std::max(maxAbs(h.position), triangle.maxAbs);
      h.origin = h.position + h.normal * h.offset;
    }
  }

  // Occlusion of the segments from each active lane's shadow origin along dir[lane] up to
  // tfar[lane]. With wantDistance the packet is one closest-hit query (rtcIntersect8): a lane is
  // occluded where it hits anything, and the hit's t gives the occluder distance. Without, an any-hit
  // query (rtcOccluded8). Both run the same triangle test and filter on the same segment, so they
  // agree on which lanes are occluded (every bundled scene's channels are bit-identical to the two
  // passes this replaced: rtcOccluded8, then rtcIntersect8 again for the occluded lanes); lanes that
  // reach the sky, usually most, cost a closest-hit query what they cost an any-hit one.
  void traceShadow(const LaneHit* hits, const glm::vec3* dir, const float* tfar, const bool* active, bool wantDistance,
                   bool* occluded, float* distance) {
    RTCRayHit8 rayHit;
    RTCRay8& ray = rayHit.ray;
    alignas(32) int valid[kLanes];
    TraceContext& context = shadowContext_;
    int count = 0;
    for (int lane = 0; lane < kLanes; ++lane) {
      occluded[lane] = false;
      distance[lane] = -1.0f;
      valid[lane] = active[lane] ? -1 : 0;
      const glm::vec3 origin = active[lane] ? hits[lane].origin : glm::vec3(0.0f);
      const glm::vec3 d = active[lane] ? dir[lane] : glm::vec3(0, 1, 0);
      ray.org_x[lane] = origin.x;
      ray.org_y[lane] = origin.y;
      ray.org_z[lane] = origin.z;
      ray.dir_x[lane] = d.x;
      ray.dir_y[lane] = d.y;
      ray.dir_z[lane] = d.z;
      ray.tnear[lane] = 0.0f;
      ray.tfar[lane] = active[lane] ? tfar[lane] : 0.0f;
      ray.time[lane] = 0.0f;
      ray.mask[lane] = ~0u;
      ray.id[lane] = unsigned(lane);
      ray.flags[lane] = 0;
      count += active[lane] ? 1 : 0;
    }
    if (count == 0) return;
    shadowRays += count;
    if (!wantDistance) {
      rtcOccluded8(valid, embree_.handle(), &context.rtc, &ray);
      // Embree marks an occluded ray by setting tfar to -inf.
      for (int lane = 0; lane < kLanes; ++lane) occluded[lane] = active[lane] && ray.tfar[lane] < 0.0f;
      return;
    }
    for (int lane = 0; lane < kLanes; ++lane) rayHit.hit.geomID[lane] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect8(valid, embree_.handle(), &context.rtc, &rayHit);
    for (int lane = 0; lane < kLanes; ++lane) {
      occluded[lane] = active[lane] && rayHit.hit.geomID[lane] != RTC_INVALID_GEOMETRY_ID;
      // The distance is measured from the surface point itself, not from the offset origin.
      if (occluded[lane])
        distance[lane] = glm::length(hits[lane].normal * hits[lane].offset + dir[lane] * ray.tfar[lane]);
    }
  }

  // Visibility (exactly 0 or 1) of one light at each hit lane; distance to the nearest occluder
  // (-1 where none; 0 where the visible side of the surface faces away from the light).
  void evalLight(const PreparedLight& prepared, const LaneHit* hits, bool wantDistance, float* vis, float* distance) {
    const Light& light = *prepared.light;
    glm::vec3 dir[kLanes];
    float tfar[kLanes];
    bool active[kLanes];
    for (int lane = 0; lane < kLanes; ++lane) {
      active[lane] = false;
      vis[lane] = 0.0f;
      distance[lane] = -1.0f;
      const LaneHit& h = hits[lane];
      if (!h.hit) continue;
      glm::vec3 toLight;
      if (light.type == LightType::Directional) {
        toLight = prepared.toLight;
        tfar[lane] = kInf;
        dir[lane] = toLight;
      } else {
        toLight = light.position - h.position;
        if (light.type == LightType::Spot) {
          const glm::dvec3 fromLight = glm::dvec3(h.position) - glm::dvec3(light.position);
          const double length = glm::length(fromLight);
          const double cosAngle = length > 0.0 ? glm::dot(fromLight, glm::dvec3(light.direction)) / length : -1.0;
          if (cosAngle < prepared.cosHalfCone) continue;  // outside the cone: unlit, no occluder
        }
        const glm::vec3 segment = light.position - h.origin;
        tfar[lane] = glm::length(segment);
        if (!(tfar[lane] > 0.0f)) continue;
        dir[lane] = segment / tfar[lane];
      }
      // The camera sees the side `normal` points to; light arriving from the other side lights
      // only the hidden side. The surface itself is the occluder, at distance 0.
      if (!(glm::dot(h.normal, toLight) > 0.0f)) {
        distance[lane] = 0.0f;
        continue;
      }
      active[lane] = true;
    }
    bool occluded[kLanes];
    float occluderDistance[kLanes];
    traceShadow(hits, dir, tfar, active, wantDistance, occluded, occluderDistance);
    for (int lane = 0; lane < kLanes; ++lane) {
      if (!active[lane]) continue;
      vis[lane] = occluded[lane] ? 0.0f : 1.0f;
      distance[lane] = occluded[lane] ? occluderDistance[lane] : -1.0f;
    }
  }

  void evalProjector(const PreparedProjector& prepared, const LaneHit* hits, ProjectorSample* out) {
    const Projector& projector = *prepared.projector;
    glm::vec3 dir[kLanes];
    float tfar[kLanes];
    bool active[kLanes];
    for (int lane = 0; lane < kLanes; ++lane) {
      active[lane] = false;
      out[lane] = ProjectorSample{};
      const LaneHit& h = hits[lane];
      if (!h.hit) continue;
      const glm::dvec4 clip = prepared.texFromWorld * glm::dvec4(glm::dvec3(h.position), 1.0);
      const double w = clip.w;
      const double u = w != 0.0 ? clip.x / w : 0.0;
      const double v = w != 0.0 ? clip.y / w : 0.0;
      const double depth = w != 0.0 ? clip.z / w : 0.0;
      out[lane].u = float(u);
      out[lane].v = float(v);
      const bool inside = w > 0.0 && u >= 0.0 && u <= 1.0 && v >= 0.0 && v <= 1.0 && depth >= 0.0 && depth <= 1.0;
      if (!inside) continue;
      if (!(glm::dot(h.normal, projector.position - h.position) > 0.0f)) continue;  // lights the hidden side
      const glm::vec3 segment = projector.position - h.origin;
      tfar[lane] = glm::length(segment);
      if (!(tfar[lane] > 0.0f)) continue;
      dir[lane] = segment / tfar[lane];
      active[lane] = true;
    }
    bool occluded[kLanes];
    float unusedDistance[kLanes];
    traceShadow(hits, dir, tfar, active, false, occluded, unusedDistance);
    const Image& image = projector.image;
    for (int lane = 0; lane < kLanes; ++lane) {
      if (!active[lane] || occluded[lane]) continue;
      out[lane].coverage = 1.0f;
      if (image.width > 0 && image.height > 0 && image.channels > 0) {
        // NEAREST: texel floor(u * W), floor(v * H), with u = 1 (v = 1) in the last column (row).
        const int x = std::min(image.width - 1, std::max(0, int(std::floor(double(out[lane].u) * image.width))));
        const int y = std::min(image.height - 1, std::max(0, int(std::floor(double(out[lane].v) * image.height))));
        for (int c = 0; c < 3; ++c) out[lane].rgb[c] = image.at(x, y, std::min(c, image.channels - 1));
      }
    }
  }

  uint64_t primaryRays = 0;
  uint64_t shadowRays = 0;

 private:
  TraceContext shadowContext_{RayKind::Shadow};
  const Scene& scene_;
  const EmbreeScene& embree_;
  const CameraRays rays_;   // Camera::rayDirection, bit for bit
  const float* objectIds_;  // per geometry id: Object::id as a float
};

// The output channels, one pointer each, in the frame's channel order (referenceChannelNames):
// base[c] is channel c's first value. Without the All set, primId, p, n, u and v are null.
struct Planes {
  float* hit = nullptr;
  float* objectId = nullptr;
  float* primId = nullptr;
  float* p[3] = {};
  float* n[3] = {};
  std::vector<float*> vis, occluderDist;
  std::vector<float*> coverage, u, v, rgb[3];

  Planes(float* const* base, size_t channelCount, size_t lightCount, size_t projectorCount, bool all)
      : vis(lightCount), occluderDist(lightCount), coverage(projectorCount), u(projectorCount), v(projectorCount) {
    size_t index = 0;
    hit = base[index++];
    objectId = base[index++];
    if (all) {
      primId = base[index++];
      for (int a = 0; a < 3; ++a) p[a] = base[index++];
      for (int a = 0; a < 3; ++a) n[a] = base[index++];
    }
    for (size_t l = 0; l < lightCount; ++l) {
      vis[l] = base[index++];
      occluderDist[l] = base[index++];
    }
    for (size_t q = 0; q < projectorCount; ++q) {
      coverage[q] = base[index++];
      if (all) {
        u[q] = base[index++];
        v[q] = base[index++];
      }
      for (int c = 0; c < 3; ++c) rgb[c].push_back(base[index++]);
    }
    if (index != channelCount) throw DriverError("reference: channel layout out of step with referenceChannelNames");
  }
};

constexpr int kTilePixels = kTileSize * kTileSize;

// A tile's values are written to a small buffer first (kTileSize x kTileSize floats per channel,
// in cache), then copied to the frame's planes row by row. A full row of a 16-pixel tile is 64
// bytes, a cache line: where the plane row is 16-byte aligned it is copied with streaming stores,
// which write whole lines without first reading them from memory (half the memory traffic of
// writing each pixel into the planes directly, which made those writes most of the reference's
// cost beyond Embree's). The caller fences (_mm_sfence) before the frame is read.
void copyTileRows(const float* tile, float* plane, int width, int x0, int y0, int x1, int y1) {
  const int count = x1 - x0;
  for (int y = y0; y < y1; ++y) {
    const float* src = tile + (y - y0) * kTileSize;
    float* dst = plane + size_t(y) * size_t(width) + size_t(x0);
    if (count % 4 == 0 && reinterpret_cast<uintptr_t>(dst) % 16 == 0) {
      for (int x = 0; x < count; x += 4) _mm_stream_ps(dst + x, _mm_loadu_ps(src + x));
    } else {
      std::memcpy(dst, src, size_t(count) * sizeof(float));
    }
  }
}

}  // namespace

// Process CPU seconds so far (user + system, all threads).
static double processCpuSeconds() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return double(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
         1e-6 * double(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}

float shadowOriginOffset(const glm::vec3& position, const glm::vec3& p0, const glm::vec3& p1, const glm::vec3& p2) {
  return originOffset(position, p0, p1, p2);
}

const char* referenceChannelsKey(ReferenceChannels channels) {
  return channels == ReferenceChannels::All ? "all" : "compare";
}

std::vector<std::string> referenceChannelNames(const Scene& scene, ReferenceChannels channels) {
  const bool all = channels == ReferenceChannels::All;
  std::vector<std::string> names = {"hit", "object_id"};
  if (all) {
    names.push_back("prim_id");
    for (const char* axis : {"x", "y", "z"}) names.push_back(std::string("P.") + axis);
    for (const char* axis : {"x", "y", "z"}) names.push_back(std::string("N.") + axis);
  }
  for (const Light& light : scene.lights) {
    names.push_back("light." + light.name + ".vis");
    names.push_back("light." + light.name + ".occluder_dist");
  }
  for (const Projector& projector : scene.projectors) {
    const std::string prefix = "proj." + projector.name + ".";
    names.push_back(prefix + "coverage");
    if (all) {
      names.push_back(prefix + "u");
      names.push_back(prefix + "v");
    }
    for (const char* color : {"R", "G", "B"}) names.push_back(prefix + color);
  }
  return names;
}

double referenceFrameBytes(const Scene& scene, ReferenceChannels channels) {
  const double count = double(referenceChannelNames(scene, channels).size());
  return count * 4.0 * double(scene.camera.width) * double(scene.camera.height);
}

Frame renderReference(const Scene& scene, const ReferenceOptions& options, ReferenceStats* stats,
                      std::vector<uint8_t>* picture) {
  if (options.spp < 1 || options.spp > 1024) {
    throw InputError("reference: error: spp " + std::to_string(options.spp) + "; expected 1..1024");
  }
  if (options.threads < 0) {
    throw InputError("reference: error: threads " + std::to_string(options.threads) + "; expected 0 (all) or more");
  }
  const int width = scene.camera.width;
  const int height = scene.camera.height;
  if (width < 1 || height < 1) {
    throw InputError(
        formatError(scene.path, "/camera",
                    "resolution " + std::to_string(width) + "x" + std::to_string(height) + "; expected at least 1x1"));
  }
  {
    std::set<std::string> lightNames, projectorNames;
    for (const Light& light : scene.lights) {
      if (!lightNames.insert(light.name).second)
        throw InputError(
            formatError(scene.path, "/lights", "two lights named \"" + light.name + "\"; expected unique names"));
    }
    for (const Projector& projector : scene.projectors) {
      if (!projectorNames.insert(projector.name).second)
        throw InputError(formatError(scene.path, "/projectors",
                                     "two projectors named \"" + projector.name + "\"; expected unique names"));
    }
  }

  const bool all = options.channels == ReferenceChannels::All;
  Frame frame;
  frame.width = width;
  frame.height = height;
  for (const std::string& name : referenceChannelNames(scene, options.channels)) {
    const bool distance = name.size() > 14 && name.compare(name.size() - 14, 14, ".occluder_dist") == 0;
    frame.add(name, distance ? -1.0f : 0.0f);
  }
  std::vector<PreparedLight> lights;
  for (const Light& light : scene.lights) {
    PreparedLight prepared;
    prepared.light = &light;
    prepared.toLight = glm::normalize(-light.direction);
    if (light.type == LightType::Spot) prepared.cosHalfCone = std::cos(double(light.coneDeg) * 0.5 * M_PI / 180.0);
    lights.push_back(prepared);
  }
  std::vector<PreparedProjector> projectors;
  for (const Projector& projector : scene.projectors)
    projectors.push_back({&projector, glm::dmat4(projector.texFromWorld())});
  // The channels in Planes' order (frame.add may move planes while channels are added: taken now).
  const size_t channelCount = frame.data.size();
  std::vector<float*> frameBase(channelCount);
  for (size_t c = 0; c < channelCount; ++c) frameBase[c] = frame.data[c].data();

  nlohmann::json lightNames = nlohmann::json::array(), projectorNames = nlohmann::json::array();
  for (const Light& light : scene.lights) lightNames.push_back(light.name);
  for (const Projector& projector : scene.projectors) projectorNames.push_back(projector.name);
  frame.meta = {{"kind", "reference"},
                {"scene", scene.name},
                {"scene_hash", scene.hash},
                {"camera_hash", scene.camera.hash()},
                {"width", width},
                {"height", height},
                {"lights", lightNames},
                {"projectors", projectorNames},
                {"spp", options.spp},
                {"reference_hash", referenceHash(scene, options)},
                {"channels", referenceChannelsKey(options.channels)}};

  const int threads = options.threads > 0 ? options.threads : std::max(1, tbb::info::default_concurrency());
  // TBB caps its workers at the hardware concurrency; an explicit --threads above that (e.g. 4
  // on a 2-core machine, for the determinism test) is honoured by raising the cap while we run.
  std::unique_ptr<tbb::global_control> parallelism;
  if (threads > tbb::info::default_concurrency()) {
    parallelism = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, size_t(threads));
  }
  tbb::task_arena arena(threads);
  const std::vector<glm::vec2> pattern = options.spp > 1 ? samplePattern(options.spp) : std::vector<glm::vec2>{};
  const int tilesX = (width + kTileSize - 1) / kTileSize;
  const int tilesY = (height + kTileSize - 1) / kTileSize;
  std::atomic<uint64_t> primaryRays{0}, shadowRays{0};
  const size_t lightCount = lights.size(), projectorCount = projectors.size();

  using Clock = std::chrono::steady_clock;
  const auto buildStart = Clock::now();
  std::unique_ptr<EmbreeScene> embree;
  arena.execute([&] { embree = std::make_unique<EmbreeScene>(scene); });
  // The picture, drawn in the tile loop from the values it writes (referencePicture's colours).
  const reference_detail::PictureShader shader(scene);
  const long pictureLight = shader.light() ? long(shader.light() - scene.lights.data()) : -1;
  uint8_t* pictureBytes = nullptr;
  if (picture) {
    picture->assign(size_t(width) * size_t(height) * 3, 0);
    pictureBytes = picture->data();
  }
  std::vector<float> objectIds(scene.objects.size());
  for (size_t g = 0; g < objectIds.size(); ++g) objectIds[g] = float(embree->geometry(unsigned(g)).object->id);
  const auto traceStart = Clock::now();
  const double traceCpuStart = processCpuSeconds();

  // Progress: tiles finish in any order; whichever thread crosses the next percent reports it
  // (under a mutex, so the callback runs on one thread at a time and the fractions only grow).
  const int tileCount = tilesX * tilesY;
  std::atomic<int> tilesDone{0};
  std::mutex progressMutex;
  int lastPercent = 0;
  auto tileFinished = [&] {
    if (!options.progress) return;
    const int done = ++tilesDone;
    const int percent = int(int64_t(done) * 100 / tileCount);
    if (percent <= lastPercent && done != tileCount) return;
    std::lock_guard<std::mutex> lock(progressMutex);
    if (percent > lastPercent) {
      lastPercent = percent;
      options.progress(double(done) / tileCount);
    }
  };

  arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<int>(0, tileCount), [&](const tbb::blocked_range<int>& range) {
      Tracer tracer(scene, *embree, objectIds.data());
      std::vector<float> tileBuffer(channelCount * kTilePixels);
      std::vector<float*> tileBase(channelCount);
      for (size_t c = 0; c < channelCount; ++c) tileBase[c] = tileBuffer.data() + c * kTilePixels;
      const Planes planes(tileBase.data(), channelCount, lightCount, projectorCount, all);
      // Camera rays need the surface point and normal only for shadow rays and the All channels.
      const bool surface = all || lightCount > 0 || projectorCount > 0 || pictureBytes;
      std::vector<float> pictureCoverage(projectorCount);
      std::vector<glm::vec3> pictureRgb(projectorCount);
      LaneHit center[kLanes], sample[kLanes];
      std::vector<float> centerVis(lightCount * kLanes), centerDist(lightCount * kLanes);
      std::vector<ProjectorSample> centerProj(projectorCount * kLanes);
      std::vector<double> visSum(lightCount * kLanes);
      std::vector<ProjectorSample> projSum(projectorCount * kLanes);
      float sampleVis[kLanes], sampleDist[kLanes];
      ProjectorSample sampleProj[kLanes];
      for (int tile = range.begin(); tile != range.end(); ++tile) {
        const int x0 = (tile % tilesX) * kTileSize, y0 = (tile / tilesX) * kTileSize;
        const int x1 = std::min(width, x0 + kTileSize), y1 = std::min(height, y0 + kTileSize);
        for (int by = y0; by < y1; by += kBlockHeight) {
          for (int bx = x0; bx < x1; bx += kBlockWidth) {
            int px[kLanes], py[kLanes];
            bool active[kLanes];
            for (int lane = 0; lane < kLanes; ++lane) {
              px[lane] = bx + lane % kBlockWidth;
              py[lane] = by + lane / kBlockWidth;
              active[lane] = px[lane] < x1 && py[lane] < y1;
            }
            tracer.tracePrimary(px, py, active, 0.5f, 0.5f, surface, center);
            for (size_t l = 0; l < lightCount; ++l)
              tracer.evalLight(lights[l], center, true, &centerVis[l * kLanes], &centerDist[l * kLanes]);
            for (size_t p = 0; p < projectorCount; ++p)
              tracer.evalProjector(projectors[p], center, &centerProj[p * kLanes]);

            int sameObject[kLanes] = {};
            if (!pattern.empty()) {
              std::fill(visSum.begin(), visSum.end(), 0.0);
              std::fill(projSum.begin(), projSum.end(), ProjectorSample{});
              bool sampleActive[kLanes];
              for (int lane = 0; lane < kLanes; ++lane) sampleActive[lane] = active[lane] && center[lane].hit;
              for (const glm::vec2& offset : pattern) {
                tracer.tracePrimary(px, py, sampleActive, offset.x, offset.y, surface, sample);
                // Only samples on the center's object count: the pixel's fractional visibility
                // is that of the surface its id and position describe.
                for (int lane = 0; lane < kLanes; ++lane) {
                  if (sample[lane].hit && sample[lane].geom != center[lane].geom) sample[lane].hit = false;
                  if (sample[lane].hit) ++sameObject[lane];
                }
                for (size_t l = 0; l < lightCount; ++l) {
                  tracer.evalLight(lights[l], sample, false, sampleVis, sampleDist);
                  for (int lane = 0; lane < kLanes; ++lane)
                    if (sample[lane].hit) visSum[l * kLanes + lane] += sampleVis[lane];
                }
                for (size_t p = 0; p < projectorCount; ++p) {
                  tracer.evalProjector(projectors[p], sample, sampleProj);
                  for (int lane = 0; lane < kLanes; ++lane) {
                    if (!sample[lane].hit) continue;
                    ProjectorSample& sum = projSum[p * kLanes + lane];
                    sum.coverage += sampleProj[lane].coverage;
                    sum.rgb += sampleProj[lane].rgb;
                  }
                }
              }
            }

            for (int lane = 0; lane < kLanes; ++lane) {
              if (!active[lane]) continue;
              const size_t pixel = size_t(py[lane] - y0) * kTileSize + size_t(px[lane] - x0);
              const LaneHit& h = center[lane];
              planes.hit[pixel] = h.hit ? 1.0f : 0.0f;
              planes.objectId[pixel] = h.hit ? h.objectId : 0.0f;
              if (all) {
                planes.primId[pixel] = h.hit ? float(h.prim) : 0.0f;
                for (int a = 0; a < 3; ++a) {
                  planes.p[a][pixel] = h.hit ? h.position[a] : 0.0f;
                  planes.n[a][pixel] = h.hit ? h.normal[a] : 0.0f;
                }
              }
              const int count = sameObject[lane];
              for (size_t l = 0; l < lightCount; ++l) {
                const size_t k = l * kLanes + lane;
                planes.vis[l][pixel] = count > 0 ? float(visSum[k] / count) : centerVis[k];
                planes.occluderDist[l][pixel] = centerDist[k];
              }
              for (size_t p = 0; p < projectorCount; ++p) {
                const size_t k = p * kLanes + lane;
                const ProjectorSample& c = centerProj[k];
                if (all) {
                  planes.u[p][pixel] = c.u;
                  planes.v[p][pixel] = c.v;
                }
                const ProjectorSample value =
                    count > 0 ? ProjectorSample{projSum[k].coverage / count, 0, 0, projSum[k].rgb / float(count)} : c;
                planes.coverage[p][pixel] = value.coverage;
                for (int ch = 0; ch < 3; ++ch) planes.rgb[ch][p][pixel] = value.rgb[ch];
                pictureCoverage[p] = value.coverage;
                pictureRgb[p] = value.rgb;
              }
              if (pictureBytes) {
                const glm::vec3 albedo =
                    h.hit ? shader.albedo(embree->geometry(h.geom).object, h.prim) : glm::vec3(0.8f);
                const float vis = pictureLight >= 0 ? planes.vis[size_t(pictureLight)][pixel] : 1.0f;
                shader.shade(h.hit, albedo, h.normal, h.position, vis, projectorCount, pictureCoverage.data(),
                             pictureRgb.data(),
                             pictureBytes + (size_t(py[lane]) * size_t(width) + size_t(px[lane])) * 3);
              }
            }
          }
        }
        for (size_t c = 0; c < channelCount; ++c) copyTileRows(tileBase[c], frameBase[c], width, x0, y0, x1, y1);
        embree->check("tracing a tile");
        tileFinished();
      }
      _mm_sfence();  // the streaming stores are visible before this thread's part is done
      primaryRays += tracer.primaryRays;
      shadowRays += tracer.shadowRays;
    });
  });
  const auto traceEnd = Clock::now();
  const double traceCpuEnd = processCpuSeconds();

  if (stats) {
    stats->primaryRays = primaryRays.load();
    stats->shadowRays = shadowRays.load();
    stats->buildSeconds = std::chrono::duration<double>(traceStart - buildStart).count();
    stats->traceSeconds = std::chrono::duration<double>(traceEnd - traceStart).count();
    stats->traceCpuSeconds = traceCpuEnd - traceCpuStart;
  }
  return frame;
}

}  // namespace shadowlab
