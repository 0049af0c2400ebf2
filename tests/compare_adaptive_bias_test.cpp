// Adaptive depth bias (bias.adaptive, raster/METHODS.md "Adaptive depth bias") end to end against
// the Embree truth on the bundled bias scenes, scored by the compare library's classes.
#include <gtest/gtest.h>

#include <cstdio>
#include <map>

#include "shadowlab/compare/compare.h"
#include "shadowlab/raster/raster.h"
#include "shadowlab/reference/reference.h"
#include "shadowlab/scenes/loader.h"
#include "support/raster_device.h"
#include "support/half_scene_reference.h"
#include "support/reference_score.h"

using namespace shadowlab;

namespace {

using AdaptiveBias = shadowlab::testing::ValidatedRasterTest;
using shadowlab::testing::Score;
using shadowlab::testing::score;

using shadowlab::testing::halfScene;
const Frame& reference(const Scene& s) { return shadowlab::testing::cachedReference(s); }

}  // namespace

// Adaptive depth bias (raster/METHODS.md "Adaptive depth bias") with every other bias off: each
// tap compared against the receiver's tangent plane at its texel centre, less the scene-scale
// epsilon. No acne on grazing where zero bias has it on half the lit ground (so a renderer that
// ignored bias.adaptive fails), and the contact line within a bound measured with margin
// (measured at 480x270: 0.14 % of the shadowed pixels lit, the default bias 0.18 %; no leak class).
TEST_F(AdaptiveBias, RemovesGrazingAcneAndKeepsTheContact) {
  REQUIRE_DEVICE();
  Method zero;
  zero.biasConstant = zero.biasSlope = zero.biasClamp = zero.biasCompare = zero.biasNormal = 0;
  Method adaptive = zero;
  adaptive.biasAdaptive = true;
  Scene g = halfScene("grazing");
  Frame zeroFrame = R->render(g, zero), adaptiveFrame = R->render(g, adaptive);
  Score zs = score(reference(g), zeroFrame, g.lights[0].name),
        as = score(reference(g), adaptiveFrame, g.lights[0].name);
  double z = double(zs.litShadowed) / double(zs.refLit), a = double(as.litShadowed) / double(as.refLit);
  const uint64_t acneZero = compareFrames(reference(g), zeroFrame).count(PixelClass::Acne);
  const uint64_t acneAdaptive = compareFrames(reference(g), adaptiveFrame).count(PixelClass::Acne);
  Scene c = halfScene("contact");
  Frame contactFrame = R->render(c, adaptive);
  Score cs = score(reference(c), contactFrame, c.lights[0].name);
  Score ds = score(reference(c), R->render(c, Method{}), c.lights[0].name);
  double leakAdaptive = double(cs.shadowLit) / double(cs.refShadow);
  double leakDefault = double(ds.shadowLit) / double(ds.refShadow);
  const uint64_t leakClass = compareFrames(reference(c), contactFrame).count(PixelClass::Leak);
  std::printf(
      "  adaptive bias: grazing lit->shadowed %.5f, acne pixels %llu (zero bias %.4f, %llu); contact "
      "shadowed->lit %.5f, leak pixels %llu (default bias %.5f)\n",
      a, (unsigned long long)acneAdaptive, z, (unsigned long long)acneZero, leakAdaptive, (unsigned long long)leakClass,
      leakDefault);
  EXPECT_GT(z, 0.10) << "zero bias must show acne on grazing";
  EXPECT_GT(acneZero, 1000u);
  EXPECT_EQ(acneAdaptive, 0u) << "adaptive bias must have no acne on grazing";
  EXPECT_LT(a, 0.001) << "what remains is the block's shadow boundary";
  EXPECT_LT(leakAdaptive, 0.003) << "adaptive bias must keep the contact line";
  EXPECT_EQ(leakClass, 0u);
}
