// renderReference: the Embree ground truth. See reference/README.md for the channels, the
// shadow-ray origin method and the sample pattern.
#include "shadowlab/reference/reference.h"

#include <algorithm>
#include <atomic>
#include <mutex>
#include <chrono>
#include <cmath>
#include <cstring>
#include <experimental/simd>
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
#include "shadowlab/scenes/number_text.h"

namespace shadowlab {
namespace {

using namespace reference_detail;
namespace stdx = std::experimental;

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

// The packet's lanes as one SIMD value each (std::experimental::simd, libstdc++'s Parallelism TS
// v2: 8 lanes, in as many native registers as the target has, two SSE registers on x86-64).
// Every operation is the IEEE operation of the scalar code in the scalar code's order (no FMA
// contraction: ISO C++ mode), so the lanes compute the same bits the scalar code did.
using FloatN = stdx::fixed_size_simd<float, kLanes>;
using DoubleN = stdx::fixed_size_simd<double, kLanes>;
using IntN = stdx::fixed_size_simd<int, kLanes>;
using MaskN = FloatN::mask_type;  // fixed_size masks convert into each other (IntN's, DoubleN's)
constexpr auto kAligned = stdx::vector_aligned;
constexpr size_t kSimdAlign = stdx::memory_alignment_v<FloatN>;
static_assert(stdx::memory_alignment_v<IntN> <= kSimdAlign && kSimdAlign <= alignof(RTCRay8),
              "HitPacket arrays and RTCRay8 fields take aligned SIMD loads and stores");

inline FloatN load(const float* p) { return FloatN(p, kAligned); }
inline IntN load(const int* p) { return IntN(p, kAligned); }
[[gnu::always_inline]] inline FloatN select(const MaskN& mask, const FloatN& yes, FloatN no) {
  stdx::where(mask, no) = yes;
  return no;
}

// The 8-ray packet of a query, one setup for the camera rays (tracePrimary), the hard lights'
// traceShadow and the sized lights' traceOccluded: the active lanes valid, each ray from `origin`
// along `dir` over [0, tfar] with its lane as id; an inactive lane's ray has length 0 along +y
// (never traced, and no zero direction for Embree to check).
[[gnu::always_inline]] inline void setRayPacket(RTCRay8& ray, int (&valid)[kLanes], const FloatN (&origin)[3],
                                                const FloatN (&dir)[3], const FloatN& tfar, const MaskN& active) {
  IntN validN = 0;
  stdx::where(active, validN) = -1;
  validN.copy_to(valid, kAligned);
  const FloatN zero = 0.0f;
  origin[0].copy_to(ray.org_x, kAligned);
  origin[1].copy_to(ray.org_y, kAligned);
  origin[2].copy_to(ray.org_z, kAligned);
  select(active, dir[0], zero).copy_to(ray.dir_x, kAligned);
  select(active, dir[1], FloatN(1.0f)).copy_to(ray.dir_y, kAligned);
  select(active, dir[2], zero).copy_to(ray.dir_z, kAligned);
  zero.copy_to(ray.tnear, kAligned);
  select(active, tfar, zero).copy_to(ray.tfar, kAligned);
  zero.copy_to(ray.time, kAligned);
  IntN(-1).copy_to(reinterpret_cast<int*>(ray.mask), kAligned);
  IntN([](int lane) { return lane; }).copy_to(reinterpret_cast<int*>(ray.id), kAligned);
  IntN(0).copy_to(reinterpret_cast<int*>(ray.flags), kAligned);
}

// The camera hits of one packet, one array per quantity across its 8 lanes (structure of arrays):
// the per-hit work is a few SIMD operations over the lanes instead of a branchy pass per lane.
// Lanes without a hit hold 0 in hitValue, objectId, geom and prim, and values of no meaning in the
// surface arrays (every reader selects hit lanes).
struct HitPacket {
  alignas(kSimdAlign) float hitValue[kLanes];  // 1 where the camera ray hit (the `hit` channel), 0 elsewhere
  alignas(kSimdAlign) float objectId[kLanes];  // Object::id of the geometry (the object_id channel); 0 where no hit
  alignas(kSimdAlign) int geom[kLanes];        // Embree geomID, primID; 0 where no hit
  alignas(kSimdAlign) int prim[kLanes];
  // With tracePrimary's `surface` only:
  alignas(kSimdAlign) float position[3][kLanes];  // world, on the triangle (barycentric interpolation in double)
  alignas(kSimdAlign) float normal[3][kLanes];    // unit geometric normal facing the camera
  alignas(kSimdAlign) float offset[kLanes];       // world distance shadow origins move along `normal`
  alignas(kSimdAlign) float origin[3][kLanes];    // shadow-ray origin: position + normal * offset

