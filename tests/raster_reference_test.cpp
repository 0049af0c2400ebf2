// The rasterizer against the Embree ground truth (renderReference) on the bundled scenes:
// agreement where it must agree, and the classic failures where a bad method must fail.
// Cameras are rendered at half the scene's resolution (same camera, fewer pixels) to keep the
// executable fast on lavapipe; pixel centers still match ray for ray.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <memory>

#include "shadowlab/raster/raster.h"
#include "support/raster_device.h"
#include "support/half_scene_reference.h"
#include "support/reference_score.h"
#include "shadowlab/reference/reference.h"
#include "shadowlab/scenes/loader.h"

namespace raster_reference_test {

using namespace shadowlab;

namespace {

using RasterVsReference = shadowlab::testing::ValidatedRasterTest;
using shadowlab::testing::Score;
using shadowlab::testing::score;

using shadowlab::testing::halfScene;
const Frame& reference(const Scene& s) { return shadowlab::testing::cachedReference(s); }

}  // namespace

TEST_F(RasterVsReference, CoverageAndObjectIdsAgreeOnEveryBundledScene) {
  REQUIRE_DEVICE();
  for (const std::string& name : bundledSceneNames()) {
    Scene s = halfScene(name);
    const Frame& ref = reference(s);
    Frame ras = R->render(s, Method{});
    ASSERT_EQ(ras.pixelCount(), ref.pixelCount());
    const auto& rh = ref.get("hit");
    const auto& ro = ref.get("object_id");
    const auto& ah = ras.get("hit");
    const auto& ao = ras.get("object_id");
    const auto& rp = ref.get("prim_id");
    const auto& ap = ras.get("prim_id");
    size_t agree = 0, samePrim = 0;
    for (size_t i = 0; i < ref.pixelCount(); ++i) {
      bool same = (rh[i] == ah[i]) && (ro[i] == ao[i]);
      agree += same;
      samePrim += same && rp[i] == ap[i];
    }
    // Primitive ids too (gl_PrimitiveID = triangle index within the object): only pixels on a
    // shared triangle edge may differ.
    EXPECT_GE(double(samePrim) / double(ref.pixelCount()), 0.995) << name << ": prim_id agreement";
    double share = double(agree) / double(ref.pixelCount());
    std::printf("  %-16s coverage+id agreement %.5f (%zu of %zu)\n", name.c_str(), share, agree, ref.pixelCount());
    EXPECT_GE(share, 0.999) << name << ": got " << share << ", expected >= 0.999";
    EXPECT_EQ(ras.meta["camera_hash"], ref.meta["camera_hash"]) << name;
    EXPECT_EQ(ras.meta["scene_hash"], ref.meta["scene_hash"]) << name;
  }
}

TEST_F(RasterVsReference, SphereOnPlaneAt4096AgreesWithTheReference) {
  REQUIRE_DEVICE();
  Scene s = halfScene("sphere_on_plane");
  Method m;
  m.mapSize = 4096;
  Score st = score(reference(s), R->render(s, m), s.lights[0].name);
  double share = double(st.both - st.wrong) / double(st.both);
  std::printf("  sphere_on_plane 4096: agreement %.5f of %zu pixels both see\n", share, st.both);
  EXPECT_GE(share, 0.995) << "got " << share << ", expected >= 0.995";
}

TEST_F(RasterVsReference, ZeroBiasOnGrazingShadowsLitPixels) {
  REQUIRE_DEVICE();
  Scene s = halfScene("grazing");
  Method zero;
  zero.biasConstant = zero.biasSlope = zero.biasClamp = zero.biasCompare = zero.biasNormal = 0;
  Score bad = score(reference(s), R->render(s, zero), s.lights[0].name);
  Score good = score(reference(s), R->render(s, Method{}), s.lights[0].name);
  double badShare = double(bad.litShadowed) / double(bad.refLit);
  double goodShare = double(good.litShadowed) / double(good.refLit);
  std::printf("  grazing: lit pixels shadowed: zero bias %.4f, default bias %.4f\n", badShare, goodShare);
  EXPECT_GT(badShare, 0.10) << "zero bias must show acne on a grazing light";
  EXPECT_LT(goodShare, 0.01) << "the default bias must not";
}

// The engines' fixes work where zero bias fails: on grazing, receiver-plane depth bias alone,
// or the normal offset alone, removes most of the acne.
TEST_F(RasterVsReference, ReceiverPlaneAndNormalOffsetFixGrazingAcne) {
  REQUIRE_DEVICE();
  Scene s = halfScene("grazing");
  Method zero;
  zero.biasConstant = zero.biasSlope = zero.biasClamp = zero.biasCompare = zero.biasNormal = 0;
  Method receiverPlane = zero;
  receiverPlane.biasReceiverPlane = true;
  receiverPlane.biasCompare = 0.00002f;  // a hair above d24 quantization (2^-24 * 256)
  Method normalOffset = zero;
  normalOffset.biasNormal = 1.5f;
  const std::string light = s.lights[0].name;
  auto acne = [&](const Method& m) {
    Score st = score(reference(s), R->render(s, m), light);
    return double(st.litShadowed) / double(st.refLit);
  };
  double z = acne(zero), rp = acne(receiverPlane), no = acne(normalOffset);
  std::printf("  grazing acne: zero bias %.4f, receiver plane %.4f, normal offset 1.5 %.4f\n", z, rp, no);
  EXPECT_LT(rp, 0.1 * z);
  EXPECT_LT(no, 0.1 * z);
}

TEST_F(RasterVsReference, HugeBiasOnContactLightsShadowedPixels) {
  REQUIRE_DEVICE();
  Scene s = halfScene("contact");
  Method huge;
  huge.biasCompare = 0.05f;  // 5% of the map's depth range
  huge.biasSlope = 50.0f;
  Score bad = score(reference(s), R->render(s, huge), s.lights[0].name);
  Score good = score(reference(s), R->render(s, Method{}), s.lights[0].name);
  double badShare = double(bad.shadowLit) / double(bad.refShadow);
  double goodShare = double(good.shadowLit) / double(good.refShadow);
  std::printf("  contact: shadowed pixels lit: huge bias %.4f, default bias %.4f\n", badShare, goodShare);
  EXPECT_GT(badShare, 0.5) << "a huge bias must leak light at the contact";
  // The default bias leaks a sliver along the contact line (peter panning is what bias costs).
  EXPECT_LT(goodShare, 0.05) << "the default bias must leak far less";
}

TEST_F(RasterVsReference, AlphaFenceShadowsFollowTheAlpha) {
  REQUIRE_DEVICE();
  Scene s = halfScene("alpha_fence");
  // Light from behind the fence, so its shadow falls on the ground in front of it, in view
  // even when the fence is solid.
  s.lights[0].direction = glm::normalize(glm::vec3(0.2f, -0.8f, 0.6f));
  s.name += "_backlit";
  s.hash += "-backlit";
  const Frame& ref = reference(s);
  Frame ras = R->render(s, Method{});
  const std::string vis = "light." + s.lights[0].name + ".vis";
  // The same fence without its alpha texture, traced: the rectangle a texture-blind shadow
  // pass would cast. Its shadowed ground pixels that the true (alpha) reference lights are the
  // holes; the raster must light them.
  Scene solid = s;
  solid.hash += "-solid";
  for (Material& mat : solid.materials) mat.hasAlpha = false;
  Frame solidRef = renderReference(solid, ReferenceOptions{});
  const auto& refId = ref.get("object_id");
  const auto& rasId = ras.get("object_id");
  const auto& solidId = solidRef.get("object_id");
  uint32_t ground = 0;
  for (const Object& o : s.objects)
    if (o.name == "ground") ground = o.id;
  ASSERT_NE(ground, 0u);
  size_t holes = 0, holesLit = 0, rectangle = 0;
  for (size_t i = 0; i < ref.pixelCount(); ++i) {
    if (refId[i] != ground || rasId[i] != ground || solidId[i] != ground) continue;
    bool solidShadow = solidRef.get(vis)[i] < 0.5f;
    rectangle += solidShadow;
    if (solidShadow && ref.get(vis)[i] >= 0.5f) {
      ++holes;
      holesLit += ras.get(vis)[i] >= 0.5f;
    }
  }
  Score st = score(ref, ras, s.lights[0].name);
  double share = double(st.both - st.wrong) / double(st.both);
  std::printf("  alpha_fence: agreement %.5f; solid-rectangle shadow %zu px, holes %zu, holes lit by raster %zu\n",
              share, rectangle, holes, holesLit);
  EXPECT_GE(share, 0.99);
  EXPECT_GT(holes, 500u) << "the scene must show holes in the fence's shadow";
  EXPECT_GE(double(holesLit), 0.9 * double(holes)) << "the shadow pass must discard below the alpha cutoff";
}

TEST_F(RasterVsReference, ReverseGuardKeepsTheImageOffSurfacesBehindTheProjector) {
  REQUIRE_DEVICE();
  Scene s = halfScene("projector");
  ASSERT_FALSE(s.projectors.empty());
  const std::string p = "proj." + s.projectors[0].name + ".";
  const Frame& ref = reference(s);
  Method guarded, unguarded;
  unguarded.projectorReverseGuard = false;
  Frame on = R->render(s, guarded);
  Frame off = R->render(s, unguarded);
  // The reference has no "reverse" channel: derive it from its hit points (w < 0 and the
  // divided coordinates inside [0,1]^2, Projector::texFromWorld's convention).
  const glm::mat4 texFromWorld = s.projectors[0].texFromWorld();
  const auto& refCoverage = ref.get(p + "coverage");
  size_t reverseCovered = 0, mirrored = 0, refReverseCount = 0, coverageAgree = 0;
  for (size_t i = 0; i < ref.pixelCount(); ++i) {
    if (ref.get("hit")[i] > 0.5f) {
      glm::vec4 t = texFromWorld * glm::vec4(ref.get("P.x")[i], ref.get("P.y")[i], ref.get("P.z")[i], 1.0f);
      glm::vec2 uv = glm::vec2(t) / t.w;
      refReverseCount += t.w < 0 && uv.x >= 0 && uv.x <= 1 && uv.y >= 0 && uv.y <= 1;
    }
    reverseCovered += on.get(p + "reverse")[i] > 0.5f && on.get(p + "coverage")[i] > 0.5f;
    mirrored += off.get(p + "reverse")[i] > 0.5f && off.get(p + "coverage")[i] > 0.5f;
    coverageAgree += (refCoverage[i] > 0.5f) == (on.get(p + "coverage")[i] > 0.5f);
  }
  double agree = double(coverageAgree) / double(ref.pixelCount());
  std::printf(
      "  projector: reverse&covered guarded %zu, unguarded %zu, reference reverse %zu, coverage agreement %.5f\n",
      reverseCovered, mirrored, refReverseCount, agree);
  EXPECT_EQ(reverseCovered, 0u);
  EXPECT_GT(mirrored, 1000u) << "without the guard the image must land on the wall behind the projector";
  EXPECT_GT(double(mirrored), 0.9 * double(refReverseCount));
  EXPECT_GE(agree, 0.995);
}

}  // namespace raster_reference_test
