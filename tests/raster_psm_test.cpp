// fit=psm's pieces without a GPU: the virtual camera's slide-back, the light in post-perspective
// space (source ahead of the viewer, inverted sink behind it, directional across), the map of the
// body into the unit cube with w > 0 and the depth order along light rays kept, the texel measure
// against the closed forms of the orthographic and LiSPSM maps, and the fallback to fit=tight's
// matrix for a view along the light (either way).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "shadowlab/raster/lispsm.h"
#include "shadowlab/raster/psm.h"
#include "shadowlab/raster/resolve_params.h"
#include "shadowlab/scenes/loader.h"

namespace raster_psm_test {

using namespace shadowlab;
using namespace shadowlab::raster;

namespace {

// A camera 5 up looking along -z (slightly down) over a box of ground and clutter.
Camera testCamera() {
  Camera c;
  c.position = {0, 5, 10};
  c.lookAt = {0, 3, -20};
  c.up = {0, 1, 0};
  c.vfovDeg = 50;
  c.width = 320;
  c.height = 180;
  c.nearPlane = 0.1f;
  c.farPlane = 200;
  return c;
}
const glm::vec3 kBoxMin(-20, 0, -80), kBoxMax(20, 4, 20);

// The caster body as light_space.cpp builds it: the visible vertices and the same moved towards the
// light to where the light's ray through the farthest one leaves the box.
std::vector<glm::dvec3> castersOf(const std::vector<glm::dvec3>& visible, glm::dvec3 towardLight) {
  double reach = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 3; ++i) {
    if (towardLight[i] == 0.0) continue;
    double face = towardLight[i] > 0.0 ? kBoxMax[i] : kBoxMin[i], largest = 0;
    for (const glm::dvec3& p : visible) largest = std::max(largest, (face - p[i]) / towardLight[i]);
    reach = std::min(reach, largest);
  }
  std::vector<glm::dvec3> out;
  for (const glm::dvec3& p : visible) {
    out.push_back(p);
    out.push_back(p + reach * towardLight);
  }
  return out;
}

glm::dvec4 texAt(const glm::dmat4& m, glm::dvec3 p) {
  glm::dvec4 t = m * glm::dvec4(p, 1.0);
  return {t.x / t.w, t.y / t.w, t.z / t.w, t.w};
}

// A deterministic point of the body's hull: a random convex combination of its vertices.
glm::dvec3 mixOf(const std::vector<glm::dvec3>& v, uint32_t& state) {
  glm::dvec3 sum(0.0);
  double total = 0;
  for (const glm::dvec3& p : v) {
    state = state * 1664525u + 1013904223u;
    double k = double(state >> 8) / double(1u << 24);
    k = k * k * k * k;  // a few vertices dominate: points spread over the hull, not at its center
    sum += k * p;
    total += k;
  }
  return sum / total;
}

struct Case {
  const char* name;
  glm::dvec3 towardLight;
  PsmLight light;
};
// The camera looks along -z: a light towards -z is ahead of the viewer, towards +z behind it.
const Case kCases[] = {
    {"ahead_high", {0.4, 0.6, -0.7}, PsmLight::Source}, {"ahead_low", {-0.2, 0.15, -1.0}, PsmLight::Source},
    {"behind_high", {0.3, 0.8, 0.5}, PsmLight::Sink},   {"behind_low", {-0.5, 0.25, 1.0}, PsmLight::Sink},
    {"overhead", {0.1, 1.0, 0.02}, PsmLight::Sink},
};

}  // namespace

