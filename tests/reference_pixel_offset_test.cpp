// ReferenceOptions::pixelOffset: the camera's sample points moved by a fraction of a pixel, what
// compare's alignment check of outside frames traces (compare/study/src/outside_alignment.cpp).
#include <limits>

#include <gtest/gtest.h>

#include "shadowlab/reference/reference.h"
#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/loader.h"

namespace shadowlab::reference_pixel_offset_test {
namespace {

Scene smallScene() {
  Scene s = loadScene(resolveScenePath("grazing"));
  s.camera.width = 96;
  s.camera.height = 54;
  return s;
}

// An offset of a whole pixel traces, at pixel i, the ray of the unshifted frame's pixel i + 1:
// (i + 1) + 0.5 and i + (0.5 + 1) are the same float for these small integers, so the same bits.
TEST(ReferencePixelOffset, AWholePixelOffsetIsTheNeighboursRayBitForBit) {
  const Scene scene = smallScene();
  ReferenceOptions plain;
  plain.channels = ReferenceChannels::Compare;
  ReferenceOptions right = plain, down = plain;
  right.pixelOffset = {1.0f, 0.0f};
  down.pixelOffset = {0.0f, 1.0f};
  const Frame a = renderReference(scene, plain), b = renderReference(scene, right), c = renderReference(scene, down);
  const int w = scene.camera.width, h = scene.camera.height;
  for (const char* channel : {"hit", "object_id", "light.sun.vis", "light.sun.occluder_dist"}) {
    const std::vector<float>&pa = a.get(channel), &pb = b.get(channel), &pc = c.get(channel);
    int differ = 0;
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        const size_t i = size_t(y) * size_t(w) + size_t(x);
        if (x + 1 < w) differ += pb[i] != pa[i + 1];
        if (y + 1 < h) differ += pc[i] != pa[i + size_t(w)];
      }
    }
    EXPECT_EQ(differ, 0) << channel;
  }
}

TEST(ReferencePixelOffset, AHalfPixelOffsetChangesTheEdgesAndTheCacheKey) {
  const Scene scene = smallScene();
  ReferenceOptions plain;
  plain.channels = ReferenceChannels::Compare;
  ReferenceOptions half = plain;
  half.pixelOffset = {0.5f, 0.0f};
  const std::vector<float> a = renderReference(scene, plain).get("light.sun.vis");
  const std::vector<float> b = renderReference(scene, half).get("light.sun.vis");
  int differ = 0;
  for (size_t i = 0; i < a.size(); ++i) differ += a[i] != b[i];
  EXPECT_GT(differ, 0);
  EXPECT_NE(referenceHash(scene, plain), referenceHash(scene, half));
  ReferenceOptions zero = plain;
  zero.pixelOffset = {0.0f, -0.0f};
  EXPECT_EQ(referenceHash(scene, plain), referenceHash(scene, zero));  // an unshifted trace keeps its key
}

TEST(ReferencePixelOffset, AnOffsetBeyondOnePixelIsRefused) {
  ReferenceOptions o;
  o.pixelOffset = {1.5f, 0.0f};
  EXPECT_THROW(renderReference(smallScene(), o), InputError);
  o.pixelOffset = {0.0f, std::numeric_limits<float>::quiet_NaN()};
  EXPECT_THROW(renderReference(smallScene(), o), InputError);
}

}  // namespace
}  // namespace shadowlab::reference_pixel_offset_test
