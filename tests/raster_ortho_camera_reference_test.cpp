// An orthographic camera (scenes/FORMAT.md "camera", "projection": "orthographic") in both
// renderers: a box on a plane under a sun, seen straight down through parallel rays. The reference's
// hit positions are the closed form (each pixel's ray starts on the view plane and meets y = 0 at
// its own x, z); the raster sees the same objects and decides lit or shadowed as the reference
// does wherever the pixel is not on a shadow edge; fits that follow a perspective frustum are
// refused naming the fit; and a perspective camera's rays and matrices are what they were.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "shadowlab/raster/raster.h"
#include "shadowlab/reference/reference.h"
#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/loader.h"
#include "support/cli.h"
#include "support/raster_device.h"
#include "support/reference_score.h"

namespace raster_ortho_camera_reference_test {

using namespace shadowlab;

namespace {

using OrthoCamera = shadowlab::testing::ValidatedRasterTest;

// 80 x 60 pixels over an 8 x 6 view (0.1 world units a pixel), 10 above the ground looking down
// with -z up in the image: pixel (x, y)'s ray starts at (0.1 x - 4, 10, 0.1 y - 3) and goes -y.
// A 2 x 1 x 2 box at the center, the sun at 50 deg elevation.
Scene orthoScene() {
  const auto dir = shadowlab::testing::freshTempDir("raster_ortho_camera");
  const std::string path = (dir / "ortho_box.json").string();
  std::ofstream(path) << R"({
    "camera": {"projection": "orthographic", "ortho_height": 6, "position": [0, 10, 0], "look_at": [0, 0, 0],
               "up": [0, 0, -1], "width": 80, "height": 60},
    "objects": [
      {"type": "plane", "name": "ground", "size": [40, 40]},
      {"type": "box", "name": "box", "size": [2, 1, 2], "transform": {"translate": [0, 0.5, 0]}}
    ],
    "lights": [{"type": "directional", "name": "sun", "elevation_deg": 50, "azimuth_deg": -120}]
  })";
  return loadScene(path);
}

}  // namespace

// The reference's P of every ground pixel is the closed form: the ray from the view plane at
// (0.1 (x + 0.5) - 4, 10, 0.1 (y + 0.5) - 3) meets y = 0 straight below it; the box's top (y = 1)
// likewise. Exact up to float rounding of the origin.
TEST(OrthoCameraRays, ReferenceHitsAreTheParallelRaysClosedForm) {
  const Scene s = orthoScene();
  ASSERT_TRUE(s.camera.orthographic());
  const Frame ref = renderReference(s, ReferenceOptions{});
  const auto& hit = ref.get("hit");
  const auto& px = ref.get("P.x");
  const auto& py = ref.get("P.y");
  const auto& pz = ref.get("P.z");
  size_t ground = 0, top = 0;
  for (int y = 0; y < 60; ++y)
    for (int x = 0; x < 80; ++x) {
      const size_t i = size_t(y) * 80 + size_t(x);
      ASSERT_EQ(hit[i], 1.0f) << x << "," << y;
      const double ex = 0.1 * (x + 0.5) - 4.0, ez = 0.1 * (y + 0.5) - 3.0;
      EXPECT_NEAR(px[i], ex, 1e-5) << x << "," << y;
      EXPECT_NEAR(pz[i], ez, 1e-5) << x << "," << y;
      const bool onBox = std::fabs(ex) < 1.0 && std::fabs(ez) < 1.0;
      EXPECT_NEAR(py[i], onBox ? 1.0 : 0.0, 1e-5) << x << "," << y;
      (onBox ? top : ground) += 1;
    }
  EXPECT_EQ(top, 400u);  // 20 x 20 pixels of the 2 x 2 top
  EXPECT_EQ(ground, 80u * 60u - 400u);
  // CameraRays gives Camera's bits.
  const CameraRays rays(s.camera);
  for (float x : {0.5f, 13.25f, 79.5f})
    for (float y : {0.5f, 41.75f}) {
      EXPECT_EQ(rays.origin(x, y), s.camera.rayOrigin(x, y));
      EXPECT_EQ(rays.direction(x, y), s.camera.rayDirection(x, y));
      EXPECT_EQ(rays.direction(x, y), glm::vec3(0, -1, 0));
    }
}