TEST(RasterPsm, VirtualCameraSlidesBackUntilEveryCasterIsAsFarAsTheNearestVisiblePoint) {
  Camera c = testCamera();
  glm::dvec3 eye(c.position), forward = glm::normalize(glm::dvec3(c.lookAt) - eye);
  // Casters from 3 behind the camera: slide zNear - zCasterMin = 2 - (-3) = 5, near = 2.
  PsmCamera v = psmVirtualCamera(c, 2.0, 50.0, -3.0, 60.0, 0.0);
  EXPECT_DOUBLE_EQ(v.slide, 5.0);
  EXPECT_DOUBLE_EQ(v.nearView, 2.0);
  EXPECT_DOUBLE_EQ(v.farView, 65.0);
  // psm.slide_back adds its share of the visible depth range (48): 5 + 0.5 * 48.
  PsmCamera w = psmVirtualCamera(c, 2.0, 50.0, -3.0, 60.0, 0.5);
  EXPECT_DOUBLE_EQ(w.slide, 29.0);
  EXPECT_DOUBLE_EQ(w.nearView, 26.0);
  // Casters no nearer than the visible body: the real camera, the paper's PSM.
  EXPECT_DOUBLE_EQ(psmVirtualCamera(c, 2.0, 50.0, 2.0, 50.0, 0.0).slide, 0.0);
  // The projection: clip w is the view depth from the virtual camera; z runs -1..1 over near..far.
  for (double depth : {-3.0, 10.0, 60.0}) {
    glm::dvec4 clip = v.clipFromWorld * glm::dvec4(eye + depth * forward, 1.0);
    EXPECT_NEAR(clip.w, depth + 5.0, 1e-9);
  }
  glm::dvec4 nearPoint = v.clipFromWorld * glm::dvec4(eye + (2.0 - 5.0) * forward, 1.0);
  glm::dvec4 farPoint = v.clipFromWorld * glm::dvec4(eye + (65.0 - 5.0) * forward, 1.0);
  EXPECT_NEAR(nearPoint.z / nearPoint.w, -1.0, 1e-9);
  EXPECT_NEAR(farPoint.z / farPoint.w, 1.0, 1e-9);
}

// The light in post-perspective space: C = clipFromWorld (towardLight, 0), C.w = the light's
// component along the view direction. Ahead: a source; behind: the inverted sink; across: directional.
TEST(RasterPsm, TheLightsKindFollowsTheSignOfItsW) {
  Camera c = testCamera();
  c.lookAt = {0, 5, -20};  // exactly horizontal: a light along +y is perpendicular to the view
  std::vector<glm::dvec3> visible = viewBoxIntersection(c, kBoxMin, kBoxMax);
  ASSERT_GE(visible.size(), 4u);
  for (auto [toward, kind] : {std::pair<glm::dvec3, PsmLight>{{0.3, 0.7, -0.6}, PsmLight::Source},
                              {{0.3, 0.7, 0.6}, PsmLight::Sink},
                              {{0.3, 0.7, 0.0}, PsmLight::Directional}}) {
    PsmFit f = psmFit(c, toward, visible, castersOf(visible, glm::normalize(toward)), 0.0, 1024);
    ASSERT_TRUE(f.ok) << toString(kind);
    EXPECT_EQ(f.light, kind) << toString(kind);
    glm::dvec4 C = f.camera.clipFromWorld * glm::dvec4(glm::normalize(toward), 0.0);
    EXPECT_NEAR(C.w, -glm::normalize(toward).z, 1e-12) << "C.w is minus the view-space z of the light";
  }
}

// The contract of light_space.h over the body, for lights ahead (source), behind (inverted sink)
// and overhead: every visible point maps into [0, 1]^3 with w > 0, every caster to a depth in
// [0, 1] with w > 0; along each light ray u, v stay put and depth falls towards the light.
TEST(RasterPsm, BodyInTheUnitCubeAndDepthOrderAlongLightRays) {
  Camera c = testCamera();
  std::vector<glm::dvec3> visible = viewBoxIntersection(c, kBoxMin, kBoxMax);
  ASSERT_GE(visible.size(), 4u);
  const double eps = 1e-9;
  for (const Case& k : kCases) {
    glm::dvec3 l = glm::normalize(k.towardLight);
    std::vector<glm::dvec3> casters = castersOf(visible, l);
    PsmFit f = psmFit(c, l, visible, casters, 0.0, 1024);
    ASSERT_TRUE(f.ok) << k.name;
    EXPECT_EQ(f.light, k.light) << k.name;
    EXPECT_GT(f.texels.warp, 0.1) << k.name << ": a real warp";
    EXPECT_GT(f.texels.texelWorldPerW, 0.0) << k.name;
    for (const glm::dvec3& p : casters) {
      glm::dvec4 t = texAt(f.texFromWorld, p);
      ASSERT_GT(t.w, 0.0) << k.name;
      EXPECT_GE(t.z, -eps) << k.name;
      EXPECT_LE(t.z, 1.0 + eps) << k.name;
    }
    uint32_t state = 7;
    for (int i = 0; i < 400; ++i) {
      glm::dvec3 p = i < int(visible.size()) ? visible[size_t(i)] : mixOf(visible, state);
      glm::dvec4 t = texAt(f.texFromWorld, p);
      ASSERT_GT(t.w, 0.0) << k.name;
      for (int a = 0; a < 3; ++a) {
        EXPECT_GE(t[a], -eps) << k.name << " axis " << a;
        EXPECT_LE(t[a], 1.0 + eps) << k.name << " axis " << a;
      }
      // Towards the light, inside the box: u, v the same (one light ray, one texel), depth falling.
      double previous = t.z;
      for (double s = 0.5; s <= 6.0; s += 0.5) {
        glm::dvec3 q = p + s * l;
        if (glm::any(glm::lessThan(q, glm::dvec3(kBoxMin))) || glm::any(glm::greaterThan(q, glm::dvec3(kBoxMax))))
          break;
        glm::dvec4 tq = texAt(f.texFromWorld, q);
        ASSERT_GT(tq.w, 0.0) << k.name;
        EXPECT_NEAR(tq.x, t.x, 1e-9) << k.name;
        EXPECT_NEAR(tq.y, t.y, 1e-9) << k.name;
        EXPECT_LT(tq.z, previous) << k.name << ": depth must fall towards the light";
        EXPECT_GE(tq.z, -eps) << k.name;
        previous = tq.z;
      }
    }
  }
}

