// fit=lispsm's pieces without a GPU: the optimal n of Wimmer et al., the basis rotated onto the
// view direction, the body (frustum n box), and the warped map's closed forms (unit cube over the body, w constant
// along light rays, texel sizes, the orthographic limit).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "shadowlab/raster/lispsm.h"

namespace raster_lispsm_test {

using namespace shadowlab::raster;

namespace {

// (u, v, depth, w) of a light-space point.
glm::dvec4 texAt(const LispsmMap& map, glm::dvec3 p) {
  glm::dvec4 t = map.texFromLight * glm::dvec4(p, 1.0);
  return {t.x / t.w, t.y / t.w, t.z / t.w, t.w};
}

bool allFinite(const glm::dmat4& m) {
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r)
      if (!std::isfinite(m[c][r])) return false;
  return true;
}

const glm::dvec3 kBodyMin(-2, 1, -4), kBodyMax(3, 5, 6);  // Wx 5, d 4, h 10

}  // namespace

TEST(RasterLispsm, InverseNearIsTheOptimalNOfWimmerEtAl) {
  // z_n 1, z_f 100, gamma 30 degrees: n_opt = (1 + sqrt(100)) / 0.5 = 22.
  EXPECT_NEAR(lispsmInverseNear(1.0, 100.0, 0.5, 1.0), 1.0 / 22.0, 1e-15);
  EXPECT_NEAR(lispsmInverseNear(1.0, 100.0, 0.5, 2.0), 1.0 / 44.0, 1e-15);
  // View perpendicular to the light: n_opt = z_n + sqrt(z_n z_f) = 0.1 + sqrt(0.1 * 250) = 5.1.
  EXPECT_NEAR(lispsmInverseNear(0.1, 250.0, 1.0, 1.0), 1.0 / 5.1, 1e-14);
  // Along the light: n infinite, no warp. Degenerate input never gives a NaN.
  EXPECT_EQ(lispsmInverseNear(1.0, 100.0, 0.0, 1.0), 0.0);
  EXPECT_EQ(lispsmInverseNear(1.0, 100.0, -0.1, 1.0), 0.0);
  EXPECT_EQ(lispsmInverseNear(1.0, 100.0, 0.5, 0.0), 0.0);
  EXPECT_EQ(lispsmInverseNear(std::nan(""), 100.0, 0.5, 1.0), 0.0);
  EXPECT_EQ(lispsmInverseNear(1.0, 100.0, std::nan(""), 1.0), 0.0);
  double tiny = lispsmInverseNear(1.0, 100.0, 1e-300, 1.0);
  EXPECT_TRUE(std::isfinite(tiny) && tiny >= 0.0 && tiny < 1e-290) << tiny;
}

TEST(RasterLispsm, BasisTurnsTheViewDirectionOntoPlusY) {
  // The light travels straight down; the view direction 30 degrees below the horizon, towards
  // (1, 0, 1): gamma = 60 degrees between them, sin 60 = 0.866.
  glm::vec3 dir(0, -1, 0);
  glm::mat4 lightView = glm::lookAt(glm::vec3(0), dir, glm::vec3(0, 0, 1));
  glm::vec3 forward = glm::normalize(glm::vec3(std::cos(glm::radians(30.0f)) * glm::normalize(glm::vec3(1, 0, 1)) +
                                               glm::vec3(0, -std::sin(glm::radians(30.0f)), 0)));
  LispsmBasis b = lispsmBasis(lightView, forward);
  EXPECT_NEAR(b.sinGamma, std::sqrt(3.0) / 2.0, 1e-6);
  glm::dvec3 f = glm::dmat3(b.lightFromWorld) * glm::dvec3(forward);
  EXPECT_NEAR(f.x, 0.0, 1e-7);
  EXPECT_NEAR(f.y, b.sinGamma, 1e-7);
  EXPECT_NEAR(f.z, -0.5, 1e-6);  // cos 60, along the light's travel (-z)
  // Still a rotation about the light: the light direction maps to -z as before, and it is rigid.
  glm::dvec3 l = glm::dmat3(b.lightFromWorld) * glm::dvec3(dir);
  EXPECT_NEAR(l.z, -1.0, 1e-7);
  EXPECT_NEAR(glm::determinant(glm::dmat3(b.lightFromWorld)), 1.0, 1e-6);
  // Exactly along the light, and against it: no axis, sinGamma 0, the light's own view.
  for (glm::vec3 along : {dir, -dir}) {
    LispsmBasis p = lispsmBasis(lightView, along);
    EXPECT_EQ(p.sinGamma, 0.0);
    EXPECT_EQ(p.lightFromWorld, glm::dmat4(lightView));
  }
  // A view from behind the light (against it, tilted) has the same sin(gamma) as one with it.
  EXPECT_NEAR(lispsmBasis(lightView, -forward).sinGamma, b.sinGamma, 1e-7);
}