  bool hit(int lane) const { return hitValue[lane] != 0.0f; }
  MaskN hitMask() const { return load(hitValue) != 0.0f; }
  void drop(int lane) { hitValue[lane] = 0.0f; }  // a sample that does not count (another object than the center's)
  glm::vec3 positionAt(int lane) const { return {position[0][lane], position[1][lane], position[2][lane]}; }
  glm::vec3 normalAt(int lane) const { return {normal[0][lane], normal[1][lane], normal[2][lane]}; }
  glm::vec3 originAt(int lane) const { return {origin[0][lane], origin[1][lane], origin[2][lane]}; }
};

struct PreparedLight {
  const Light* light = nullptr;
  glm::vec3 toLight{0.0f};    // directional: unit, -direction
  double cosHalfCone = -1.0;  // spot: lit where cos(angle to the axis) >= this
  // A sized light (Light::sized(); reference/README.md, "Sized lights"): its stratified pattern.
  bool sized = false;
  uint32_t index = 0;                               // the light's index in the scene: part of each point's seed
  int samples = 0;                                  // light samples per point (ReferenceOptions::lightSamples)
  float stratumWidth = 1.0f, stratumHeight = 1.0f;  // 1 / strata across, 1 / strata down
  // Per light sample k, padded with zeros to whole packets: its stratum's column and row, and the
  // two keys its jitter hashes with the point's seed.
  std::vector<float> stratumX, stratumY;
  std::vector<uint32_t> keyX, keyY;
  // Directional: the cap around toLight, half angle angularDiameterDeg / 2.
  glm::vec3 tangent{0.0f}, bitangent{0.0f};
  float oneMinusCos = 0.0f;  // 1 - cos(half angle)
  double sinHalf = 0.0;      // sin(half angle)
};

// A sized light's result at one point: `lit` of `samples` light samples reach the light. A
// deterministic point (outside a spot's cone, inside the light's sphere, the whole cap below the
// horizon, no hit) has sampled = false and vis exactly 0 or 1.
struct SoftPoint {
  float vis = 0.0f;
  int lit = 0;
  bool sampled = false;
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

// Integer hash (lowbias32, Wellons' hash-prospector): the sized lights' jitter. Integer operations,
// so both compilations give the same bits.
using UintN = stdx::fixed_size_simd<uint32_t, kLanes>;
template <typename T>
inline T mixBits(T x) {
  x ^= x >> 16;
  x *= 0x7feb352du;
  x ^= x >> 15;
  x *= 0x846ca68bu;
  x ^= x >> 16;
  return x;
}

// A point's seed for a sized light's jitter: the pixel, the pixel sample (0 the center, s + 1 the
// spp pattern's sample s) and the light.
inline uint32_t pointSeed(int px, int py, uint32_t pixelSample, uint32_t light) {
  return mixBits(uint32_t(px) ^ mixBits(uint32_t(py) ^ mixBits(pixelSample ^ mixBits(light + 0x9e3779b9u))));
}

// (cos a, sin a) for a in [-pi/4, pi/4] by their Taylor polynomials (remainders below 3e-9, under
// float's rounding there), plain multiplies and adds: the same bits in both compilations.
[[gnu::always_inline]] inline void cosSinQuarter(const FloatN& a, FloatN& c, FloatN& s) {
  const FloatN a2 = a * a;
  s = a * (1.0f + a2 * (-1.0f / 6.0f + a2 * (1.0f / 120.0f + a2 * (-1.0f / 5040.0f + a2 * (1.0f / 362880.0f)))));
  c = 1.0f +
      a2 * (-0.5f + a2 * (1.0f / 24.0f + a2 * (-1.0f / 720.0f + a2 * (1.0f / 40320.0f + a2 * (-1.0f / 3628800.0f)))));
}

// An orthonormal basis around the unit axis (Duff et al. 2017, "Building an Orthonormal Basis,
// Revisited").
inline void basisAround(const glm::vec3& axis, glm::vec3& tangent, glm::vec3& bitangent) {
  const float sign = std::copysign(1.0f, axis.z);
  const float a = -1.0f / (sign + axis.z);
  const float b = axis.x * axis.y * a;
  tangent = glm::vec3(1.0f + sign * axis.x * axis.x * a, sign * b, -sign * axis.x);
  bitangent = glm::vec3(b, sign + axis.y * axis.y * a, -axis.y);
}

// A sized light's pattern: `samples` equal-area strata of the unit square, strataX across (the
// largest divisor of samples <= its square root) by samples / strataX down; sample k in column
// k % strataX, row k / strataX. Each point jitters each sample inside its stratum by a hash.
void prepareSized(PreparedLight& prepared, int samples) {
  const Light& light = *prepared.light;
  prepared.sized = true;
  prepared.samples = samples;
  int across = int(std::sqrt(double(samples)));
  while (samples % across != 0) --across;
  prepared.stratumWidth = 1.0f / float(across);
  prepared.stratumHeight = 1.0f / float(samples / across);
  const size_t padded = size_t(samples + kLanes - 1) / kLanes * kLanes;
  prepared.stratumX.assign(padded, 0.0f);
  prepared.stratumY.assign(padded, 0.0f);
  prepared.keyX.assign(padded, 0u);
  prepared.keyY.assign(padded, 0u);
  for (int k = 0; k < samples; ++k) {
    prepared.stratumX[size_t(k)] = float(k % across);
    prepared.stratumY[size_t(k)] = float(k / across);
    prepared.keyX[size_t(k)] = mixBits(uint32_t(2 * k) + 0x85ebca6bu);
    prepared.keyY[size_t(k)] = mixBits(uint32_t(2 * k + 1) + 0x85ebca6bu);
  }
  if (light.type == LightType::Directional) {
    basisAround(prepared.toLight, prepared.tangent, prepared.bitangent);
    const double half = double(light.angularDiameterDeg) * 0.5 * M_PI / 180.0;
    const double sinQuarter = std::sin(half * 0.5);
    prepared.oneMinusCos = float(2.0 * sinQuarter * sinQuarter);
    prepared.sinHalf = std::sin(half);
  }
}

// shadowOriginOffset, inlined into the trace.
inline float maxAbs(const glm::vec3& p) { return std::max(std::fabs(p.x), std::max(std::fabs(p.y), std::fabs(p.z))); }
inline float originOffset(const glm::vec3& position, const glm::vec3& p0, const glm::vec3& p1, const glm::vec3& p2) {
  return kOriginOffsetScale * std::max(std::max(maxAbs(position), maxAbs(p0)), std::max(maxAbs(p1), maxAbs(p2)));
}

// The per-packet methods that do SIMD work are [[gnu::flatten]]: libstdc++'s fixed_size simd is a
// tree of small functions, and GCC left some out of line (a call per multiply, per where()), which
// cost the shadow side about a fifth of its time.
class Tracer {
 public:
  Tracer(const Scene& scene, const EmbreeScene& embree, const float* objectIds,
         const TriangleData* const* triangleTables)
      : scene_(scene), embree_(embree), rays_(scene.camera), objectIds_(objectIds), triangleTables_(triangleTables) {}

  // Camera rays through (px + dx, py + dy) for the active lanes.
  // Without `surface` only hitValue, objectId, geom and prim are filled: no shadow ray or All
  // channel needs the rest.
  void tracePrimary(const int* px, const int* py, const bool* active, float dx, float dy, bool surface,
                    HitPacket& hits) {
    RTCRayHit8 rayHit;
    alignas(kSimdAlign) int valid[kLanes];
    const MaskN activeMask(active, stdx::element_aligned);
    FloatN origin[3] = {0.0f, 0.0f, 0.0f}, dir[3] = {0.0f, 0.0f, 0.0f};  // inactive lanes: zeros
    if (scene_.camera.orthographic()) {
      // Parallel rays, each from its point of the image plane (Camera::rayOrigin).
      for (int lane = 0; lane < kLanes; ++lane) {
        if (!active[lane]) continue;
        const glm::vec3 laneOrigin = rays_.origin(px[lane] + dx, py[lane] + dy);
        const glm::vec3 laneDir = rays_.direction(px[lane] + dx, py[lane] + dy);
        for (int a = 0; a < 3; ++a) {
          origin[a][lane] = laneOrigin[a];
          dir[a][lane] = laneDir[a];
        }
      }
    } else {
      // The packet's directions in one go (CameraRays::perspectiveDirection: direction's bits).
      const DoubleN x([&](auto lane) { return double(float(px[lane]) + dx); });
      const DoubleN y([&](auto lane) { return double(float(py[lane]) + dy); });
      DoubleN dir64[3];
      rays_.perspectiveDirection(x, y, dir64);
      for (int a = 0; a < 3; ++a) {
        dir[a] = stdx::static_simd_cast<FloatN>(dir64[a]);
        origin[a] = scene_.camera.position[a];
      }
    }
    setRayPacket(rayHit.ray, valid, origin, dir, FloatN(kInf), activeMask);
    IntN(int(RTC_INVALID_GEOMETRY_ID)).copy_to(reinterpret_cast<int*>(rayHit.hit.geomID), kAligned);
    IntN(int(RTC_INVALID_GEOMETRY_ID)).copy_to(reinterpret_cast<int*>(rayHit.hit.primID), kAligned);
    primaryRays += unsigned(stdx::popcount(activeMask));
    TraceContext context(RayKind::Camera);
    rtcIntersect8(valid, embree_.handle(), &context.rtc, &rayHit);
    const IntN geom = load(reinterpret_cast<const int*>(rayHit.hit.geomID));
    const MaskN hit = load(valid) != 0 && geom != int(RTC_INVALID_GEOMETRY_ID);
    IntN zero = 0;
    select(hit, FloatN(1.0f), FloatN(0.0f)).copy_to(hits.hitValue, kAligned);
    IntN value = geom;
    stdx::where(!hit, value) = zero;
    value.copy_to(hits.geom, kAligned);
    value = load(reinterpret_cast<const int*>(rayHit.hit.primID));
    stdx::where(!hit, value) = zero;
    value.copy_to(hits.prim, kAligned);
    const FloatN objectId([&](auto lane) { return hit[lane] ? objectIds_[hits.geom[lane]] : 0.0f; });
    objectId.copy_to(hits.objectId, kAligned);
    if (surface) computeSurface(rayHit, hit, hits);
  }

