#include "embree_scene.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "shadowlab/scenes/error.h"

namespace shadowlab::reference_detail {
namespace {

const char* errorName(RTCError code) {
  switch (code) {
    case RTC_ERROR_NONE: return "RTC_ERROR_NONE";
    case RTC_ERROR_UNKNOWN: return "RTC_ERROR_UNKNOWN";
    case RTC_ERROR_INVALID_ARGUMENT: return "RTC_ERROR_INVALID_ARGUMENT";
    case RTC_ERROR_INVALID_OPERATION: return "RTC_ERROR_INVALID_OPERATION";
    case RTC_ERROR_OUT_OF_MEMORY: return "RTC_ERROR_OUT_OF_MEMORY";
    case RTC_ERROR_UNSUPPORTED_CPU: return "RTC_ERROR_UNSUPPORTED_CPU";
    case RTC_ERROR_CANCELLED: return "RTC_ERROR_CANCELLED";
  }
  return "RTC_ERROR_?";
}

// Embree calls this for every candidate hit on a geometry that has it (intersect and occluded,
// packets and single rays alike), before it accepts the hit. Setting valid[i] = 0 rejects the hit
// and traversal goes on, exactly as if the triangle were not there for that ray. Shadow rays need
// no rule against their own triangle: their origin is offset off the surface (reference.cpp).
void filterHits(const RTCFilterFunctionNArguments* args) {
  const auto* geometry = static_cast<const GeometryData*>(args->geometryUserPtr);
  const auto* context = reinterpret_cast<const TraceContext*>(args->context);
  const unsigned n = args->N;
  for (unsigned i = 0; i < n; ++i) {
    if (args->valid[i] != -1) continue;
    if (context->kind == RayKind::Shadow && !geometry->castsShadow) {
      args->valid[i] = 0;
      continue;
    }
    const unsigned prim = RTCHitN_primID(args->hit, n, i);
    const uint8_t flags = geometry->flags[prim];
    if (flags == 0) continue;
    if (flags & kOneSided) {
      const glm::vec3& normal = geometry->triangles[prim].normal;
      const float along = normal.x * RTCRayN_dir_x(args->ray, n, i) + normal.y * RTCRayN_dir_y(args->ray, n, i) +
                          normal.z * RTCRayN_dir_z(args->ray, n, i);
      // Camera rays see the front face when they travel against its normal. A shadow ray travels
      // from the receiver toward the light, so the light sees the occluder's front face when the
      // normal points back along the ray toward the light (along > 0). Edge-on counts as a back face.
      const bool backFace = context->kind == RayKind::Camera ? along >= 0.0f : along <= 0.0f;
      if (backFace) {
        args->valid[i] = 0;
        continue;
      }
    }
    if (flags & kAlpha) {
      const Object& object = *geometry->object;
      const glm::uvec3& tri = object.triangles[prim];
      // Embree's barycentrics: P = (1 - u - v) p0 + u p1 + v p2, and the same weights for uvs.
      const float u = RTCHitN_u(args->hit, n, i);
      const float v = RTCHitN_v(args->hit, n, i);
      const glm::vec2 uv = (1.0f - u - v) * object.uvs[tri.x] + u * object.uvs[tri.y] + v * object.uvs[tri.z];
      const Material& material = (*geometry->materials)[object.triangleMaterial[prim]];
      if (sampleAlphaNearest(material.alphaTexture, uv) < material.alphaCutoff) args->valid[i] = 0;
    }
  }
}

}  // namespace

TraceContext::TraceContext(RayKind k) : kind(k) {
  rtcInitIntersectContext(&rtc);
  // Camera packets are 4x2 pixel blocks and shadow packets start from neighbouring points toward
  // one light: coherent in both cases.
  rtc.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
}

void EmbreeScene::errorCallback(void* self, RTCError code, const char* message) {
  auto* scene = static_cast<EmbreeScene*>(self);
  std::lock_guard<std::mutex> lock(scene->messageMutex_);
  scene->lastMessage_ = std::string(errorName(code)) + ": " + (message ? message : "");
}

void EmbreeScene::check(const char* what) const {
  const RTCError code = rtcGetDeviceError(device_);
  if (code == RTC_ERROR_NONE) return;
  std::lock_guard<std::mutex> lock(messageMutex_);
  std::string detail = lastMessage_.empty() ? errorName(code) : lastMessage_;
  throw DriverError(std::string("embree: ") + what + ": " + detail);
}

EmbreeScene::EmbreeScene(const Scene& scene) {
  device_ = rtcNewDevice(nullptr);
  if (!device_) {
    throw DriverError(std::string("embree: rtcNewDevice failed: ") + errorName(rtcGetDeviceError(nullptr)));
  }
  // A constructor that throws (a bad mesh, an Embree error) runs no destructor: release what was
  // made so far on the way out, or every rejected scene leaks its device.
  struct ReleaseOnThrow {
    RTCDevice& device;
    RTCScene& scene;
    bool armed = true;
    ~ReleaseOnThrow() {
      if (!armed) return;
      if (scene) rtcReleaseScene(scene);
      rtcReleaseDevice(device);
      scene = nullptr;
      device = nullptr;
    }
  } releaseOnThrow{device_, scene_};
  rtcSetDeviceErrorFunction(device_, &EmbreeScene::errorCallback, this);
  check("rtcNewDevice");

  scene_ = rtcNewScene(device_);
  // Robust mode: watertight triangle tests, so no camera or shadow ray slips through the shared
  // edge of two triangles (a speck of false light would be an error in the ground truth itself).
  rtcSetSceneFlags(scene_, RTC_SCENE_FLAG_ROBUST);
  rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_HIGH);
  check("rtcNewScene");