TEST(RasterLispsm, ZeroWarpIsTheTightOrthographicFit) {
  // rho = 0: u = (x + 2) / 5, v = (5 - y) / 4, depth = (6 - z) / 10, w = 1: fit=tight's box fit
  // (texFromViewOrtho with the light looking down -z: depth grows away from the light).
  LispsmMap map = lispsmTexFromLight(kBodyMin, kBodyMax, 0.7, 0.0, 1000);
  for (glm::dvec3 p : {glm::dvec3(-2, 1, -4), glm::dvec3(3, 5, 6), glm::dvec3(0.5, 2.5, 1), glm::dvec3(9, -3, 20)}) {
    glm::dvec4 t = texAt(map, p);
    EXPECT_NEAR(t.x, (p.x + 2.0) / 5.0, 1e-14);
    EXPECT_NEAR(t.y, (5.0 - p.y) / 4.0, 1e-14);
    EXPECT_NEAR(t.z, (6.0 - p.z) / 10.0, 1e-14);
    EXPECT_EQ(t.w, 1.0);
  }
  EXPECT_DOUBLE_EQ(map.texelWorldPerW, 5.0 / 1000.0);  // the larger side / map size
}

TEST(RasterLispsm, WarpKeepsTheBodyInTheUnitCubeAndDepthOrderAlongLightRays) {
  const double rho = 2.0;                  // n = 0.5 before a body 4 deep: w from 1 to 9
  for (double eyeX : {0.7, -2.0, 10.0}) {  // the eye above the body, on its edge, far beside it
    LispsmMap map = lispsmTexFromLight(kBodyMin, kBodyMax, eyeX, rho, 512);
    ASSERT_TRUE(allFinite(map.texFromLight));
    glm::dvec3 lo(1e9), hi(-1e9);
    for (int i = 0; i < 8; ++i) {
      glm::dvec3 c((i & 1) ? kBodyMax.x : kBodyMin.x, (i & 2) ? kBodyMax.y : kBodyMin.y,
                   (i & 4) ? kBodyMax.z : kBodyMin.z);
      glm::dvec4 t = texAt(map, c);
      EXPECT_NEAR(t.w, 1.0 + rho * (c.y - kBodyMin.y), 1e-12);
      lo = glm::min(lo, glm::dvec3(t));
      hi = glm::max(hi, glm::dvec3(t));
    }
    // The corners span exactly [0, 1] in u, v and depth (linear-fractional: extremes at corners).
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(lo[k], 0.0, 1e-12) << "eyeX " << eyeX << " coordinate " << k;
      EXPECT_NEAR(hi[k], 1.0, 1e-12) << "eyeX " << eyeX << " coordinate " << k;
    }
    // Interior points stay inside; along a light ray (z varies) w, u and v stay, and depth
    // grows away from the light (towards -z), so the comparison's order is the world's.
    EXPECT_EQ(map.texFromLight[2][3], 0.0) << "w must not depend on z";
    for (double fx : {0.0, 0.3, 1.0})
      for (double fy : {0.0, 0.6, 1.0}) {
        glm::dvec3 p = kBodyMin + glm::dvec3(fx, fy, 0.0) * (kBodyMax - kBodyMin);
        double lastDepth = -1.0;
        glm::dvec4 top = texAt(map, glm::dvec3(p.x, p.y, kBodyMax.z));
        for (double z = kBodyMax.z; z >= kBodyMin.z; z -= 2.5) {
          glm::dvec4 t = texAt(map, glm::dvec3(p.x, p.y, z));
          EXPECT_EQ(t.w, top.w);
          EXPECT_NEAR(t.x, top.x, 1e-14);
          EXPECT_NEAR(t.y, top.y, 1e-14);
          EXPECT_GT(t.z, lastDepth);
          EXPECT_GE(t.z, -1e-12);
          EXPECT_LE(t.z, 1.0 + 1e-12);
          EXPECT_GE(t.x, -1e-12);
          EXPECT_LE(t.x, 1.0 + 1e-12);
          lastDepth = t.z;
        }
      }
    // Orientation as fit=tight's (u along x, v against y, depth against z: det > 0), so
    // cull=front/back keep their meaning in the warped map.
    glm::dvec3 p(0.4, 2.0, 1.0);
    const double e = 1e-6;
    glm::dvec3 t0(texAt(map, p));
    glm::dmat3 jac(glm::dvec3(texAt(map, p + glm::dvec3(e, 0, 0))) - t0,
                   glm::dvec3(texAt(map, p + glm::dvec3(0, e, 0))) - t0,
                   glm::dvec3(texAt(map, p + glm::dvec3(0, 0, e))) - t0);
    EXPECT_GT(glm::determinant(jac), 0.0);
  }
}

