// Cascade split distances: the practical split scheme, checked against the formula written out
// independently here, and the depth range the splits cover.
#include <gtest/gtest.h>

#include <cmath>

#include "shadowlab/raster/cascades.h"

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