  // Occlusion of the segments from each active lane's shadow origin along dir up to tfar. With
  // wantDistance the packet is one closest-hit query (rtcIntersect8): a lane is occluded where it
  // hits anything, and the hit's t gives the occluder distance, measured from the surface point
  // itself (|normal offset + t dir|), not from the offset origin. Without, an any-hit query
  // (rtcOccluded8). Both run the same triangle test and filter on the same segment, so they agree
  // on which lanes are occluded; lanes that reach the sky, usually most, cost a closest-hit query
  // what they cost an any-hit one. Returns the occluded lanes (none, untraced, where none is active).
  [[gnu::flatten]] MaskN traceShadow(const HitPacket& hits, const FloatN (&dir)[3], const FloatN& tfar,
                                     const MaskN& active, bool wantDistance, FloatN& distance) {
    const int count = stdx::popcount(active);
    if (count == 0) return MaskN(false);
    shadowRays += unsigned(count);
    RTCRayHit8 rayHit;
    RTCRay8& ray = rayHit.ray;
    alignas(kSimdAlign) int valid[kLanes];
    const FloatN zero = 0.0f;
    const FloatN origin[3] = {select(active, load(hits.origin[0]), zero), select(active, load(hits.origin[1]), zero),
                              select(active, load(hits.origin[2]), zero)};
    setRayPacket(ray, valid, origin, dir, tfar, active);
    if (!wantDistance) {
      rtcOccluded8(valid, embree_.handle(), &shadowContext_.rtc, &ray);
      // Embree marks an occluded ray by setting tfar to -inf.
      return active && load(ray.tfar) < 0.0f;
    }
    IntN(int(RTC_INVALID_GEOMETRY_ID)).copy_to(reinterpret_cast<int*>(rayHit.hit.geomID), kAligned);
    rtcIntersect8(valid, embree_.handle(), &shadowContext_.rtc, &rayHit);
    const MaskN occluded =
        active && MaskN(load(reinterpret_cast<const int*>(rayHit.hit.geomID)) != int(RTC_INVALID_GEOMETRY_ID));
    const FloatN t = select(occluded, load(ray.tfar), zero);
    const FloatN offset = load(hits.offset);
    FloatN v[3];
    for (int a = 0; a < 3; ++a) v[a] = load(hits.normal[a]) * offset + dir[a] * t;
    distance = stdx::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);  // glm::length's order
    return occluded;
  }

  // Visibility (exactly 0 or 1) of one light at each hit lane; distance to the nearest occluder
  // (-1 where none; 0 where the visible side of the surface faces away from the light).
  [[gnu::flatten]] void evalLight(const PreparedLight& prepared, const HitPacket& hits, bool wantDistance, float* vis,
                                  float* distance) {
    const Light& light = *prepared.light;
    FloatN dir[3], toLight[3], tfar;
    MaskN reached = hits.hitMask();  // the light reaches the point: inside a spot's cone, a segment > 0
    if (light.type == LightType::Directional) {
      for (int a = 0; a < 3; ++a) toLight[a] = dir[a] = prepared.toLight[a];
      tfar = kInf;
    } else {
      FloatN segment[3];
      for (int a = 0; a < 3; ++a) {
        toLight[a] = light.position[a] - load(hits.position[a]);
        segment[a] = light.position[a] - load(hits.origin[a]);
      }
      tfar = stdx::sqrt(segment[0] * segment[0] + segment[1] * segment[1] + segment[2] * segment[2]);
      for (int a = 0; a < 3; ++a) dir[a] = segment[a] / tfar;
      reached = reached && tfar > 0.0f;
      if (light.type == LightType::Spot) {
        // Outside the cone (tested in double): unlit, no occluder.
        DoubleN fromLight[3];
        for (int a = 0; a < 3; ++a)
          fromLight[a] = stdx::static_simd_cast<DoubleN>(load(hits.position[a])) - double(light.position[a]);
        const DoubleN length =
            stdx::sqrt(fromLight[0] * fromLight[0] + fromLight[1] * fromLight[1] + fromLight[2] * fromLight[2]);
        const DoubleN along = fromLight[0] * double(light.direction.x) + fromLight[1] * double(light.direction.y) +
                              fromLight[2] * double(light.direction.z);
        DoubleN cosAngle = -1.0;
        stdx::where(length > 0.0, cosAngle) = along / length;
        reached = reached && !MaskN(cosAngle < prepared.cosHalfCone);
      }
    }
    // The camera sees the side `normal` points to; light arriving from the other side lights only
    // the hidden side. The surface itself is the occluder there, at distance 0.
    const FloatN facing =
        load(hits.normal[0]) * toLight[0] + load(hits.normal[1]) * toLight[1] + load(hits.normal[2]) * toLight[2];
    const MaskN active = reached && facing > 0.0f;
    FloatN occluderDistance = 0.0f;
    const MaskN occluded = traceShadow(hits, dir, tfar, active, wantDistance, occluderDistance);
    select(active && !occluded, FloatN(1.0f), FloatN(0.0f)).copy_to(vis, stdx::element_aligned);
    FloatN value = select(reached && !active, FloatN(0.0f), FloatN(-1.0f));
    if (wantDistance) stdx::where(occluded, value) = occluderDistance;
    value.copy_to(distance, stdx::element_aligned);
  }