// Casters behind the camera (the light behind and high: its rays from the box's top pass over the
// camera): the virtual camera slides back until the nearest lies zNear in front of it, and w stays
// positive on them. Without the slide their w would be negative: clipped away, no shadow.
TEST(RasterPsm, CastersBehindTheViewerSlideTheVirtualCameraBack) {
  Camera c = testCamera();
  std::vector<glm::dvec3> visible = viewBoxIntersection(c, kBoxMin, kBoxMax);
  glm::dvec3 l = glm::normalize(glm::dvec3(0.0, 0.5, 1.0));
  std::vector<glm::dvec3> casters = castersOf(visible, l);
  glm::dvec3 eye(c.position), forward = glm::normalize(glm::dvec3(c.lookAt) - eye);
  double zNear = std::numeric_limits<double>::infinity(), zCasterMin = zNear;
  for (const glm::dvec3& p : visible) zNear = std::min(zNear, glm::dot(p - eye, forward));
  for (const glm::dvec3& p : casters) zCasterMin = std::min(zCasterMin, glm::dot(p - eye, forward));
  ASSERT_LT(zCasterMin, 0.0) << "the test needs casters behind the camera";
  PsmFit f = psmFit(c, l, visible, casters, 0.0, 1024);
  ASSERT_TRUE(f.ok);
  EXPECT_EQ(f.light, PsmLight::Sink);
  EXPECT_NEAR(f.camera.slide, zNear - zCasterMin, 1e-9);
  EXPECT_NEAR(f.camera.nearView, zNear, 1e-9);
  for (const glm::dvec3& p : casters) EXPECT_GT(texAt(f.texFromWorld, p).w, 0.0);
  // psm.slide_back moves it further and weakens the warp.
  PsmFit weaker = psmFit(c, l, visible, casters, 1.0, 1024);
  ASSERT_TRUE(weaker.ok);
  EXPECT_GT(weaker.camera.slide, f.camera.slide);
  EXPECT_LT(weaker.texels.warp, 0.5 * f.texels.warp);
}

// psmTexels on maps with closed forms: an orthographic map has warp 0 and texel side / map size;
// LiSPSM's map has warp d / n exactly (its 2D denominator 1 + (y - y0) / n enters det J cubed).
TEST(RasterPsm, TexelMeasureMatchesTheClosedForms) {
  glm::dvec3 bodyMin(-2, 1, -4), bodyMax(3, 5, 6);  // light space: the light looks down -z
  std::vector<glm::dvec3> corners;
  for (int i = 0; i < 8; ++i)
    corners.push_back(
        {(i & 1) ? bodyMax.x : bodyMin.x, (i & 2) ? bodyMax.y : bodyMin.y, (i & 4) ? bodyMax.z : bodyMin.z});
  glm::dvec3 towardLight(0, 0, 1);
  LispsmMap ortho = lispsmTexFromLight(bodyMin, bodyMax, 0.5, 0.0, 1000);
  PsmTexels t = psmTexels(ortho.texFromLight, towardLight, corners, 1000);
  EXPECT_NEAR(t.warp, 0.0, 1e-12);
  EXPECT_NEAR(t.texelWorldPerW, 5.0 / 1000.0, 1e-12);  // the larger side (x: 5) / map size
  double n = 2.0, d = 4.0;
  LispsmMap warped = lispsmTexFromLight(bodyMin, bodyMax, 0.5, 1.0 / n, 1000);
  EXPECT_NEAR(psmTexels(warped.texFromLight, towardLight, corners, 1000).warp, d / n, 1e-9);
}