// The raster with the same camera: every pixel on the same object as the reference, and the lit
// or shadowed decision the reference's except along the shadow's edges (map aliasing: at most the
// pixels within one map texel of the edge). The map: 2048^2 over the scene's bounding sphere.
TEST_F(OrthoCamera, RasterAgreesWithTheReference) {
  REQUIRE_DEVICE();
  const Scene s = orthoScene();
  const Frame ref = renderReference(s, ReferenceOptions{});
  Method m;
  m.mapSize = 2048;
  const Frame ras = R->render(s, m);
  const shadowlab::testing::Score sc = shadowlab::testing::score(ref, ras, "sun");
  EXPECT_EQ(sc.both, 80u * 60u);  // the same object under every pixel
  // The box's shadow beside it: its 2 x 2 footprint swept 1 / tan(50 deg) = 0.84 along the sun's
  // horizontal direction d, less the footprint: 0.84 * 2 (|d.x| + |d.z|), 1.68..2.37 world units^2
  // whatever d, 168..237 pixels of 0.1 x 0.1.
  EXPECT_GE(sc.refShadow, 160u);
  EXPECT_LE(sc.refShadow, 240u);
  EXPECT_GT(sc.refLit, 3000u);
  // The mismatches lie on the shadow's outline: each has a 4-neighbour the reference decides the
  // other way.
  const auto& rv = ref.get("light.sun.vis");
  const auto& av = ras.get("light.sun.vis");
  size_t interior = 0;
  for (int y = 1; y < 59; ++y)
    for (int x = 1; x < 79; ++x) {
      const size_t i = size_t(y) * 80 + size_t(x);
      if ((rv[i] >= 0.5f) == (av[i] >= 0.5f)) continue;
      bool edge = false;
      for (size_t j : {i - 1, i + 1, i - 80, i + 80}) edge = edge || (rv[j] >= 0.5f) != (rv[i] >= 0.5f);
      interior += !edge;
    }
  EXPECT_EQ(interior, 0u) << sc.wrong << " mismatches";
  EXPECT_LT(sc.wrong, 80u);
  // The texel footprint m on the ground (Lloyd's 1 / sMin of d(texel)/d(pixel)): the sphere fit's
  // map spans the bounds' sphere, radius sqrt(20^2 + 0.5^2 + 20^2) = 28.288, so a texel is
  // 56.577 / 2048 = 0.027625; a pixel's 0.1 of ground shrinks to 0.1 sin(50 deg) across the light,
  // so sMin = 0.0766 / 0.027625 texels a pixel and m = 0.3606 everywhere on the ground (the same for
  // every pixel: parallel rays). A perspective footprint (scaled by the ray's t) would be 10x off.
  const auto& footprint = ras.get("light.sun.m");
  const auto& py = ref.get("P.y");
  const double expectedM = (2.0 * std::sqrt(800.25) / 2048.0) / (0.1 * std::sin(50.0 * 3.14159265358979 / 180.0));
  size_t groundPixels = 0;
  for (size_t i = 0; i < footprint.size(); ++i) {
    if (std::fabs(py[i]) > 1e-4f) continue;
    ++groundPixels;
    EXPECT_NEAR(footprint[i], expectedM, 0.002 * expectedM) << i;
  }
  EXPECT_EQ(groundPixels, 80u * 60u - 400u);
  std::printf("orthographic box: %zu compared, %zu mismatches (error_rate %.4f)\n", sc.both, sc.wrong, sc.errorRate);
}

// Fits that follow the camera's frustum: refused with the orthographic camera, naming the fit.
TEST_F(OrthoCamera, FrustumFitsAreRefused) {
  REQUIRE_DEVICE();
  const Scene s = orthoScene();
  for (Fit fit : {Fit::Tight, Fit::Cascades, Fit::Lispsm, Fit::Psm, Fit::Tsm, Fit::Sdsm}) {
    Method m;
    m.mapSize = 256;
    m.fit = fit;
    try {
      R->render(s, m);
      ADD_FAILURE() << toString(fit) << ": no error";
    } catch (const InputError& e) {
      EXPECT_NE(
          std::string(e.what()).find("method: fit: error: got " + toString(fit) + " with the orthographic camera of "),
          std::string::npos)
          << e.what();
      EXPECT_NE(std::string(e.what()).find("expected fit=sphere"), std::string::npos) << e.what();
    }
  }
}

}  // namespace raster_ortho_camera_reference_test