// Near texels get denser: along the axis a texel at w is d w^2 / ((1 + d/n) size) long, across it
// Wx w / size wide (eye above the body); texelWorldPerW * w bounds both and is exact on the far face.
TEST(RasterLispsm, TexelSizesFollowTheClosedForms) {
  const double rho = 2.0, d = 4.0, wx = 5.0;
  const int size = 512;
  LispsmMap map = lispsmTexFromLight(kBodyMin, kBodyMax, 0.7, rho, size);
  const double e = 1e-7;
  for (double fy : {0.0, 0.25, 0.5, 1.0}) {
    glm::dvec3 p(0.7, kBodyMin.y + fy * d, 0.0);  // on the eye's line: no shear in u
    double w = 1.0 + rho * (p.y - kBodyMin.y);
    glm::dvec4 t = texAt(map, p), tx = texAt(map, p + glm::dvec3(e, 0, 0)), ty = texAt(map, p + glm::dvec3(0, e, 0));
    double texelX = e / std::abs(tx.x - t.x) / size, texelY = e / std::abs(ty.y - t.y) / size;
    EXPECT_NEAR(texelX, wx * w / size, 1e-6 * texelX) << "fy " << fy;
    EXPECT_NEAR(texelY, d * w * w / ((1.0 + rho * d) * size), 1e-6 * texelY) << "fy " << fy;
    EXPECT_LE(std::max(texelX, texelY), map.texelWorldPerW * w * (1.0 + 1e-6)) << "fy " << fy;
  }
  EXPECT_DOUBLE_EQ(map.texelWorldPerW, std::max(wx, d) / size);
  // On the near face the texels along the axis are (1 + d/n) = 9 times shorter than fit=tight's
  // d / size, on the far face 9 times longer.
  glm::dvec4 a = texAt(map, glm::dvec3(0.7, kBodyMin.y, 0)), b = texAt(map, glm::dvec3(0.7, kBodyMin.y + e, 0));
  EXPECT_NEAR((e / std::abs(b.y - a.y)) / (d / 1.0), 1.0 / 9.0, 1e-6);
}

