#include "light_space.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "shadowlab/raster/cascades.h"
#include "shadowlab/raster/lispsm.h"
#include "shadowlab/raster/psm.h"
#include "shadowlab/raster/sdsm.h"
#include "shadowlab/raster/tsm.h"

#include <glm/gtc/matrix_transform.hpp>

namespace shadowlab::raster {

namespace {

glm::vec3 upFor(glm::vec3 dir) { return std::abs(dir.y) > 0.99f ? glm::vec3(0, 0, 1) : glm::vec3(0, 1, 0); }

// View space (right-handed, looking down -z) -> tex, orthographic box.
glm::mat4 texFromViewOrtho(float left, float right, float bottom, float top, float nearZ, float farZ) {
  glm::mat4 m(0.0f);  // glm: m[column][row]
  m[0][0] = 1.0f / (right - left);
  m[3][0] = -left / (right - left);
  m[1][1] = -1.0f / (top - bottom);  // v = 0 at the top
  m[3][1] = top / (top - bottom);
  m[2][2] = -1.0f / (farZ - nearZ);  // depth = (-z - near) / (far - near)
  m[3][2] = -nearZ / (farZ - nearZ);
  m[3][3] = 1.0f;
  return m;
}

// View space -> tex, perspective with square aspect. w = -z.
glm::mat4 texFromViewPerspective(float fovRad, float nearZ, float farZ) {
  float k = 1.0f / std::tan(0.5f * fovRad);
  glm::mat4 m(0.0f);
  m[0][0] = 0.5f * k;  // u*w = 0.5 k x + 0.5 w
  m[2][0] = -0.5f;
  m[1][1] = -0.5f * k;  // v*w = -0.5 k y + 0.5 w
  m[2][1] = -0.5f;
  m[2][2] = -farZ / (farZ - nearZ);  // depth*w = f/(f-n) (w - n)
  m[3][2] = -farZ * nearZ / (farZ - nearZ);
  m[2][3] = -1.0f;
  return m;
}

float farthestCorner(const Scene& scene, glm::vec3 from) {
  glm::vec3 lo = scene.boundsMin(), hi = scene.boundsMax();
  float best = 0;
  for (int i = 0; i < 8; ++i) {
    glm::vec3 c((i & 1) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y, (i & 4) ? hi.z : lo.z);
    best = std::max(best, glm::length(c - from));
  }
  return best;
}

// The box of all scene vertices in a light's view space, padded by a hair so the extreme
// vertices rasterize inside the map, not on its border. All zero for a scene without vertices.
void sceneBoundsIn(const Scene& scene, const glm::mat4& lightFromWorld, glm::vec3& boundsMin, glm::vec3& boundsMax) {
  float inf = std::numeric_limits<float>::infinity();
  boundsMin = glm::vec3(inf);
  boundsMax = glm::vec3(-inf);
  for (const Object& o : scene.objects)
    for (const glm::vec3& p : o.positions) {
      glm::vec3 v = glm::vec3(lightFromWorld * glm::vec4(p, 1.0f));
      boundsMin = glm::min(boundsMin, v);
      boundsMax = glm::max(boundsMax, v);
    }
  if (!(boundsMin.x <= boundsMax.x)) boundsMin = boundsMax = glm::vec3(0);
  glm::vec3 pad = glm::max((boundsMax - boundsMin) * 1e-4f, glm::vec3(1e-5f));
  boundsMin -= pad;
  boundsMax += pad;
}

// The part of the scene in the view frustum: per object with vertices, the exact intersection of
// the frustum (camera near..far) with the object's box (lispsm.h's viewBoxIntersection), empty
// where they miss. One box for the whole scene would count the empty air around a camera standing
// inside it as visible.
std::vector<std::vector<glm::dvec3>> visibleBody(const Scene& scene, const Camera& camera) {
  std::vector<std::vector<glm::dvec3>> parts;
  for (const Object& o : scene.objects) {
    if (o.positions.empty()) continue;
    glm::vec3 objectMin = o.positions.front(), objectMax = objectMin;
    for (const glm::vec3& p : o.positions) {
      objectMin = glm::min(objectMin, p);
      objectMax = glm::max(objectMax, p);
    }
    std::vector<glm::dvec3> c = viewBoxIntersection(camera, objectMin, objectMax);
    if (!c.empty()) parts.push_back(std::move(c));
  }
  return parts;
}

// Warps below this strength (d / n: how much denser the near face's texels are along the axis,
// minus 1) are not worth a second basis: the fit falls back to fit=tight exactly. It also covers
// the view along the light, where the warp has no axis (sin(gamma) = 0, d / n = 0).
constexpr double kLispsmMinWarp = 1e-3;

// The part of the scene in the fit camera's view frustum, as the union of the frustum's exact
// intersections with each object's box (lispsm.h; one box for the whole scene would count the
// empty air around a camera standing inside it as visible, z_n would drop to the near plane): its
// vertices (world) and their view-depth range [zNear, zFar]. Empty when nothing is in view.
struct ViewBody {
  std::vector<glm::dvec3> corners;
  double zNear = 0, zFar = 0;
};
ViewBody viewBody(const Scene& scene, const Camera& camera) {
  ViewBody body;
  for (const std::vector<glm::dvec3>& part : visibleBody(scene, camera))
    body.corners.insert(body.corners.end(), part.begin(), part.end());
  glm::dvec3 forward64 = glm::normalize(glm::dvec3(camera.lookAt) - glm::dvec3(camera.position));
  double inf = std::numeric_limits<double>::infinity();
  body.zNear = inf;
  body.zFar = -inf;
  for (const glm::dvec3& c : body.corners) {
    double depth = glm::dot(c - glm::dvec3(camera.position), forward64);
    body.zNear = std::min(body.zNear, depth);
    body.zFar = std::max(body.zFar, depth);
  }
  return body;
}

// fit=lispsm for a directional light; false where it falls back to fit=tight.
bool lispsmLayer(const Scene& scene, const Camera& camera, const glm::mat4& lightViewFromWorld, const Method& method,
                 MapLayer& layer) {
  glm::vec3 forward = glm::normalize(camera.lookAt - camera.position);
  LispsmBasis basis = lispsmBasis(lightViewFromWorld, forward);
  if (!(basis.sinGamma > 0.0)) return false;
  glm::mat4 lightFromWorld(basis.lightFromWorld);
  // The body: the view frustum's part of the scene (viewBody), its light-space x/y box clipped to
  // the scene's as fit=tight does, extended towards the light to the scene bounds so that every
  // caster lies in it. Every visible point is in it.
  ViewBody body = viewBody(scene, camera);
  if (body.corners.empty()) return false;  // nothing of the scene in view: no body to warp for
  double zNear = body.zNear, zFar = body.zFar;
  double inf = std::numeric_limits<double>::infinity();
  glm::dvec2 lo(inf), hi(-inf);
  for (const glm::dvec3& c : body.corners) {
    glm::dvec2 l(basis.lightFromWorld * glm::dvec4(c, 1.0));
    lo = glm::min(lo, l);
    hi = glm::max(hi, l);
  }
  glm::vec3 sceneMin, sceneMax;
  sceneBoundsIn(scene, lightFromWorld, sceneMin, sceneMax);
  glm::dvec2 clippedLo = glm::max(lo, glm::dvec2(sceneMin)), clippedHi = glm::min(hi, glm::dvec2(sceneMax));
  if (clippedLo.x < clippedHi.x && clippedLo.y < clippedHi.y) lo = clippedLo, hi = clippedHi;
  glm::dvec2 pad = glm::max((hi - lo) * 1e-4, glm::dvec2(1e-5));
  glm::dvec3 bodyMin(lo - pad, sceneMin.z), bodyMax(hi + pad, sceneMax.z);
  double inverseNear =
      lispsmInverseNear(std::max(zNear, 1e-4), std::max(zFar, zNear), basis.sinGamma, method.lispsmNScale);
  if (!(inverseNear * (bodyMax.y - bodyMin.y) >= kLispsmMinWarp)) return false;
  double eyeX = (basis.lightFromWorld * glm::dvec4(glm::dvec3(camera.position), 1.0)).x;
  LispsmMap map = lispsmTexFromLight(bodyMin, bodyMax, eyeX, inverseNear, method.mapSize);
  layer.texFromWorld = glm::mat4(map.texFromLight * basis.lightFromWorld);
  layer.texelWorldPerW = float(map.texelWorldPerW);
  return true;
}

// The casters that can shadow a visible point lie on its ray towards the light, inside the scene's
// box. Per part of the visible body: its vertices and the same moved towards the light by T, the
// smallest over the box's faces the light's rays leave by of the largest exit distance over the
// vertices (each face's exit distance is affine in the point, so its largest over the part is at
// a vertex: the hull holds every such caster).
std::vector<glm::dvec3> casterBody(const Scene& scene, const std::vector<std::vector<glm::dvec3>>& parts,
                                   glm::dvec3 towardLight) {
  glm::dvec3 lo(scene.boundsMin()), hi(scene.boundsMax());
  std::vector<glm::dvec3> out;
  for (const std::vector<glm::dvec3>& part : parts) {
    double reach = std::numeric_limits<double>::infinity();
    for (int i = 0; i < 3; ++i) {
      if (towardLight[i] == 0.0) continue;
      double face = towardLight[i] > 0.0 ? hi[i] : lo[i], largest = 0.0;
      for (const glm::dvec3& p : part) largest = std::max(largest, (face - p[i]) / towardLight[i]);
      reach = std::min(reach, largest);
    }
    if (!std::isfinite(reach)) reach = 0.0;
    for (const glm::dvec3& p : part) {
      out.push_back(p);
      out.push_back(p + reach * towardLight);
    }
  }
  return out;
}

// fit=psm for a directional light (psm.h); false where it falls back to fit=tight: nothing of the
// scene in view, no cone from the light in post-perspective space holding the casters, or a warp
// below kLispsmMinWarp (the view along the light, either way: the map is orthographic there).
bool psmLayer(const Scene& scene, const Camera& camera, glm::vec3 lightDirection, const Method& method,
              MapLayer& layer) {
  std::vector<std::vector<glm::dvec3>> parts = visibleBody(scene, camera);
  std::vector<glm::dvec3> visible;
  for (const std::vector<glm::dvec3>& part : parts) visible.insert(visible.end(), part.begin(), part.end());
  if (visible.empty()) return false;
  glm::dvec3 towardLight = -glm::normalize(glm::dvec3(lightDirection));
  PsmFit fit =
      psmFit(camera, towardLight, visible, casterBody(scene, parts, towardLight), method.psmSlideBack, method.mapSize);
  if (!fit.ok || !(fit.texels.warp >= kLispsmMinWarp)) return false;
  layer.texFromWorld = glm::mat4(fit.texFromWorld);
  layer.texelWorldPerW = float(fit.texels.texelWorldPerW);
  return true;
}

// Trapezoids whose warp is below this strength (lambda / eta: w on the base is 1 + lambda / eta
// times w on the top, the texels there that much wider) fall back to fit=tight exactly, as fit=lispsm
// does below kLispsmMinWarp.
constexpr double kTsmMinWarp = 1e-3;

// fit=tsm for a directional light (tsm.h); false where it falls back to fit=tight: nothing of the
// scene in view, no center line (the view along the light: the near and far faces' centers project
// to one point), no eta for the 80 % rule, or a warp below kTsmMinWarp.
bool tsmLayer(const Scene& scene, const Camera& camera, const glm::mat4& lightViewFromWorld, const Method& method,
              MapLayer& layer) {
  ViewBody body = viewBody(scene, camera);
  if (body.corners.empty()) return false;
  glm::dmat4 lightView(lightViewFromWorld);
  std::vector<glm::dvec3> hull;
  hull.reserve(body.corners.size());
  for (const glm::dvec3& c : body.corners) hull.push_back(glm::dvec3(lightView * glm::dvec4(c, 1.0)));
  glm::dvec3 eye(camera.position);
  glm::dvec3 forward = glm::normalize(glm::dvec3(camera.lookAt) - eye);
  auto project = [&](double viewDepth) { return glm::dvec2(lightView * glm::dvec4(eye + forward * viewDepth, 1.0)); };
  double focusDepth = body.zNear + double(method.tsmFocusDistance) * (body.zFar - body.zNear);
  glm::vec3 sceneMin, sceneMax;
  sceneBoundsIn(scene, lightViewFromWorld, sceneMin, sceneMax);
  TsmMap map = tsmFit(hull, project(body.zNear), project(body.zFar), project(focusDepth), double(method.tsmFocus),
                      double(sceneMin.z), double(sceneMax.z), method.mapSize);
  if (!map.valid || !(map.lambda / map.eta >= kTsmMinWarp)) return false;
  layer.texFromWorld = glm::mat4(map.texFromLight * lightView);
  layer.texelWorldPerW = float(map.texelWorldPerW);
  // The depth is the light's own (Martin & Tan): the shadow pass writes it, the resolve compares
  // it; texFromWorld's z / w (the same depth over w) only places the vertices for the clipper.
  layer.lightDepth = true;
  layer.depthFromWorld = glm::vec4(map.depthFromLight * lightView);  // a row: (depth row) * lightView
  return true;
}

// fit=sdsm for a directional light (sdsm.h): the splits over the samples' depth range, each
// layer's crop the box of its samples (a slice no sample reads: fit=cascades' crop of it, which no
// pixel looks up); false without samples, where the caller fits as fit=cascades.
bool sdsmLayers(const Camera& camera, const glm::mat4& lightViewFromWorld, const Method& method,
                const std::vector<glm::vec3>& visiblePoints, glm::vec3 sceneMin, glm::vec3 sceneMax, LightSpace& out) {
  const std::vector<SdsmSample> samples = sdsmSamples(visiblePoints, camera, lightViewFromWorld);
  ViewDepthRange range;
  if (!sdsmDepthRange(samples, range)) return false;
  const int count = std::clamp(method.cascadeCount, 1, 8);
  const std::vector<double> splits = cascadeSplits(range.nearView, range.farView, count, method.sdsmLambda);
  const std::vector<SdsmBounds> bounds = sdsmPartitionBounds(samples, splits, method.cascadeBlend);
  for (int i = 0; i < count; ++i) {
    const CascadeCrop crop = bounds[size_t(i)].samples > 0
                                 ? sdsmCrop(bounds[size_t(i)], method.mapSize, method.sdsmSnap)
                                 : cascadeCrop(camera, lightViewFromWorld, splits[size_t(i)], splits[size_t(i) + 1],
                                               method.mapSize, false, glm::vec2(sceneMin), glm::vec2(sceneMax));
    MapLayer layer;
    layer.texelWorldPerW = crop.texelWorld;
    // The depth range is the scene's: casters between the light and the samples still cast.
    layer.texFromWorld =
        texFromViewOrtho(crop.minLight.x, crop.maxLight.x, crop.minLight.y, crop.maxLight.y, -sceneMax.z, -sceneMin.z) *
        lightViewFromWorld;
    out.layers.push_back(layer);
  }
  for (double c : splits) out.cascadeSplitsView.push_back(float(c));
  return true;
}

}  // namespace

glm::mat4 clipFromTex() {
  glm::mat4 m(1.0f);
  m[0][0] = 2.0f;
  m[3][0] = -1.0f;
  m[1][1] = 2.0f;
  m[3][1] = -1.0f;
  return m;
}

int cubeFace(glm::vec3 v) {
  glm::vec3 a = glm::abs(v);
  if (a.x >= a.y && a.x >= a.z) return v.x > 0 ? 0 : 1;
  if (a.y >= a.z) return v.y > 0 ? 2 : 3;
  return v.z > 0 ? 4 : 5;
}

LightSpace fitLight(const Scene& scene, const Light& light, const Method& method, const Camera& fitCamera,
                    const std::vector<glm::vec3>* visiblePoints) {
  const int mapSize = method.mapSize;
  LightSpace out;
  glm::vec3 lo = scene.boundsMin(), hi = scene.boundsMax();
  glm::vec3 center = 0.5f * (lo + hi);
  float radius = std::max(0.5f * glm::length(hi - lo), 1e-4f) * 1.001f;
  if (light.type == LightType::Directional) {
    out.depthClamp = true;
    glm::vec3 dir = glm::normalize(light.direction);
    glm::mat4 viewFromWorld = glm::lookAt(center, center + dir, upFor(dir));
    if (method.fit == Fit::Sphere) {
      MapLayer layer;
      layer.texFromWorld = texFromViewOrtho(-radius, radius, -radius, radius, -radius, radius) * viewFromWorld;
      layer.texelWorldPerW = 2.0f * radius / float(mapSize);
      out.layers.push_back(layer);
      return out;
    }
    const Camera& camera = fitCamera;
    if (method.fit == Fit::Lispsm || method.fit == Fit::Psm || method.fit == Fit::Tsm) {
      MapLayer layer;
      bool warped = method.fit == Fit::Lispsm ? lispsmLayer(scene, camera, viewFromWorld, method, layer)
                    : method.fit == Fit::Psm  ? psmLayer(scene, camera, dir, method, layer)
                                              : tsmLayer(scene, camera, viewFromWorld, method, layer);
      if (warped) {
        out.layers.push_back(layer);
        return out;
      }
    }
    // The scene's bounds in light space (the box of all vertices): the depth range of every
    // layer (the near plane pulled back to the scene bounds, so a caster between the light and a
    // slice still writes the slice's map) and the clip of the x/y crops (texels outside the
    // scene are wasted).
    glm::vec3 sceneMin, sceneMax;
    sceneBoundsIn(scene, viewFromWorld, sceneMin, sceneMax);
    if (method.fit == Fit::Sdsm && visiblePoints &&
        sdsmLayers(camera, viewFromWorld, method, *visiblePoints, sceneMin, sceneMax, out))
      return out;
    bool stabilize = method.fit == Fit::Cascades && method.cascadeStabilize;
    ViewDepthRange range = cascadeDepthRange(camera, lo, hi);
    if (stabilize) {
      // Stabilized crops must keep their size while the camera moves: the clipped range (and so
      // every split) would change with the camera's position, the camera's own range does not.
      range = cameraDepthRange(camera);
    }
    int count = isCascadedFit(method.fit) ? std::clamp(method.cascadeCount, 1, 8) : 1;
    std::vector<double> splits = cascadeSplits(range.nearView, range.farView, count, method.cascadeLambda);
    for (int i = 0; i < count; ++i) {
      CascadeCrop crop = cascadeCrop(camera, viewFromWorld, splits[size_t(i)], splits[size_t(i) + 1], mapSize,
                                     stabilize, glm::vec2(sceneMin), glm::vec2(sceneMax));
      MapLayer layer;
      layer.texelWorldPerW = crop.texelWorld;
      layer.texFromWorld = texFromViewOrtho(crop.minLight.x, crop.maxLight.x, crop.minLight.y, crop.maxLight.y,
                                            -sceneMax.z, -sceneMin.z) *
                           viewFromWorld;
      out.layers.push_back(layer);
    }
    if (isCascadedFit(method.fit))
      for (double c : splits) out.cascadeSplitsView.push_back(float(c));
    return out;
  }
  float nearZ = std::max(light.nearPlane, 1e-5f);
  float farZ = std::max(farthestCorner(scene, light.position) * 1.01f, nearZ * 2.0f);
  if (light.type == LightType::Spot) {
    glm::vec3 dir = glm::normalize(light.direction);
    float fov = glm::radians(std::clamp(light.coneDeg, 1e-3f, 179.0f));
    MapLayer layer;
    layer.texFromWorld =
        texFromViewPerspective(fov, nearZ, farZ) * glm::lookAt(light.position, light.position + dir, upFor(dir));
    layer.texelWorldPerW = 2.0f * std::tan(0.5f * fov) / float(mapSize);
    out.layers.push_back(layer);
    return out;
  }
  const glm::vec3 axes[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  for (const glm::vec3& axis : axes) {
    MapLayer layer;
    layer.texFromWorld = texFromViewPerspective(glm::radians(90.0f), nearZ, farZ) *
                         glm::lookAt(light.position, light.position + axis, upFor(axis));
    layer.texelWorldPerW = 2.0f / float(mapSize);
    out.layers.push_back(layer);
  }
  return out;
}

MapLayer projectorLayer(const Projector& projector, int mapSize) {
  MapLayer layer;
  layer.texFromWorld = projector.texFromWorld();
  float fov = glm::radians(projector.fovDeg);
  layer.texelWorldPerW = 2.0f * std::tan(0.5f * fov) / float(mapSize);
  return layer;
}

}  // namespace shadowlab::raster
