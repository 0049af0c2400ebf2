// Cascade split distances: the practical split scheme, checked against the formula written out
// independently here, and the depth range the splits cover.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include <glm/gtc/matrix_transform.hpp>

#include "shadowlab/raster/cascades.h"

namespace raster_cascades_test {

using namespace shadowlab;
using namespace shadowlab::raster;

TEST(RasterCascades, SplitsFollowThePracticalSchemeFormula) {
  const double n = 0.5, f = 200.0;
  const int count = 4;
  for (double lambda : {0.0, 0.5, 1.0}) {
    std::vector<double> c = cascadeSplits(n, f, count, lambda);
    ASSERT_EQ(c.size(), size_t(count) + 1);
    for (int i = 0; i <= count; ++i) {
      // Independently: logarithmic part n (f/n)^(i/N), uniform part n + (f - n) i/N.
      double logPart = n * std::exp(std::log(f / n) * i / count);
      double uniformPart = n + (f - n) * i / count;
      double expected = lambda * logPart + (1.0 - lambda) * uniformPart;
      EXPECT_NEAR(c[size_t(i)], expected, 1e-12 * f) << "lambda " << lambda << " i " << i;
    }
    EXPECT_EQ(c.front(), n);
    EXPECT_EQ(c.back(), f);
    for (int i = 0; i < count; ++i) EXPECT_LT(c[size_t(i)], c[size_t(i) + 1]) << "lambda " << lambda;
  }
  // Closed forms at the two ends of lambda, N = 4, n = 0.5, f = 200 (f/n = 400, 400^(1/4) = sqrt(20)):
  // uniform: 0.5 + 49.875 i; logarithmic: 0.5 * 20^(i/2).
  std::vector<double> uniform = cascadeSplits(n, f, count, 0.0), logarithmic = cascadeSplits(n, f, count, 1.0);
  EXPECT_NEAR(uniform[1], 50.375, 1e-12);
  EXPECT_NEAR(uniform[2], 100.25, 1e-12);
  EXPECT_NEAR(logarithmic[1], 0.5 * std::sqrt(20.0), 1e-12);
  EXPECT_NEAR(logarithmic[2], 10.0, 1e-12);
  EXPECT_NEAR(logarithmic[3], 0.5 * 20.0 * std::sqrt(20.0), 1e-10);
}

TEST(RasterCascades, OneCascadeIsTheWholeRange) {
  std::vector<double> c = cascadeSplits(0.1, 50.0, 1, 0.75);
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(c[0], 0.1);
  EXPECT_EQ(c[1], 50.0);
}

TEST(RasterCascades, DepthRangeIsTheCameraClippedToTheSceneBox) {
  Camera cam;
  cam.position = {0, 0, 10};
  cam.lookAt = {0, 0, 0};
  cam.nearPlane = 0.1f;
  cam.farPlane = 1000.0f;
  // Box z in [-5, 5]: view depths 5..15 along -z.
  ViewDepthRange r = cascadeDepthRange(cam, {-1, -1, -5}, {1, 1, 5});
  EXPECT_FLOAT_EQ(r.nearView, 5.0f);
  EXPECT_FLOAT_EQ(r.farView, 15.0f);
  // Camera inside the box: near is the camera's; far the camera's far when the box reaches beyond.
  cam.farPlane = 12.0f;
  r = cascadeDepthRange(cam, {-1, -1, -5}, {1, 1, 50});
  EXPECT_FLOAT_EQ(r.nearView, 0.1f);
  EXPECT_FLOAT_EQ(r.farView, 12.0f);
  // The box wholly behind the camera: no NaN, the camera's own range.
  r = cascadeDepthRange(cam, {-1, -1, 20}, {1, 1, 30});
  EXPECT_FLOAT_EQ(r.nearView, 0.1f);
  EXPECT_FLOAT_EQ(r.farView, 12.0f);
  // near = far: still a valid, non-empty range.
  cam.nearPlane = cam.farPlane = 3.0f;
  r = cascadeDepthRange(cam, {-1, -1, -5}, {1, 1, 5});
  EXPECT_TRUE(std::isfinite(r.nearView) && std::isfinite(r.farView));
  EXPECT_GT(r.farView, r.nearView);
  std::vector<double> c = cascadeSplits(r.nearView, r.farView, 8, 0.75);
  for (double x : c) EXPECT_TRUE(std::isfinite(x));
}

// Stabilized crops: the same size wherever the camera stands or looks, and their corners on the
// whole-texel grid of light space, so a moving camera shifts the map by whole texels (no crawl).
// The slice's corners stay inside. Unstabilized crops change size as the camera turns.
TEST(RasterCascades, StabilizedCropsKeepSizeAndSnapToWholeTexels) {
  glm::vec3 dir = glm::normalize(glm::vec3(0.3f, -0.8f, -0.5f));
  glm::mat4 lightFromWorld = glm::lookAt(glm::vec3(0), dir, glm::vec3(0, 1, 0));
  const int mapSize = 1024;
  const double nearView = 5.0, farView = 20.0;
  const glm::vec2 sceneMin(-1e6f), sceneMax(1e6f);
  float side = -1, texel = -1;
  float plainSideMin = 1e30f, plainSideMax = 0;
  for (int step = 0; step < 16; ++step) {
    Camera cam;
    cam.width = 960;
    cam.height = 540;
    cam.vfovDeg = 50;
    cam.position = glm::vec3(0.37f * step, 1.7f + 0.05f * step, 8.0f - 1.3f * step);
    float yaw = 0.11f * step;
    cam.lookAt = cam.position + glm::vec3(std::sin(yaw), -0.1f, -std::cos(yaw));
    CascadeCrop c = cascadeCrop(cam, lightFromWorld, nearView, farView, mapSize, true, sceneMin, sceneMax);
    glm::vec2 extent = c.maxLight - c.minLight;
    if (side < 0) side = extent.x, texel = c.texelWorld;
    EXPECT_EQ(c.texelWorld, texel) << "step " << step;
    EXPECT_NEAR(extent.x, side, 1e-4f * side) << "step " << step;
    EXPECT_NEAR(extent.y, side, 1e-4f * side) << "step " << step;
    EXPECT_NEAR(extent.x / c.texelWorld, float(mapSize), 1e-3f);
    for (float v : {c.minLight.x, c.minLight.y}) {
      float texels = v / c.texelWorld;
      EXPECT_NEAR(texels, std::round(texels), 1e-2f) << "step " << step << ": crop corner off the texel grid";
    }
    // The slice's 8 corners (camera space -> world -> light) lie inside the crop.
    glm::mat4 worldFromCamera = glm::inverse(cam.viewFromWorld());
    float tanY = std::tan(0.5f * glm::radians(cam.vfovDeg)), tanX = tanY * 960.0f / 540.0f;
    for (int k = 0; k < 8; ++k) {
      float d = float((k & 4) ? farView : nearView);
      glm::vec4 pc((k & 1) ? tanX * d : -tanX * d, (k & 2) ? tanY * d : -tanY * d, -d, 1.0f);
      glm::vec2 l = glm::vec2(lightFromWorld * (worldFromCamera * pc));
      EXPECT_TRUE(l.x >= c.minLight.x && l.x <= c.maxLight.x && l.y >= c.minLight.y && l.y <= c.maxLight.y)
          << "step " << step << " corner " << k;
    }
    CascadeCrop plain = cascadeCrop(cam, lightFromWorld, nearView, farView, mapSize, false, sceneMin, sceneMax);
    float plainSide = std::max(plain.maxLight.x - plain.minLight.x, plain.maxLight.y - plain.minLight.y);
    plainSideMin = std::min(plainSideMin, plainSide);
    plainSideMax = std::max(plainSideMax, plainSide);
    EXPECT_LE(plainSide, side) << "the unstabilized box is the tighter one";
  }
  std::printf("  stabilized crop side %.4f (texel %.6f); unstabilized side %.4f .. %.4f\n", side, texel, plainSideMin,
              plainSideMax);
  EXPECT_GT(plainSideMax - plainSideMin, 0.01f * plainSideMax) << "turning the camera must change an unstabilized crop";
}

}  // namespace raster_cascades_test