TEST(RasterLispsm, DegenerateBodiesStayFinite) {
  for (double rho : {0.0, 1e-12, 1.0, 1e12}) {
    LispsmMap flat = lispsmTexFromLight(glm::dvec3(1, 2, 3), glm::dvec3(1, 2, 3), 1.0, rho, 16);
    EXPECT_TRUE(allFinite(flat.texFromLight)) << rho;
    EXPECT_TRUE(std::isfinite(flat.texelWorldPerW) && flat.texelWorldPerW > 0.0) << rho;
    LispsmMap badEye = lispsmTexFromLight(kBodyMin, kBodyMax, std::nan(""), rho, 16);
    EXPECT_TRUE(allFinite(badEye.texFromLight)) << rho;
  }
  LispsmMap nanRho = lispsmTexFromLight(kBodyMin, kBodyMax, 0.0, std::nan(""), 16);
  EXPECT_EQ(nanRho.texFromLight, lispsmTexFromLight(kBodyMin, kBodyMax, 0.0, 0.0, 16).texFromLight);
}

namespace {

shadowlab::Camera squareCamera(glm::vec3 position, glm::vec3 lookAt) {
  shadowlab::Camera c;
  c.position = position;
  c.lookAt = lookAt;
  c.up = {0, 1, 0};
  c.vfovDeg = 90.0f;  // tan(45) = 1 both ways: the side planes are |x|, |y| <= depth
  c.width = c.height = 64;
  c.nearPlane = 0.1f;
  c.farPlane = 100.0f;
  return c;
}

// The view depth range of the body's vertices.
void depthRange(const std::vector<glm::dvec3>& v, const shadowlab::Camera& c, double& lo, double& hi) {
  glm::dvec3 forward = glm::normalize(glm::dvec3(c.lookAt) - glm::dvec3(c.position));
  lo = 1e300;
  hi = -1e300;
  for (const glm::dvec3& p : v) {
    double d = glm::dot(p - glm::dvec3(c.position), forward);
    lo = std::min(lo, d);
    hi = std::max(hi, d);
  }
}

}  // namespace

TEST(RasterLispsm, ViewBoxIntersectionIsTheExactBody) {
  double lo = 0, hi = 0;
  // A box wholly in view: its 8 corners, depths 5..10.
  shadowlab::Camera c = squareCamera({0, 0, 0}, {0, 0, -1});
  std::vector<glm::dvec3> inside = viewBoxIntersection(c, {-1, -1, -10}, {1, 1, -5});
  ASSERT_EQ(inside.size(), 8u);
  depthRange(inside, c, lo, hi);
  EXPECT_NEAR(lo, 5.0, 1e-9);
  EXPECT_NEAR(hi, 10.0, 1e-9);
  // A flat ground 5 below a camera looking level: the frustum's lower plane (45 degrees down)
  // meets it at depth 5 (not at the near plane, as the box's corners alone would say), the box's
  // far edge at depth 50; across, |x| <= depth.
  c = squareCamera({0, 5, 0}, {0, 5, -1});
  std::vector<glm::dvec3> ground = viewBoxIntersection(c, {-50, 0, -50}, {50, 0, 50});
  ASSERT_FALSE(ground.empty());
  depthRange(ground, c, lo, hi);
  EXPECT_NEAR(lo, 5.0, 1e-9);
  EXPECT_NEAR(hi, 50.0, 1e-9);
  for (const glm::dvec3& p : ground) {
    EXPECT_NEAR(p.y, 0.0, 1e-9);
    EXPECT_LE(std::abs(p.x), -p.z + 1e-9);
    EXPECT_LE(-p.z, 50.0 + 1e-9);
  }
  // The camera inside the box: the near plane bounds the body; a box behind it: no body.
  std::vector<glm::dvec3> around = viewBoxIntersection(c, {-50, 0, -50}, {50, 10, 50});
  depthRange(around, c, lo, hi);
  EXPECT_NEAR(lo, 0.1, 1e-6);
  EXPECT_TRUE(viewBoxIntersection(c, {-1, 0, 3}, {1, 2, 6}).empty());
}

}  // namespace raster_lispsm_test