  // A sized light at each lane in `lanes` (hit lanes; the others get SoftPoint{}): the visible
  // fraction of the light's cap as seen from the lane's shadow origin, by prepared.samples
  // stratified directions, uniform in solid angle, in rtcOccluded8 packets of 8 samples of one
  // point. A sample whose direction is below the surface's horizon (N . dir <= 0) does not reach
  // the light; a sphere light's ray ends where it meets the sphere.
  void evalSizedLight(const PreparedLight& prepared, const HitPacket& hits, const bool* lanes, const int* px,
                      const int* py, uint32_t pixelSample, SoftPoint* out) {
    const Light& light = *prepared.light;
    for (int lane = 0; lane < kLanes; ++lane) {
      out[lane] = SoftPoint{};
      if (!lanes[lane] || !hits.hit(lane)) continue;
      const glm::vec3 position = hits.positionAt(lane), origin = hits.originAt(lane);
      glm::vec3 axis = prepared.toLight, tangent = prepared.tangent, bitangent = prepared.bitangent;
      float oneMinusCos = prepared.oneMinusCos;
      double sinHalf = prepared.sinHalf;
      if (light.type != LightType::Directional) {
        if (light.type == LightType::Spot) {
          // The cone test of the hard light (evalLight), on the direction to the light's center.
          double fromLight[3];
          for (int a = 0; a < 3; ++a) fromLight[a] = double(position[a]) - double(light.position[a]);
          const double length =
              std::sqrt(fromLight[0] * fromLight[0] + fromLight[1] * fromLight[1] + fromLight[2] * fromLight[2]);
          const double along = fromLight[0] * double(light.direction.x) + fromLight[1] * double(light.direction.y) +
                               fromLight[2] * double(light.direction.z);
          const double cosAngle = length > 0.0 ? along / length : -1.0;
          if (cosAngle < prepared.cosHalfCone) continue;  // outside the cone: 0
        }
        const glm::dvec3 toCenter = glm::dvec3(light.position) - glm::dvec3(origin);
        const double distance2 = glm::dot(toCenter, toCenter);
        const double radius = double(light.radius);
        if (distance2 <= radius * radius) {  // inside or on the light's sphere: fully lit
          out[lane].vis = 1.0f;
          continue;
        }
        const double distance = std::sqrt(distance2);
        sinHalf = radius / distance;
        const double sin2 = sinHalf * sinHalf;
        oneMinusCos = float(sin2 / (1.0 + std::sqrt(1.0 - sin2)));  // 1 - sqrt(1 - r^2 / d^2), without cancellation
        axis = glm::vec3(toCenter / distance);
        basisAround(axis, tangent, bitangent);
      }
      const glm::vec3 normal = hits.normalAt(lane);
      // The whole cap below the horizon: 0, no ray.
      if (glm::dot(glm::dvec3(normal), glm::dvec3(axis)) <= -sinHalf) continue;
      out[lane].sampled = true;
      const UintN seed = pointSeed(px[lane], py[lane], pixelSample, prepared.index);
      const FloatN center[3] = {light.position.x - origin.x, light.position.y - origin.y, light.position.z - origin.z};
      const float radius2 = light.radius * light.radius;
      int lit = 0;
      for (int k = 0; k < prepared.samples; k += kLanes) {
        FloatN dir[3];
        sampleCap(prepared, k, seed, tangent, bitangent, axis, oneMinusCos, dir);
        const MaskN valid = MaskN(IntN([](int i) { return i; }) < prepared.samples - k) &&
                            normal.x * dir[0] + normal.y * dir[1] + normal.z * dir[2] > 0.0f;
        FloatN tfar = kInf;
        if (light.type != LightType::Directional) {
          // The exact ray/sphere distance: along - sqrt(r^2 - (perpendicular distance)^2).
          const FloatN along = center[0] * dir[0] + center[1] * dir[1] + center[2] * dir[2];
          const FloatN cx = center[1] * dir[2] - center[2] * dir[1];
          const FloatN cy = center[2] * dir[0] - center[0] * dir[2];
          const FloatN cz = center[0] * dir[1] - center[1] * dir[0];
          tfar = along - stdx::sqrt(stdx::max(FloatN(0.0f), radius2 - (cx * cx + cy * cy + cz * cz)));
        }
        lit += stdx::popcount(valid && !traceOccluded(origin, dir, tfar, valid));
      }
      out[lane].lit = lit;
      out[lane].vis = float(double(lit) / double(prepared.samples));
    }
  }

