// Camera, projector and texture conventions shared by the reference (rays) and the rasterizer
// (matrices). Both renderers must agree to the last pixel, so the formulas live here once.
#include "shadowlab/scenes/scene.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include <glm/gtc/matrix_transform.hpp>

#include "shadowlab/scenes/io.h"

namespace shadowlab {

namespace {

// Right-handed perspective into Vulkan clip space for a camera looking down -z (view space, y up):
//   clip.x = (f / aspect) * x
//   clip.y = -f * y                              (Vulkan NDC y points down: +y_view -> top row)
//   clip.z = far / (near - far) * z + near * far / (near - far)   (z = -near -> 0, z = -far -> 1)
//   clip.w = -z
// with f = 1 / tan(vfov / 2). The viewport (x = 0, y = 0, width W, height H) then maps
// NDC to pixels: px = (ndc.x + 1) / 2 * W, py = (ndc.y + 1) / 2 * H, so pixel centers
// (i + 0.5, j + 0.5) are the points rayDirection(i + 0.5, j + 0.5) passes through.
glm::mat4 vulkanPerspective(float vfovDeg, float aspect, float nearPlane, float farPlane) {
  float f = 1.0f / std::tan(glm::radians(vfovDeg) * 0.5f);
  glm::mat4 m(0.0f);  // glm is column-major: m[col][row]
  m[0][0] = f / aspect;
  m[1][1] = -f;
  m[2][2] = farPlane / (nearPlane - farPlane);
  m[2][3] = -1.0f;
  m[3][2] = nearPlane * farPlane / (nearPlane - farPlane);
  return m;
}

}  // namespace

const std::vector<KindInfo<LightType>>& lightTypeKinds() {
#define SHADOWLAB_ROW(name, code, key, help) {LightType::name, key, help},
  static const std::vector<KindInfo<LightType>> kinds = {SHADOWLAB_LIGHT_TYPES(SHADOWLAB_ROW)};
#undef SHADOWLAB_ROW
  return kinds;
}

// Alpha test lookup, both renderers: nearest texel with repeat addressing,
//   x = floor(frac(u) * W), y = floor(frac(v) * H), frac(t) = t - floor(t),
// clamped to W-1 / H-1 because frac of a value just below an integer can round to 1.0f.
// v = 0 is the top row of the image.
float sampleAlphaNearest(const Image& alpha, glm::vec2 uv) {
  if (alpha.width <= 0 || alpha.height <= 0 || alpha.channels <= 0) return 1.0f;
  float fu = uv.x - std::floor(uv.x);
  float fv = uv.y - std::floor(uv.y);
  int x = std::min(alpha.width - 1, std::max(0, int(std::floor(fu * float(alpha.width)))));
  int y = std::min(alpha.height - 1, std::max(0, int(std::floor(fv * float(alpha.height)))));
  return alpha.at(x, y, alpha.channels - 1);
}

// Projective texture matrix: bias * projection * view, where
//   view       = lookAt(position, position + direction, up)        (right-handed, looks down -z)
//   projection = vulkanPerspective(fovDeg, aspect, near, far)       (NDC y down, depth 0..1)
//   bias       = u = 0.5 * ndc.x + 0.5, v = 0.5 * ndc.y + 0.5, depth unchanged
// so (u, v, depth) = xyz / w with v = 0 at the image's top row, and w = -z_view: the distance
// in front of the projector along its axis (w <= 0: behind it).
glm::mat4 Projector::texFromWorld() const {
  glm::mat4 view(glm::lookAt(glm::dvec3(position), glm::dvec3(position) + glm::dvec3(direction), glm::dvec3(up)));
  glm::mat4 proj = vulkanPerspective(fovDeg, aspect, nearPlane, farPlane);
  glm::mat4 bias(1.0f);
  bias[0][0] = 0.5f;
  bias[1][1] = 0.5f;
  bias[3][0] = 0.5f;
  bias[3][1] = 0.5f;
  return bias * proj * view;
}

// Computed in double and rounded once, so the float matrix and the float ray agree to ~1e-5 px.
glm::mat4 Camera::viewFromWorld() const {
  return glm::mat4(glm::lookAt(glm::dvec3(position), glm::dvec3(lookAt), glm::dvec3(up)));
}

// Orthographic: x, y scaled by the half extents (y flipped: Vulkan's y down), depth 0 at near and
// 1 at far, w = 1; the pixel centers match rayOrigin's.
glm::mat4 Camera::clipFromView() const {
  if (!orthographic()) return vulkanPerspective(vfovDeg, float(width) / float(height), nearPlane, farPlane);
  const double halfH = 0.5 * double(orthoHeight), halfW = halfH * double(float(width) / float(height));
  glm::dmat4 m(0.0);
  m[0][0] = 1.0 / halfW;
  m[1][1] = -1.0 / halfH;
  m[2][2] = 1.0 / (double(nearPlane) - double(farPlane));
  m[3][2] = double(nearPlane) / (double(nearPlane) - double(farPlane));
  m[3][3] = 1.0;
  return glm::mat4(m);
}

// The inverse of clipFromView for the point at image position (x, y) in pixels:
//   ndc = (2x / W - 1, 2y / H - 1)
//   d_view = (ndc.x * aspect * t, -ndc.y * t, -1), t = tan(vfov / 2), aspect = W / H
// expressed in world space with glm::lookAt's basis (right s, up u, forward f), then normalized.
// Double inside: the reference traces these rays and the rasterizer uses the float matrices;
// both must land on the same pixel center.
CameraRays::CameraRays(const Camera& camera)
    : position_(camera.position),
      forward_(glm::normalize(glm::dvec3(camera.lookAt) - glm::dvec3(camera.position))),
      right_(glm::normalize(glm::cross(forward_, glm::dvec3(camera.up)))),
      trueUp_(glm::cross(right_, forward_)),
      tanHalfFov_(std::tan(double(glm::radians(camera.vfovDeg)) * 0.5)),
      aspect_(double(float(camera.width) / float(camera.height))),
      halfHeight_(camera.orthographic() ? 0.5 * double(camera.orthoHeight) : 0.0),
      width_(camera.width),
      height_(camera.height) {}

// Orthographic: every ray is the view direction, from the image plane's point
//   origin = position + ndc.x * aspect * h * s - ndc.y * h * u,  h = orthoHeight / 2.
glm::vec3 CameraRays::direction(float x, float y) const {
  if (halfHeight_ > 0) return glm::vec3(forward_);
  double out[3];
  perspectiveDirection(double(x), double(y), out);
  return glm::vec3(out[0], out[1], out[2]);
}

glm::vec3 CameraRays::origin(float x, float y) const {
  if (!(halfHeight_ > 0)) return glm::vec3(position_);
  const double ndcX = 2.0 * x / width_ - 1.0;
  const double ndcY = 2.0 * y / height_ - 1.0;
  return glm::vec3(position_ + (ndcX * aspect_ * halfHeight_) * right_ - (ndcY * halfHeight_) * trueUp_);
}

glm::vec3 Camera::rayDirection(float x, float y) const { return CameraRays(*this).direction(x, y); }
glm::vec3 Camera::rayOrigin(float x, float y) const { return CameraRays(*this).origin(x, y); }

std::string Camera::hash() const {
  float floats[10] = {position.x, position.y, position.z, lookAt.x, lookAt.y, lookAt.z, up.x, up.y, up.z, vfovDeg};
  int32_t ints[2] = {width, height};
  unsigned char bytes[sizeof(floats) + sizeof(ints)];
  std::memcpy(bytes, floats, sizeof(floats));
  std::memcpy(bytes + sizeof(floats), ints, sizeof(ints));
  const std::string h = hashHex(fnv1a64(bytes, sizeof(bytes)));
  if (!orthographic()) return h;
  // Orthographic: orthoHeight continues the hash (a perspective camera's hash is unchanged).
  uint64_t seed = 0;
  for (char c : h) seed = (seed << 4) | uint64_t(c <= '9' ? c - '0' : c - 'a' + 10);
  return hashHex(fnv1a64(&orthoHeight, sizeof(orthoHeight), seed));
}

glm::vec3 Scene::boundsMin() const {
  glm::vec3 lo(std::numeric_limits<float>::infinity());
  bool any = false;
  for (const auto& o : objects)
    for (const auto& p : o.positions) {
      lo = glm::min(lo, p);
      any = true;
    }
  return any ? lo : glm::vec3(0.0f);
}

glm::vec3 Scene::boundsMax() const {
  glm::vec3 hi(-std::numeric_limits<float>::infinity());
  bool any = false;
  for (const auto& o : objects)
    for (const auto& p : o.positions) {
      hi = glm::max(hi, p);
      any = true;
    }
  return any ? hi : glm::vec3(0.0f);
}

const Light* Scene::findLight(const std::string& lightName) const {
  for (const auto& l : lights)
    if (l.name == lightName) return &l;
  return nullptr;
}

std::string Scene::lightOrDefault(const std::string& lightName) const {
  if (!lightName.empty()) return lightName;
  return lights.empty() ? "" : lights.front().name;
}

const CameraPath* Scene::findPath(const std::string& pathName) const {
  for (const auto& p : paths)
    if (p.name == pathName) return &p;
  return nullptr;
}

size_t Scene::triangleCount() const {
  size_t n = 0;
  for (const auto& o : objects) n += o.triangles.size();
  return n;
}

}  // namespace shadowlab
