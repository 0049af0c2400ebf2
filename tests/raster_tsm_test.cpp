// fit=tsm's pieces without a GPU (Martin & Tan 2004): the 80 % rule's eta, N_T (the trapezoid's
// corners onto the square's), the trapezoid around the projected body, the focus point on the
// 0.8 line, depth order along light rays, and the fallback to fit=tight's exact matrix.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "shadowlab/raster/lispsm.h"
#include "shadowlab/raster/resolve_params.h"
#include "shadowlab/raster/tsm.h"
#include "support/quad.h"

namespace raster_tsm_test {

using namespace shadowlab;
using namespace shadowlab::raster;

namespace {

// (u, v, depth, w) of a light-space point.
glm::dvec4 texAt(const TsmMap& map, glm::dvec3 p) {
  glm::dvec4 t = map.texFromLight * glm::dvec4(p, 1.0);
  return {t.x / t.w, t.y / t.w, t.z / t.w, t.w};
}

double cross2(glm::dvec2 a, glm::dvec2 b) { return a.x * b.y - a.y * b.x; }

// A view frustum's projection onto a light's image plane: a camera at the origin of the light
// view space looking along `forward`, its body [zNear, zFar] deep, the 8 corners in light space.
struct Projected {
  std::vector<glm::dvec3> hull;
  glm::dvec2 nearCenter, farCenter;
  glm::dvec3 eye, forward;
  double zNear, zFar;
};
Projected frustumInLight(glm::dvec3 eye, glm::dvec3 forward, double zNear, double zFar, double tanHalf) {
  Projected p{{}, {}, {}, eye, glm::normalize(forward), zNear, zFar};
  glm::dvec3 f = p.forward;
  glm::dvec3 right = glm::normalize(glm::cross(f, std::abs(f.y) < 0.9 ? glm::dvec3(0, 1, 0) : glm::dvec3(1, 0, 0)));
  glm::dvec3 up = glm::cross(right, f);
  for (double z : {zNear, zFar})
    for (double sx : {-1.0, 1.0})
      for (double sy : {-1.0, 1.0}) p.hull.push_back(eye + f * z + (right * sx + up * sy) * (z * tanHalf));
  p.nearCenter = glm::dvec2(eye + f * zNear);
  p.farCenter = glm::dvec2(eye + f * zFar);
  return p;
}

}  // namespace

// eta of the 80 % rule: the closed form, and the point at deltaPrime on the 1D perspective
// y(s) = a - b / s (y(eta) = +1, y(eta + lambda) = -1) lands on xi = 1 - 2 focusLine.
TEST(RasterTsm, EtaIsTheEightyPercentRule) {
  // lambda 10, deltaPrime 2, xi = -0.6: eta = 10 * 2 * 0.4 / (10 * 1.6 - 4) = 8 / 12.
  EXPECT_NEAR(tsmEta(10.0, 2.0, 0.8), 8.0 / 12.0, 1e-15);
  for (double lambda : {1.0, 10.0, 300.0})
    for (double share : {0.01, 0.2, 0.5, 0.79})
      for (double focusLine : {0.8, 0.6, 0.95}) {
        if (share >= focusLine) continue;
        double deltaPrime = share * lambda, eta = tsmEta(lambda, deltaPrime, focusLine);
        ASSERT_TRUE(eta > 0.0 && std::isfinite(eta));
        double b = -2.0 * eta * (eta + lambda) / lambda, a = 1.0 + b / eta;
        EXPECT_NEAR(a - b / (eta + lambda), -1.0, 1e-12);
        EXPECT_NEAR(a - b / (eta + deltaPrime), 1.0 - 2.0 * focusLine, 1e-12) << lambda << " " << share;
      }
  // No eta: the focus region already has the share in the uniform map (or bad input); q on the
  // top line for an empty focus region.
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_EQ(tsmEta(10.0, 8.0, 0.8), inf);
  EXPECT_EQ(tsmEta(10.0, 9.0, 0.8), inf);
  EXPECT_EQ(tsmEta(0.0, 1.0, 0.8), inf);
  EXPECT_EQ(tsmEta(10.0, 1.0, 1.0), inf);
  EXPECT_EQ(tsmEta(10.0, std::nan(""), 0.8), inf);
  EXPECT_EQ(tsmEta(10.0, 0.0, 0.8), 0.0);
}

// N_T maps any trapezoid's corners onto the square's: t0 (-1,-1), t1 (1,-1), t2 (1,1), t3 (-1,1),
// whatever its orientation, position and asymmetry, with w > 0 over it.
TEST(RasterTsm, TrapezoidToSquareMapsTheCorners) {
  const glm::dvec2 square[4] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
  for (double angle : {0.0, 0.7, 2.5, -1.9})
    for (double skew : {0.0, 0.8, -2.0}) {
      // In a local frame: the top (half width 1) at s = 2, the base (half width 4) at s = 8,
      // shifted sideways by skew * s: the sides meet at the origin.
      glm::dvec2 ex(std::cos(angle), std::sin(angle)), es(-ex.y, ex.x), origin(3.0, -5.0);
      auto at = [&](double x, double s) { return origin + ex * (x + skew * s) + es * s; };
      std::array<glm::dvec2, 4> t = {at(-4, 8), at(4, 8), at(1, 2), at(-1, 2)};
      glm::dmat3 nt = tsmTrapezoidToSquare(t);
      for (int i = 0; i < 4; ++i) {
        glm::dvec3 h = nt * glm::dvec3(t[size_t(i)], 1.0);
        ASSERT_GT(h.z, 0.0);
        EXPECT_NEAR(h.x / h.z, square[i].x, 1e-12) << angle << " " << skew << " corner " << i;
        EXPECT_NEAR(h.y / h.z, square[i].y, 1e-12) << angle << " " << skew << " corner " << i;
      }
      // w = 1 on the top, 4 on the base (s / eta); the top-center goes to (0, 1).
      EXPECT_NEAR((nt * glm::dvec3(t[2], 1.0)).z, 1.0, 1e-12);
      EXPECT_NEAR((nt * glm::dvec3(t[0], 1.0)).z, 4.0, 1e-12);
      glm::dvec3 c = nt * glm::dvec3(at(0, 2), 1.0);
      EXPECT_NEAR(c.x / c.z, 0.0, 1e-12);
    }
}

// The fit on projected frustums under several light directions: the trapezoid holds every
// vertex of the projected body (inside its four edges and inside [0,1]^2 of the map), N_T sends
// its corners to the map's corners, the focus point lands on the 0.8 line (to float precision),
// and depth is monotonic along light rays with w constant along them.
TEST(RasterTsm, TrapezoidHoldsTheHullAndTheFocusPointLandsOnTheFocusLine) {
  struct Case {
    glm::dvec3 forward;
    double focusShare, focusLine;
  } cases[] = {{{0, 1, -0.3}, 0.5, 0.8},   {{1, 0.2, -0.6}, 0.2, 0.8}, {{-0.3, -1, 0.4}, 0.1, 0.8},
               {{0.5, 0.5, -2}, 0.3, 0.8}, {{0, 1, 0}, 0.05, 0.6},     {{0.2, -1, 0.1}, 0.4, 0.9}};
  for (const Case& c : cases) {
    Projected p = frustumInLight({1, 2, 3}, c.forward, 0.5, 60.0, std::tan(0.5 * glm::radians(50.0)));
    glm::dvec3 focus3 = p.eye + p.forward * (p.zNear + c.focusShare * (p.zFar - p.zNear));
    TsmMap map = tsmFit(p.hull, p.nearCenter, p.farCenter, glm::dvec2(focus3), c.focusLine, -40.0, 40.0, 1024);
    ASSERT_TRUE(map.valid);
    ASSERT_GT(map.eta, 0.0);
    // Contained: each vertex on the inner side of every edge, and inside the map.
    const auto& t = map.trapezoid;
    double orientation = cross2(t[1] - t[0], t[2] - t[1]);
    for (const glm::dvec3& v : p.hull) {
      for (int i = 0; i < 4; ++i) {
        glm::dvec2 a = t[size_t(i)], b = t[size_t((i + 1) % 4)];
        EXPECT_GT(cross2(b - a, glm::dvec2(v) - a) * orientation, 0.0) << "edge " << i;
      }
      glm::dvec4 uvdw = texAt(map, v);
      EXPECT_GT(uvdw.w, 0.0);
      EXPECT_GE(uvdw.x, 0.0);
      EXPECT_LE(uvdw.x, 1.0);
      EXPECT_GE(uvdw.y, 0.0);
      EXPECT_LE(uvdw.y, 1.0);
    }
    // The corners go to the map's corners: t0 (0, 1), t1 (1, 1), t2 (1, 0), t3 (0, 0) in (u, v).
    const glm::dvec2 uv[4] = {{0, 1}, {1, 1}, {1, 0}, {0, 0}};
    for (int i = 0; i < 4; ++i) {
      glm::dvec4 m = texAt(map, glm::dvec3(t[size_t(i)], 0.0));
      EXPECT_NEAR(m.x, uv[i].x, 1e-9);
      EXPECT_NEAR(m.y, uv[i].y, 1e-9);
    }
    // The 80 % rule: the focus point on the line v = focusLine, to float precision.
    glm::dvec4 f = texAt(map, focus3);
    EXPECT_NEAR(f.y, c.focusLine, 1e-6) << c.forward.x << " " << c.forward.y << " " << c.forward.z;
    EXPECT_EQ(float(f.y), float(c.focusLine));
    // The near center on the top side of it, the far center below it.
    EXPECT_LT(texAt(map, glm::dvec3(p.nearCenter, 0.0)).y, c.focusLine);
    EXPECT_GT(texAt(map, glm::dvec3(p.farCenter, 0.0)).y, c.focusLine);
    // Along a light ray (x, y fixed, z towards the light): w constant, depth falling as z rises
    // (nearer the light), in [0, 1] over the depth range; the unwarped depth is the light's own.
    for (const glm::dvec3& v : p.hull) {
      glm::dvec4 lo = texAt(map, {v.x, v.y, -40.0}), mid = texAt(map, {v.x, v.y, 5.0}),
                 hi = texAt(map, {v.x, v.y, 40.0});
      EXPECT_DOUBLE_EQ(lo.w, hi.w);
      EXPECT_GT(lo.z, mid.z);
      EXPECT_GT(mid.z, hi.z);
      EXPECT_LE(lo.z, 1.0 + 1e-12);
      EXPECT_GE(hi.z, -1e-12);
      EXPECT_NEAR(glm::dot(map.depthFromLight, glm::dvec4(v.x, v.y, 5.0, 1.0)), 35.0 / 80.0, 1e-12);
    }
    // texelWorldPerW bounds the texel at the base's center: across, the base's width / size over w.
    glm::dvec4 base = texAt(map, glm::dvec3(0.5 * (t[0] + t[1]), 0.0));
    EXPECT_GE(map.texelWorldPerW * base.w * 1024.0, glm::length(t[1] - t[0]) * (1.0 - 1e-9));
  }
}

// No center line (the view along the light: near and far centers project to one point), and no
// eta (the focus region already past the 0.8 line): invalid, the caller falls back.
TEST(RasterTsm, DegenerateViewsAreInvalid) {
  Projected along = frustumInLight({0, 0, 0}, {0, 0, -1}, 0.5, 60.0, 0.5);
  EXPECT_FALSE(tsmFit(along.hull, along.nearCenter, along.farCenter, along.nearCenter, 0.8, -1, 1, 64).valid);
  Projected p = frustumInLight({0, 0, 0}, {0, 1, -0.3}, 0.5, 60.0, 0.5);
  EXPECT_FALSE(tsmFit(p.hull, p.nearCenter, p.farCenter, p.farCenter, 0.8, -1, 1, 64).valid);
  EXPECT_FALSE(tsmFit({}, p.nearCenter, p.farCenter, p.nearCenter, 0.8, -1, 1, 64).valid);
}

namespace {

Scene groundScene(glm::vec3 cameraPosition, glm::vec3 lookAt, glm::vec3 lightDirection) {
  Scene s;
  s.name = "ground";
  s.materials.push_back(Material{});
  shadowlab::testing::addQuad(s, 1, {-10, 0, 10}, {20, 0, 0}, {0, 0, -20});
  shadowlab::testing::addQuad(s, 2, {-1, 2, 1}, {2, 0, 0}, {0, 0, -2});
  s.camera.position = cameraPosition;
  s.camera.lookAt = lookAt;
  s.camera.up = {0, 0, -1};
  s.camera.width = 160;
  s.camera.height = 90;
  s.camera.vfovDeg = 50;
  Light sun;
  sun.name = "sun";
  sun.direction = lightDirection;
  s.lights.push_back(sun);
  return s;
}

}  // namespace

// The view exactly along (or against) the light: fit=tsm is fit=tight, the same matrix bit for
// bit, as fit=lispsm's fallback; a view across the light gets its own perspective layer.
TEST(RasterTsm, ViewAlongTheLightFallsBackToTightsMatrix) {
  Method tight, tsm, lispsm;
  tight.fit = Fit::Tight;
  tsm.fit = Fit::Tsm;
  lispsm.fit = Fit::Lispsm;
  for (glm::vec3 light : {glm::vec3(0, -1, 0), glm::vec3(0, 1, 0)}) {
    Scene s = groundScene({0.5f, 12, 0.25f}, {0.5f, 0, 0.25f}, light);
    FrameLayers a = fitFrameLayers(s, &s.lights[0], tight, s.camera);
    FrameLayers b = fitFrameLayers(s, &s.lights[0], tsm, s.camera);
    FrameLayers c = fitFrameLayers(s, &s.lights[0], lispsm, s.camera);
    ASSERT_EQ(a.layers.size(), 1u);
    ASSERT_EQ(b.layers.size(), 1u);
    EXPECT_EQ(a.layers[0].texFromWorld, b.layers[0].texFromWorld);
    EXPECT_EQ(a.layers[0].texelWorldPerW, b.layers[0].texelWorldPerW);
    EXPECT_EQ(c.layers[0].texFromWorld, b.layers[0].texFromWorld);  // as lispsm falls back
  }
  // Across the light: a projective layer (w varies), not tight's.
  Scene s = groundScene({0, 3, 9}, {0, 0, -5}, {0.3f, -1, 0.2f});
  FrameLayers a = fitFrameLayers(s, &s.lights[0], tight, s.camera);
  FrameLayers b = fitFrameLayers(s, &s.lights[0], tsm, s.camera);
  EXPECT_NE(a.layers[0].texFromWorld, b.layers[0].texFromWorld);
  EXPECT_NE(b.layers[0].texFromWorld[0][3], 0.0f);
  // Its depth is the light's own: tight's (affine, w = 1) depth row, the same light-space z range.
  ASSERT_TRUE(b.layers[0].lightDepth);
  EXPECT_FALSE(a.layers[0].lightDepth);
  const glm::mat4& t = a.layers[0].texFromWorld;
  for (int c = 0; c < 4; ++c) EXPECT_NEAR(b.layers[0].depthFromWorld[c], t[c][2], 1e-6) << c;
  EXPECT_EQ(resolveSpecialization(s, &s.lights[0], tsm, b)[raster::abi::kSpecLightDepth], 1u);
  EXPECT_EQ(resolveSpecialization(s, &s.lights[0], tight, a)[raster::abi::kSpecLightDepth], 0u);
  EXPECT_EQ(packResolveParams(s, &s.lights[0], tsm, s.camera, b, {}).lightDepth, b.layers[0].depthFromWorld);
}

}  // namespace raster_tsm_test