  void evalProjector(const PreparedProjector& prepared, const HitPacket& hits, ProjectorSample* out) {
    const Projector& projector = *prepared.projector;
    alignas(kSimdAlign) float dir[3][kLanes] = {}, tfar[kLanes] = {};
    alignas(kSimdAlign) int active[kLanes] = {};
    for (int lane = 0; lane < kLanes; ++lane) {
      out[lane] = ProjectorSample{};
      if (!hits.hit(lane)) continue;
      const glm::vec3 position = hits.positionAt(lane);
      const glm::dvec4 clip = prepared.texFromWorld * glm::dvec4(glm::dvec3(position), 1.0);
      const double w = clip.w;
      const double u = w != 0.0 ? clip.x / w : 0.0;
      const double v = w != 0.0 ? clip.y / w : 0.0;
      const double depth = w != 0.0 ? clip.z / w : 0.0;
      out[lane].u = float(u);
      out[lane].v = float(v);
      const bool inside = w > 0.0 && u >= 0.0 && u <= 1.0 && v >= 0.0 && v <= 1.0 && depth >= 0.0 && depth <= 1.0;
      if (!inside) continue;
      // Lights the hidden side.
      if (!(glm::dot(hits.normalAt(lane), projector.position - position) > 0.0f)) continue;
      const glm::vec3 segment = projector.position - hits.originAt(lane);
      tfar[lane] = glm::length(segment);
      if (!(tfar[lane] > 0.0f)) continue;
      for (int a = 0; a < 3; ++a) dir[a][lane] = segment[a] / tfar[lane];
      active[lane] = -1;
    }
    const FloatN dirN[3] = {load(dir[0]), load(dir[1]), load(dir[2])};
    const MaskN activeN = load(active) != 0;
    FloatN unusedDistance = 0.0f;
    const MaskN occluded = traceShadow(hits, dirN, load(tfar), activeN, false, unusedDistance);
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
  // The hit point, the camera-facing normal and the shadow origin of every lane at once: each
  // lane's triangle is gathered from its table into registers (the zero triangle where no hit),
  // then each quantity is a few SIMD operations, the scalar rule's operations in its order.
  [[gnu::flatten]] void computeSurface(const RTCRayHit8& rayHit, const MaskN& hit, HitPacket& hits) const {
    // Lanes without a hit take the first hit lane's triangle: their values are never read, and a
    // packet whose hits all lie on one triangle (most of a ground plane's) then broadcasts it
    // instead of gathering it lane by lane.
    static const TriangleData kNoTriangle{};
    const TriangleData* first = &kNoTriangle;
    for (int lane = kLanes - 1; lane >= 0; --lane)
      if (hit[lane]) first = &triangleTables_[hits.geom[lane]][hits.prim[lane]];
    const TriangleData* triangle[kLanes];
    bool one = true;
    for (int lane = 0; lane < kLanes; ++lane) {
      triangle[lane] = hit[lane] ? &triangleTables_[hits.geom[lane]][hits.prim[lane]] : first;
      one = one && triangle[lane] == first;
    }
    auto gather = [&](auto field) {
      return one ? FloatN(field(*first)) : FloatN([&](auto lane) { return field(*triangle[lane]); });
    };
    // (1 - u - v) p0 + u p1 + v p2, in double, with Embree's barycentrics (undefined where no hit).
    const FloatN zero = 0.0f;
    const DoubleN u = stdx::static_simd_cast<DoubleN>(select(hit, load(rayHit.hit.u), zero));
    const DoubleN v = stdx::static_simd_cast<DoubleN>(select(hit, load(rayHit.hit.v), zero));
    const DoubleN w = 1.0 - u - v;
    FloatN position[3], n[3];
    for (int a = 0; a < 3; ++a) {
      const DoubleN p0 = stdx::static_simd_cast<DoubleN>(gather([a](const TriangleData& t) { return t.p[0][a]; }));
      const DoubleN p1 = stdx::static_simd_cast<DoubleN>(gather([a](const TriangleData& t) { return t.p[1][a]; }));
      const DoubleN p2 = stdx::static_simd_cast<DoubleN>(gather([a](const TriangleData& t) { return t.p[2][a]; }));
      position[a] = stdx::static_simd_cast<FloatN>(w * p0 + u * p1 + v * p2);
      n[a] = gather([a](const TriangleData& t) { return t.normal[a]; });
    }
    // A degenerate triangle (zero normal in its table) takes Embree's geometric normal: it never
    // happens on a bundled scene.
    const MaskN degenerate = hit && n[0] == 0.0f && n[1] == 0.0f && n[2] == 0.0f;
    if (stdx::any_of(degenerate)) {
      for (int lane = 0; lane < kLanes; ++lane) {
        if (!degenerate[lane]) continue;
        const glm::vec3 ng =
            glm::normalize(glm::vec3(rayHit.hit.Ng_x[lane], rayHit.hit.Ng_y[lane], rayHit.hit.Ng_z[lane]));
        for (int a = 0; a < 3; ++a) n[a][lane] = ng[a];
      }
    }
    // Facing the camera: flipped where it points along the camera ray (glm::dot's order).
    const FloatN along = n[0] * load(rayHit.ray.dir_x) + n[1] * load(rayHit.ray.dir_y) + n[2] * load(rayHit.ray.dir_z);
    const MaskN flip = along > 0.0f;
    for (int a = 0; a < 3; ++a) stdx::where(flip, n[a]) = -n[a];
    // shadowOriginOffset, with the vertices' part taken from the triangle's table (std::max's
    // operand order does not matter here: no NaN, and fabs leaves no -0).
    const FloatN pointMax =
        stdx::max(stdx::abs(position[0]), stdx::max(stdx::abs(position[1]), stdx::abs(position[2])));
    const FloatN offset =
        kOriginOffsetScale * stdx::max(pointMax, gather([](const TriangleData& t) { return t.maxAbs; }));
    offset.copy_to(hits.offset, kAligned);
    for (int a = 0; a < 3; ++a) {
      position[a].copy_to(hits.position[a], kAligned);
      n[a].copy_to(hits.normal[a], kAligned);
      (position[a] + n[a] * offset).copy_to(hits.origin[a], kAligned);
    }
  }

  // Light samples k..k+7 of a sized light's cap around `axis`: each sample's stratum of the unit
  // square, jittered by the hash of the point's seed and the sample's key, then Shirley and Chiu's
  // concentric map to the unit disc and the disc to the cap (1 - cos(theta) = r^2 (1 - cos(theta_max))):
  // both maps preserve area, so the directions are uniform in solid angle, one per equal-solid-angle
  // stratum.
  [[gnu::flatten]] static void sampleCap(const PreparedLight& prepared, int k, const UintN& seed,
                                         const glm::vec3& tangent, const glm::vec3& bitangent, const glm::vec3& axis,
                                         float oneMinusCos, FloatN (&dir)[3]) {
    const UintN hx = mixBits(seed ^ UintN(&prepared.keyX[size_t(k)], stdx::element_aligned));
    const UintN hy = mixBits(seed ^ UintN(&prepared.keyY[size_t(k)], stdx::element_aligned));
    constexpr float kUnit = 1.0f / 16777216.0f;  // 24 bits to [0, 1)
    const FloatN jx = stdx::static_simd_cast<FloatN>(stdx::static_simd_cast<IntN>(hx >> 8)) * kUnit;
    const FloatN jy = stdx::static_simd_cast<FloatN>(stdx::static_simd_cast<IntN>(hy >> 8)) * kUnit;
    const FloatN u = (FloatN(&prepared.stratumX[size_t(k)], stdx::element_aligned) + jx) * prepared.stratumWidth;
    const FloatN v = (FloatN(&prepared.stratumY[size_t(k)], stdx::element_aligned) + jy) * prepared.stratumHeight;
    const FloatN sx = 2.0f * u - 1.0f, sy = 2.0f * v - 1.0f;
    const MaskN wide = stdx::abs(sx) > stdx::abs(sy);
    const FloatN r = select(wide, sx, sy);
    const FloatN other = select(wide, sy, sx);
    const FloatN ratio = other / select(r == 0.0f, FloatN(1.0f), r);
    FloatN c, s;
    cosSinQuarter(ratio * float(M_PI / 4.0), c, s);
    // (r cos(phi), r sin(phi)) / |r|: phi = pi/4 * sy/sx where |sx| > |sy|, else pi/2 - pi/4 * sx/sy.
    const FloatN sign = select(r < 0.0f, FloatN(-1.0f), FloatN(1.0f));
    const FloatN ex = sign * select(wide, c, s), ey = sign * select(wide, s, c);
    const FloatN h = r * r * oneMinusCos;
    const FloatN cosTheta = 1.0f - h;
    const FloatN sinTheta = stdx::sqrt(h * (2.0f - h));
    const FloatN lx = sinTheta * ex, ly = sinTheta * ey;
    for (int a = 0; a < 3; ++a) dir[a] = tangent[a] * lx + bitangent[a] * ly + axis[a] * cosTheta;
  }

  // Occlusion (any hit) of 8 rays from one origin, the valid lanes; Embree marks an occluded ray by
  // setting tfar to -inf.
  [[gnu::flatten]] MaskN traceOccluded(const glm::vec3& origin, const FloatN (&dir)[3], const FloatN& tfar,
                                       const MaskN& valid) {
    const int count = stdx::popcount(valid);
    if (count == 0) return MaskN(false);
    shadowRays += unsigned(count);
    RTCRay8 ray;
    alignas(kSimdAlign) int validLanes[kLanes];
    const FloatN packetOrigin[3] = {FloatN(origin.x), FloatN(origin.y), FloatN(origin.z)};
    setRayPacket(ray, validLanes, packetOrigin, dir, tfar, valid);
    rtcOccluded8(validLanes, embree_.handle(), &shadowContext_.rtc, &ray);
    return valid && load(ray.tfar) < 0.0f;
  }

  TraceContext shadowContext_{RayKind::Shadow};
  const Scene& scene_;
  const EmbreeScene& embree_;
  const CameraRays rays_;                      // Camera::rayDirection and rayOrigin, bit for bit
  const float* objectIds_;                     // per geometry id: Object::id as a float
  const TriangleData* const* triangleTables_;  // per geometry id: its triangles (EmbreeScene::geometry)
};

// The output channels, one pointer each, in the frame's channel order (referenceChannelNames):
// base[c] is channel c's first value. Without the All set, primId, p, n, u and v are null.
struct Planes {
  float* hit = nullptr;
  float* objectId = nullptr;
  float* primId = nullptr;
  float* p[3] = {};
  float* n[3] = {};
  std::vector<float*> vis, occluderDist, visSigma;  // visSigma: null for a hard light
  std::vector<float*> coverage, u, v, rgb[3];

