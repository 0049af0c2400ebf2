#pragma once
// Private to reference/: the Embree device and scene for one shadowlab::Scene, and the filter
// function that gives Embree the harness's rules (alpha cutoff, one-sided materials, objects that
// cast no shadow). Only geometries that need one of those rules get the filter: an opaque,
// two-sided, shadow-casting object is traced at Embree's bare speed.
#include <cstdint>
#include <mutex>
#include <string>
#include <vector>

#include <embree3/rtcore.h>
#include <glm/glm.hpp>

#include "shadowlab/scenes/scene.h"

namespace shadowlab::reference_detail {

// Packet width used everywhere: rtcIntersect8 / rtcOccluded8.
constexpr int kLanes = 8;

enum TriangleFlags : uint8_t {
  kOneSided = 1,  // material.twoSided == false
  kAlpha = 2,     // material has an alpha texture (holes where alpha < cutoff)
};

// One triangle as a camera ray's hit needs it, in one place (one or two cache lines instead of the
// index, three positions and the normal spread over four arrays).
struct TriangleData {
  glm::vec3 p[3];       // the object's positions at the triangle's indices
  glm::vec3 normal;     // unit, cross(p1 - p0, p2 - p0) (CCW front); 0 for a degenerate triangle
  float maxAbs = 0.0f;  // the largest coordinate magnitude among p[0..2] (the shadow-origin rule)
};

// What the filter and the trace need about one Object, reachable from Embree's geometry user pointer.
struct GeometryData {
  unsigned geomId = 0;  // == index into Scene::objects
  const Object* object = nullptr;
  const std::vector<Material>* materials = nullptr;
  std::vector<TriangleData> triangles;  // per triangle
  std::vector<uint8_t> flags;           // per triangle, TriangleFlags
  bool castsShadow = true;
  bool anyFlags = false;  // some triangle has TriangleFlags: camera and shadow rays need the filter
};

enum class RayKind : uint8_t { Camera, Shadow };

// Extended intersect context: Embree passes this pointer to the filter (the RTCIntersectContext
// must be the first member), which needs to know whether a camera or a shadow ray hit.
struct TraceContext {
  RTCIntersectContext rtc;
  RayKind kind = RayKind::Camera;

  explicit TraceContext(RayKind k);
};

class EmbreeScene {
 public:
  // Builds one triangle geometry per object (geomID = object index, primID = triangle index).
  // Throws DriverError on any Embree error.
  explicit EmbreeScene(const Scene& scene);
  ~EmbreeScene();
  EmbreeScene(const EmbreeScene&) = delete;
  EmbreeScene& operator=(const EmbreeScene&) = delete;

  RTCScene handle() const { return scene_; }
  const GeometryData& geometry(unsigned geomId) const { return geometries_[geomId]; }
  // Throws DriverError naming `what` and Embree's message when the device holds an error.
  void check(const char* what) const;

 private:
  RTCDevice device_ = nullptr;
  RTCScene scene_ = nullptr;
  std::vector<GeometryData> geometries_;
  // Embree's error callback may run on any thread.
  mutable std::mutex messageMutex_;
  mutable std::string lastMessage_;
  static void errorCallback(void* self, RTCError code, const char* message);
};

}  // namespace shadowlab::reference_detail