// The view exactly along the light, either way: in post-perspective space the light sits on the
// view axis and its rays stay parallel to it, the map is orthographic (warp 0): the fit falls
// back to fit=tight's matrix, as fit=lispsm does. Any other view warps.
TEST(RasterPsm, ViewAlongTheLightFallsBackToTightsMatrix) {
  Scene s = loadScene(resolveScenePath("long_view"));
  glm::vec3 forward = glm::normalize(s.camera.lookAt - s.camera.position);
  Method tight, psm;
  tight.fit = Fit::Tight;
  psm.fit = Fit::Psm;
  glm::vec3 side = glm::normalize(glm::cross(forward, glm::vec3(0, 1, 0)));
  // Exactly along (sign 1: the light behind the viewer, its rays travelling with the view; -1:
  // against it), and 2 degrees off behind it: there the slide-back (220, the casters reach the
  // box's far end) leaves the light a hair beyond the far plane in PPS, no cone from it holds the
  // body, and the map is the orthographic one too.
  for (glm::vec3 dir : {forward, -forward, glm::normalize(forward + 0.035f * side)}) {
    s.lights[0].direction = dir;
    FrameLayers a = fitFrameLayers(s, &s.lights[0], tight, s.camera);
    FrameLayers b = fitFrameLayers(s, &s.lights[0], psm, s.camera);
    ASSERT_EQ(b.layers.size(), 1u);
    EXPECT_EQ(a.layers[0].texFromWorld, b.layers[0].texFromWorld) << dir.x << " " << dir.z;
    EXPECT_EQ(a.layers[0].texelWorldPerW, b.layers[0].texelWorldPerW) << dir.x << " " << dir.z;
  }
  // 5 degrees off (either way) and the bundled sun: a warped, projective layer.
  Scene bundled = loadScene(resolveScenePath("long_view"));
  for (glm::vec3 dir : {glm::normalize(forward + 0.087f * side), glm::normalize(-forward + 0.087f * side),
                        bundled.lights[0].direction}) {
    s.lights[0].direction = dir;
    glm::mat4 a = fitFrameLayers(s, &s.lights[0], tight, s.camera).layers[0].texFromWorld;
    glm::mat4 b = fitFrameLayers(s, &s.lights[0], psm, s.camera).layers[0].texFromWorld;
    EXPECT_NE(a, b);
    EXPECT_NE(b[0][3], 0.0f);  // a projective w row: not an orthographic box
  }
}

// On the bundled scenes with a directional light, the visible body's points lie in the map's unit
// cube: every view-frustum vertex of every object's box. Scenes whose light is not directional fit
// as before (fit=psm does not apply).
TEST(RasterPsm, BundledScenesVisibleBodyInsideTheMap) {
  Method psm;
  psm.fit = Fit::Psm;
  psm.mapSize = 1024;
  int checked = 0;
  for (const std::string& name : bundledSceneNames()) {
    Scene s = loadScene(resolveScenePath(name));
    if (s.lights.empty() || s.lights[0].type != LightType::Directional) continue;
    glm::mat4 m = fitFrameLayers(s, &s.lights[0], psm, s.camera).layers[0].texFromWorld;
    for (const Object& o : s.objects) {
      if (o.positions.empty()) continue;
      glm::vec3 lo = o.positions.front(), hi = lo;
      for (const glm::vec3& p : o.positions) lo = glm::min(lo, p), hi = glm::max(hi, p);
      for (const glm::dvec3& p : viewBoxIntersection(s.camera, lo, hi)) {
        glm::vec4 t = m * glm::vec4(glm::vec3(p), 1.0f);
        ASSERT_GT(t.w, 0.0f) << name;
        glm::vec3 uvz = glm::vec3(t) / t.w;
        for (int a = 0; a < 3; ++a) {
          EXPECT_GE(uvz[a], -1e-4f) << name << " " << o.name << " axis " << a;
          EXPECT_LE(uvz[a], 1.0f + 1e-4f) << name << " " << o.name << " axis " << a;
        }
      }
    }
    ++checked;
  }
  EXPECT_GE(checked, 6);
}

}  // namespace raster_psm_test