  Planes(float* const* base, size_t channelCount, const std::vector<PreparedLight>& lights, size_t projectorCount,
         bool all)
      : vis(lights.size()),
        occluderDist(lights.size()),
        visSigma(lights.size()),
        coverage(projectorCount),
        u(projectorCount),
        v(projectorCount) {
    size_t index = 0;
    hit = base[index++];
    objectId = base[index++];
    if (all) {
      primId = base[index++];
      for (int a = 0; a < 3; ++a) p[a] = base[index++];
      for (int a = 0; a < 3; ++a) n[a] = base[index++];
    }
    for (size_t l = 0; l < lights.size(); ++l) {
      vis[l] = base[index++];
      occluderDist[l] = base[index++];
      if (lights[l].sized) visSigma[l] = base[index++];
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

// A packet's values (lanes in the block's row-major order) into a tile plane at the block's first
// pixel: `rows` rows of `rowLanes` values (all of a 4 x 2 block but at a tile's ragged edge).
inline void putBlock(float* tilePlane, const float* values, int rowLanes, int rows) {
  for (int r = 0; r < rows; ++r) {
    float* dst = tilePlane + r * kTileSize;
    const float* src = values + r * kBlockWidth;
    if (rowLanes == kBlockWidth) {
      std::memcpy(dst, src, kBlockWidth * sizeof(float));
    } else {
      for (int i = 0; i < rowLanes; ++i) dst[i] = src[i];
    }
  }
}

// The All set's prim_id, P and N of a packet (out of line: inlined, it slowed the camera rays'
// loop of the Compare set, which does not run it, by several percent).
[[gnu::noinline]] void putSurface(const HitPacket& hits, const Planes& planes, size_t blockPixel, int rowLanes,
                                  int rows) {
  alignas(kSimdAlign) float values[kLanes];
  const MaskN hit = hits.hitMask();
  stdx::static_simd_cast<FloatN>(load(hits.prim)).copy_to(values, kAligned);
  putBlock(planes.primId + blockPixel, values, rowLanes, rows);
  for (int a = 0; a < 3; ++a) {
    select(hit, load(hits.position[a]), FloatN(0.0f)).copy_to(values, kAligned);
    putBlock(planes.p[a] + blockPixel, values, rowLanes, rows);
    select(hit, load(hits.normal[a]), FloatN(0.0f)).copy_to(values, kAligned);
    putBlock(planes.n[a] + blockPixel, values, rowLanes, rows);
  }
}

// A sized light's vis and vis_sigma of a packet (reference/README.md, "Sized lights"). vis: the
// center's SoftPoint at spp 1 (centerOnly), else the mean over the samples on the center's object,
// or the center's own where none is. vis_sigma: the standard error's binomial bound over the points
// that were sampled, sqrt(p (1 - p) / n) per point with p = (lit + 1/2) / (n + 1), combined over
// the pixel's points. occluder_dist (the hard ray's, toward the center) becomes -1 where the
// center's origin is inside the light's sphere (fully lit).
template <typename Put>
void putSizedLight(Tracer& tracer, const PreparedLight& prepared, const HitPacket& center, const int* px, const int* py,
                   bool centerOnly, const int* sameObject, SoftPoint* centerSoft, const double* visSum,
                   const int* sampledPoints, const int* litSamples, float* distance, const Put& put, float* visPlane,
                   float* sigmaPlane) {
  const Light& light = *prepared.light;
  if (!centerOnly) {
    bool lanes[kLanes];
    bool any = false;
    for (int lane = 0; lane < kLanes; ++lane) {
      lanes[lane] = center.hit(lane) && sameObject[lane] == 0;
      any = any || lanes[lane];
    }
    if (any) {
      tracer.evalSizedLight(prepared, center, lanes, px, py, 0, centerSoft);
    } else {
      std::fill(centerSoft, centerSoft + kLanes, SoftPoint{});
    }
  }
  const double samples = double(prepared.samples);
  alignas(kSimdAlign) float vis[kLanes], sigma[kLanes];
  for (int lane = 0; lane < kLanes; ++lane) {
    const bool own = centerOnly || sameObject[lane] == 0;
    const double points = own ? 1.0 : double(sameObject[lane]);
    const double sampled = own ? (centerSoft[lane].sampled ? 1.0 : 0.0) : double(sampledPoints[lane]);
    const double lit = own ? double(centerSoft[lane].lit) : double(litSamples[lane]);
    vis[lane] = own ? centerSoft[lane].vis : float(visSum[lane] / points);
    sigma[lane] = 0.0f;
    if (sampled > 0.0) {
      const double n = samples * sampled;
      const double p = (lit + 0.5) / (n + 1.0);
      sigma[lane] = float(sampled / points * std::sqrt(p * (1.0 - p) / n));
    }
    if (light.type != LightType::Directional && center.hit(lane)) {
      const glm::dvec3 toCenter = glm::dvec3(light.position) - glm::dvec3(center.originAt(lane));
      if (glm::dot(toCenter, toCenter) <= double(light.radius) * double(light.radius)) distance[lane] = -1.0f;
    }
  }
  put(visPlane, vis);
  put(sigmaPlane, sigma);
}

// A tile's values are written to a small buffer first (kTileSize x kTileSize floats per channel,
// in cache), then copied to the frame's planes row by row. A full row of a 16-pixel tile is 64
// bytes, a cache line: where the plane row is 16-byte aligned it is copied with streaming stores,
// which write whole lines without first reading them from memory (half the memory traffic of
// writing each pixel into the planes directly, which made those writes most of the reference's
// cost beyond Embree's). The caller fences (_mm_sfence) before the frame is read.
// A row whose every value has the bits `fill`, the value the plane was filled with when the frame
// was made (renderReference, frame.add), is not written at all: the plane holds those bits already.
// Most rows of occluder_dist (-1: lit, or no hit) and of a background's hit, object_id and vis (0)
// are such rows; skipping them saves their memory traffic, the largest part of the planes' cost.
void copyTileRows(const float* tile, float* plane, int width, int x0, int y0, int x1, int y1, uint32_t fill) {
  const int count = x1 - x0;
  for (int y = y0; y < y1; ++y) {
    const float* src = tile + (y - y0) * kTileSize;
    float* dst = plane + size_t(y) * size_t(width) + size_t(x0);
    uint32_t differ = 0;
    for (int x = 0; x < count; ++x) {
      uint32_t bits;
      std::memcpy(&bits, src + x, sizeof bits);
      differ |= bits ^ fill;
    }
    if (differ == 0) continue;
    if (count % 4 == 0 && reinterpret_cast<uintptr_t>(dst) % 16 == 0) {
      for (int x = 0; x < count; x += 4) _mm_stream_ps(dst + x, _mm_loadu_ps(src + x));
    } else {
      std::memcpy(dst, src, size_t(count) * sizeof(float));
    }
  }
}

}  // namespace

// The trace is compiled twice where CMake finds x86-64 (SHADOWLAB_REFERENCE_HAS_AVX2): here for the
// baseline, and by reference_avx2.cpp (SHADOWLAB_REFERENCE_AVX2_TU) for AVX2, where it defines only
// the trace, as renderReferenceAvx2. renderReference runs that one where the CPU has AVX2
// (ReferenceOptions::simd); both give the same bits.
#if defined(SHADOWLAB_REFERENCE_HAS_AVX2) || defined(SHADOWLAB_REFERENCE_AVX2_TU)
namespace reference_detail {
Frame renderReferenceAvx2(const Scene& scene, const ReferenceOptions& options, ReferenceStats* stats,
                          std::vector<uint8_t>* picture);
}
#endif
#ifdef SHADOWLAB_REFERENCE_AVX2_TU
#define SHADOWLAB_RENDER_REFERENCE reference_detail::renderReferenceAvx2
#else
#define SHADOWLAB_RENDER_REFERENCE renderReference

bool referenceHasAvx2() {
#ifdef SHADOWLAB_REFERENCE_HAS_AVX2
  static const bool has = __builtin_cpu_supports("avx2");
  return has;
#else
  return false;
#endif
}
#endif

// Process CPU seconds so far (user + system, all threads).
static double processCpuSeconds() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return double(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
         1e-6 * double(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}

#ifndef SHADOWLAB_REFERENCE_AVX2_TU
void checkSpp(long long spp, const std::string& file, const std::string& place) {
  if (spp < kMinSpp || spp > kMaxSpp)
    throw InputError(formatError(file, place,
                                 "got " + std::to_string(spp) + "; expected an integer " + std::to_string(kMinSpp) +
                                     ".." + std::to_string(kMaxSpp) + " (reference samples per pixel)"));
}

void checkLightSamples(long long samples, const std::string& file, const std::string& place) {
  if (samples < kMinLightSamples || samples > kMaxLightSamples)
    throw InputError(formatError(file, place,
                                 "got " + std::to_string(samples) + "; expected an integer " +
                                     std::to_string(kMinLightSamples) + ".." + std::to_string(kMaxLightSamples) +
                                     " (light samples per pixel sample of a sized light)"));
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
    if (light.sized()) names.push_back("light." + light.name + ".vis_sigma");
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
#endif

Frame SHADOWLAB_RENDER_REFERENCE(const Scene& scene, const ReferenceOptions& options, ReferenceStats* stats,
                                 std::vector<uint8_t>* picture) {
#ifndef SHADOWLAB_REFERENCE_AVX2_TU
  if (options.simd == ReferenceSimd::Avx2 && !referenceHasAvx2())
    throw DriverError("reference: error: the AVX2 trace was asked for; this build or CPU has none");
#ifdef SHADOWLAB_REFERENCE_HAS_AVX2
  if (options.simd != ReferenceSimd::Baseline && referenceHasAvx2())
    return reference_detail::renderReferenceAvx2(scene, options, stats, picture);
#endif
#endif
  checkSpp(options.spp, "reference");
  checkLightSamples(options.lightSamples, "reference");
  if (options.threads < 0) {
    throw InputError("reference: error: threads " + std::to_string(options.threads) + "; expected 0 (all) or more");
  }
  if (!(std::fabs(options.pixelOffset.x) <= 1.0f && std::fabs(options.pixelOffset.y) <= 1.0f)) {
    throw InputError("reference: error: pixel offset (" + numberText(options.pixelOffset.x) + ", " +
                     numberText(options.pixelOffset.y) + "); expected each component in [-1, 1]");
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
    prepared.index = uint32_t(lights.size());
    if (light.sized()) prepareSized(prepared, options.lightSamples);
    lights.push_back(prepared);
  }
  std::vector<PreparedProjector> projectors;
  for (const Projector& projector : scene.projectors)
    projectors.push_back({&projector, glm::dmat4(projector.texFromWorld())});
  // The channels in Planes' order (frame.add may move planes while channels are added: taken now).
  const size_t channelCount = frame.data.size();
  std::vector<float*> frameBase(channelCount);
  std::vector<uint32_t> frameFill(channelCount);  // each plane's fill value's bits (copyTileRows)
  for (size_t c = 0; c < channelCount; ++c) {
    frameBase[c] = frame.data[c].data();
    std::memcpy(&frameFill[c], frameBase[c], sizeof(uint32_t));  // frame.add filled every value with it
  }

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
  if (std::any_of(scene.lights.begin(), scene.lights.end(), [](const Light& light) { return light.sized(); }))
    frame.meta["light_samples"] = options.lightSamples;

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
  std::vector<const TriangleData*> triangleTables(scene.objects.size());
  for (size_t g = 0; g < objectIds.size(); ++g) {
    objectIds[g] = float(embree->geometry(unsigned(g)).object->id);
    triangleTables[g] = embree->geometry(unsigned(g)).triangles.data();
  }
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

  const glm::vec2 shift = options.pixelOffset;
  arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<int>(0, tileCount), [&](const tbb::blocked_range<int>& range) {
      Tracer tracer(scene, *embree, objectIds.data(), triangleTables.data());
      std::vector<float> tileBuffer(channelCount * kTilePixels);
      std::vector<float*> tileBase(channelCount);
      for (size_t c = 0; c < channelCount; ++c) tileBase[c] = tileBuffer.data() + c * kTilePixels;
      const Planes planes(tileBase.data(), channelCount, lights, projectorCount, all);
      // Camera rays need the surface point and normal only for shadow rays and the All channels.
      const bool surface = all || lightCount > 0 || projectorCount > 0 || pictureBytes;
      std::vector<float> pictureCoverage(projectorCount);
      std::vector<glm::vec3> pictureRgb(projectorCount);
      HitPacket center, sample;
      std::vector<float> centerVis(lightCount * kLanes), centerDist(lightCount * kLanes);
      std::vector<ProjectorSample> centerProj(projectorCount * kLanes);
      std::vector<double> visSum(lightCount * kLanes);
      // Sized lights, per light and lane: the points sampled and their light samples that reach the
      // light (vis_sigma), the center's own result.
      std::vector<int> sampledPoints(lightCount * kLanes), litSamples(lightCount * kLanes);
      std::vector<SoftPoint> centerSoft(lightCount * kLanes);
      SoftPoint soft[kLanes];
      const bool everyLane[kLanes] = {true, true, true, true, true, true, true, true};
      std::vector<ProjectorSample> projSum(projectorCount * kLanes);
      alignas(kSimdAlign) float sampleVis[kLanes], sampleDist[kLanes];
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
            tracer.tracePrimary(px, py, active, 0.5f + shift.x, 0.5f + shift.y, surface, center);
            for (size_t l = 0; l < lightCount; ++l) {
              tracer.evalLight(lights[l], center, true, &centerVis[l * kLanes], &centerDist[l * kLanes]);
              if (!lights[l].sized) continue;
              // A sized light: occluder_dist is the hard ray's, toward the light's center; vis
              // comes from the light samples (the center's own, at spp 1).
              if (pattern.empty())
                tracer.evalSizedLight(lights[l], center, everyLane, px, py, 0, &centerSoft[l * kLanes]);
            }
            for (size_t p = 0; p < projectorCount; ++p)
              tracer.evalProjector(projectors[p], center, &centerProj[p * kLanes]);

            int sameObject[kLanes] = {};
            if (!pattern.empty()) {
              std::fill(visSum.begin(), visSum.end(), 0.0);
              std::fill(sampledPoints.begin(), sampledPoints.end(), 0);
              std::fill(litSamples.begin(), litSamples.end(), 0);
              std::fill(projSum.begin(), projSum.end(), ProjectorSample{});
              bool sampleActive[kLanes];
              for (int lane = 0; lane < kLanes; ++lane) sampleActive[lane] = active[lane] && center.hit(lane);
              for (size_t sampleIndex = 0; sampleIndex < pattern.size(); ++sampleIndex) {
                const glm::vec2& offset = pattern[sampleIndex];
                tracer.tracePrimary(px, py, sampleActive, offset.x + shift.x, offset.y + shift.y, surface, sample);
                // Only samples on the center's object count: the pixel's fractional visibility
                // is that of the surface its id and position describe.
                for (int lane = 0; lane < kLanes; ++lane) {
                  if (sample.hit(lane) && sample.geom[lane] != center.geom[lane]) sample.drop(lane);
                  if (sample.hit(lane)) ++sameObject[lane];
                }
                for (size_t l = 0; l < lightCount; ++l) {
                  if (lights[l].sized) {
                    tracer.evalSizedLight(lights[l], sample, everyLane, px, py, uint32_t(sampleIndex + 1), soft);
                    for (int lane = 0; lane < kLanes; ++lane) {
                      if (!sample.hit(lane)) continue;
                      visSum[l * kLanes + lane] += soft[lane].vis;
                      sampledPoints[l * kLanes + lane] += soft[lane].sampled ? 1 : 0;
                      litSamples[l * kLanes + lane] += soft[lane].lit;
                    }
                    continue;
                  }
                  tracer.evalLight(lights[l], sample, false, sampleVis, sampleDist);
                  for (int lane = 0; lane < kLanes; ++lane)
                    if (sample.hit(lane)) visSum[l * kLanes + lane] += sampleVis[lane];
                }
                for (size_t p = 0; p < projectorCount; ++p) {
                  tracer.evalProjector(projectors[p], sample, sampleProj);
                  for (int lane = 0; lane < kLanes; ++lane) {
                    if (!sample.hit(lane)) continue;
                    ProjectorSample& sum = projSum[p * kLanes + lane];
                    sum.coverage += sampleProj[lane].coverage;
                    sum.rgb += sampleProj[lane].rgb;
                  }
                }
              }
            }

            // The packet's values, then into the tile's planes a block row at a time. The values
            // are stored as SIMD values where they are made lane by lane otherwise: putBlock reads
            // a row as one 16-byte load, which a CPU cannot forward from four scalar stores (it
            // waits for them to reach the cache).
            const int rowLanes = std::min(kBlockWidth, x1 - bx), rows = std::min(kBlockHeight, y1 - by);
            const size_t blockPixel = size_t(by - y0) * kTileSize + size_t(bx - x0);
            auto put = [&](float* plane, const float* values) { putBlock(plane + blockPixel, values, rowLanes, rows); };
            alignas(kSimdAlign) float values[kLanes];
            put(planes.hit, center.hitValue);
            put(planes.objectId, center.objectId);
            if (all) putSurface(center, planes, blockPixel, rowLanes, rows);
            for (size_t l = 0; l < lightCount; ++l) {
              const float* vis = &centerVis[l * kLanes];
              if (lights[l].sized) {
                putSizedLight(tracer, lights[l], center, px, py, pattern.empty(), sameObject, &centerSoft[l * kLanes],
                              &visSum[l * kLanes], &sampledPoints[l * kLanes], &litSamples[l * kLanes],
                              &centerDist[l * kLanes], put, planes.vis[l], planes.visSigma[l]);
                put(planes.occluderDist[l], &centerDist[l * kLanes]);
                continue;
              }
              if (!pattern.empty()) {
                for (int lane = 0; lane < kLanes; ++lane) {
                  const int count = sameObject[lane];
                  values[lane] = count > 0 ? float(visSum[l * kLanes + lane] / count) : vis[lane];
                }
                vis = values;
              }
              put(planes.vis[l], vis);
              put(planes.occluderDist[l], &centerDist[l * kLanes]);
            }
            if (projectorCount > 0 || pictureBytes) {
              for (int lane = 0; lane < kLanes; ++lane) {
                if (!active[lane]) continue;
                const size_t pixel = size_t(py[lane] - y0) * kTileSize + size_t(px[lane] - x0);
                const int count = sameObject[lane];
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
                  const bool hit = center.hit(lane);
                  const glm::vec3 albedo =
                      hit ? shader.albedo(embree->geometry(center.geom[lane]).object, center.prim[lane])
                          : glm::vec3(0.8f);
                  const float vis = pictureLight >= 0 ? planes.vis[size_t(pictureLight)][pixel] : 1.0f;
                  shader.shade(hit, albedo, center.normalAt(lane), center.positionAt(lane), vis, projectorCount,
                               pictureCoverage.data(), pictureRgb.data(),
                               pictureBytes + (size_t(py[lane]) * size_t(width) + size_t(px[lane])) * 3);
                }
              }
            }
          }
        }
        for (size_t c = 0; c < channelCount; ++c)
          copyTileRows(tileBase[c], frameBase[c], width, x0, y0, x1, y1, frameFill[c]);
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