  geometries_.resize(scene.objects.size());
  for (size_t index = 0; index < scene.objects.size(); ++index) {
    const Object& object = scene.objects[index];
    GeometryData& data = geometries_[index];
    data.geomId = unsigned(index);
    data.object = &object;
    data.materials = &scene.materials;
    data.castsShadow = object.castsShadow;
    const size_t triangleCount = object.triangles.size();
    if (object.triangleMaterial.size() != triangleCount) {
      throw DriverError("reference: object \"" + object.name + "\" has " +
                        std::to_string(object.triangleMaterial.size()) + " triangle materials for " +
                        std::to_string(triangleCount) + " triangles");
    }
    data.triangles.resize(triangleCount);
    data.flags.resize(triangleCount);
    for (size_t t = 0; t < triangleCount; ++t) {
      const glm::uvec3& tri = object.triangles[t];
      if (tri.x >= object.positions.size() || tri.y >= object.positions.size() || tri.z >= object.positions.size()) {
        throw DriverError("reference: object \"" + object.name + "\" triangle " + std::to_string(t) +
                          " indexes past its " + std::to_string(object.positions.size()) + " positions");
      }
      const uint32_t materialIndex = object.triangleMaterial[t];
      if (materialIndex >= scene.materials.size()) {
        throw DriverError("reference: object \"" + object.name + "\" triangle " + std::to_string(t) +
                          " uses material " + std::to_string(materialIndex) + " of " +
                          std::to_string(scene.materials.size()));
      }
      const glm::dvec3 p0(object.positions[tri.x]), p1(object.positions[tri.y]), p2(object.positions[tri.z]);
      const glm::dvec3 cross = glm::cross(p1 - p0, p2 - p0);
      const double length = glm::length(cross);
      TriangleData& triangle = data.triangles[t];
      triangle.normal = length > 0.0 ? glm::vec3(cross / length) : glm::vec3(0.0f);
      triangle.p[0] = object.positions[tri.x];
      triangle.p[1] = object.positions[tri.y];
      triangle.p[2] = object.positions[tri.z];
      for (const glm::vec3& p : triangle.p)
        triangle.maxAbs = std::max(triangle.maxAbs, std::max(std::fabs(p.x), std::max(std::fabs(p.y), std::fabs(p.z))));
      const Material& material = scene.materials[materialIndex];
      uint8_t flags = 0;
      if (!material.twoSided) flags |= kOneSided;
      if (material.hasAlpha) {
        if (object.uvs.size() != object.positions.size()) {
          throw InputError(formatError(scene.path, "",
                                       "object \"" + object.name + "\" uses the alpha-tested material \"" +
                                           material.name + "\" but has " + std::to_string(object.uvs.size()) +
                                           " texture coordinates; expected one per position (" +
                                           std::to_string(object.positions.size()) + ")"));
        }
        flags |= kAlpha;
      }
      data.flags[t] = flags;
      if (flags) data.anyFlags = true;
    }

    RTCGeometry geometry = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
    // Embree's own buffers (not shared ones): it pads them for its 16-byte vertex loads.
    auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                                 3 * sizeof(float), object.positions.size()));
    auto* indices = static_cast<unsigned*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                   3 * sizeof(unsigned), triangleCount));
    check("rtcSetNewGeometryBuffer");
    if (!object.positions.empty()) {
      std::memcpy(vertices, object.positions.data(), object.positions.size() * 3 * sizeof(float));
    }
    if (triangleCount) std::memcpy(indices, object.triangles.data(), triangleCount * 3 * sizeof(unsigned));
    rtcSetGeometryUserData(geometry, &data);
    // The filter only where a rule applies, per geometry: one-sided or alpha-tested triangles
    // (camera and shadow rays), or an object that casts no shadow (shadow rays: the occluded
    // queries and the closest-hit pass for occluder_dist, which uses rtcIntersect8). Opaque,
    // two-sided, shadow-casting geometry has none, so Embree accepts its hits without a callback.
    if (data.anyFlags || !data.castsShadow) {
      rtcSetGeometryIntersectFilterFunction(geometry, &filterHits);
      rtcSetGeometryOccludedFilterFunction(geometry, &filterHits);
    }
    rtcCommitGeometry(geometry);
    rtcAttachGeometryByID(scene_, geometry, unsigned(index));
    rtcReleaseGeometry(geometry);
    check("building the triangle geometry");
  }
  rtcCommitScene(scene_);
  check("rtcCommitScene");
  releaseOnThrow.armed = false;
}

EmbreeScene::~EmbreeScene() {
  if (scene_) rtcReleaseScene(scene_);
  if (device_) rtcReleaseDevice(device_);
}

}  // namespace shadowlab::reference_detail
