// CompareContext (compare.h) without any renderer: synthetic frames of one evidence group (the same
// hit, object ids, m and cascade planes; vis and evidence differ per configuration) must give the
// same Metrics JSON, bit for bit, and the same classification as the full compareFrames; frames
// the context does not apply to (another group, no group, another reference, another size, other
// planes) must take the full path.
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "shadowlab/compare/compare.h"
#include "shadowlab/scenes/error.h"

namespace shadowlab::compare_metrics_context_test {
namespace {

constexpr float kPlane = 1, kCaster = 2, kThird = 3;

struct Group {
  int width = 0, height = 0;
  Frame reference;
  Frame raster;  // the group's planes; vis and evidence filled per configuration
};

Frame emptyFrame(int w, int h) {
  Frame f;
  f.width = w;
  f.height = h;
  f.meta["scene"] = "synthetic";
  f.meta["scene_hash"] = "00000000000000aa";
  f.meta["camera_hash"] = "00000000000000bb";
  f.meta["lights"] = {"sun"};
  return f;
}

// A reference with random shadow blobs (a few fractional pixels on their rims), background rows,
// a second object; the raster shares the geometry but for a few mismatches, has a random m
// (0.3..6 pixels per texel: aliasing limits from under a pixel to a dozen) and three cascades in
// bands of rows. `cascaded` false: no cascade channel (the default fit).
Group makeGroup(int w, int h, bool cascaded, unsigned seed) {
  Group g;
  g.width = w;
  g.height = h;
  g.reference = emptyFrame(w, h);
  g.raster = emptyFrame(w, h);
  g.reference.meta["kind"] = "reference";
  g.raster.meta["kind"] = "raster";
  g.raster.meta["light"] = "sun";
  g.raster.meta["evidence_group"] = "group-" + std::to_string(seed) + (cascaded ? "c" : "");
  g.raster.meta["method"] = {{"fit", cascaded ? "cascades" : "fixed"}, {"cascades.count", 3}};
  for (Frame* f : {&g.reference, &g.raster})
    for (const char* c : {"hit", "object_id", "light.sun.vis"}) f->add(c, 0.0f);
  g.reference.add("light.sun.occluder_dist", -1.0f);
  g.raster.add("light.sun.m", 0.0f);
  if (cascaded) g.raster.add("light.sun.cascade", 0.0f);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<float> blobs;
  for (int k = 0; k < 7; ++k) blobs.insert(blobs.end(), {u(rng) * w, u(rng) * h, 4 + 14 * u(rng)});
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const size_t i = size_t(y) * w + x;
      const bool background = y >= h - 3;
      float vis = 1.0f;
      for (size_t k = 0; k < blobs.size(); k += 3) {
        const float r = std::hypot(x - blobs[k], y - blobs[k + 1]) - blobs[k + 2];
        vis = std::min(vis, std::clamp(r + 0.5f, 0.0f, 1.0f));  // fractional within half a pixel of the rim
      }
      const float object = x < w / 5 ? kThird : kPlane;
      for (Frame* f : {&g.reference, &g.raster}) {
        f->get("hit")[i] = background ? 0.0f : 1.0f;
        f->get("object_id")[i] = background ? 0.0f : object;
      }
      if (!background) {
        g.reference.get("light.sun.vis")[i] = vis;
        g.reference.get("light.sun.occluder_dist")[i] = vis >= 0.5f ? -1.0f : 0.004f + 0.3f * u(rng);
      }
      g.raster.get("light.sun.m")[i] = 0.3f + 5.7f * u(rng);
      if (cascaded) g.raster.get("light.sun.cascade")[i] = float(std::min(2, 3 * y / h));
      if (u(rng) < 0.01f) g.raster.get("object_id")[i] = kCaster;  // geometry mismatches
    }
  }
  g.raster.get("light.sun.m")[5] = std::numeric_limits<float>::quiet_NaN();  // sanitized as compare does
  return g;
}

// One configuration of the group: the group's planes, the reference's decisions flipped at ~4% of
// the pixels (and some fractional values), random evidence at those (acne, leak, coverage and
// candidates for aliasing or other all occur), zeros elsewhere as evidence on demand leaves them.
Frame configuration(const Group& g, unsigned seed, bool withMoments) {
  Frame f = g.raster;
  const char* evidence[] = {"receiver_depth", "map_depth", "occluder_id", "in_map", "bias_depth", "bias_world"};
  for (const char* c : evidence) f.add(std::string("light.sun.") + c, 0.0f);
  if (withMoments) {
    f.add("light.sun.moment_mean", 0.0f);
    f.add("light.sun.moment_bound", 0.0f);
  }
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  const std::vector<float>& refVis = g.reference.get("light.sun.vis");
  std::vector<float>& vis = f.get("light.sun.vis");
  for (size_t i = 0; i < f.pixelCount(); ++i) {
    const bool refLit = refVis[i] >= 0.5f;
    vis[i] = refLit ? 1.0f : 0.0f;
    const float r = u(rng);
    if (r < 0.005f) vis[i] = u(rng);  // fractional (a filter)
    if (r > 0.96f) vis[i] = refLit ? 0.0f : 1.0f;
    // Values outside 0..1 (a filter's overshoot) and NaN: compare clamps them (NaN to 0), which
    // the context's vectorized runs must leave to its exact path.
    if (r > 0.955f && r <= 0.96f) {
      const float odd[] = {1.5f, -0.25f, std::numeric_limits<float>::quiet_NaN(), 1.0f + 1e-6f};
      vis[i] = odd[size_t(u(rng) * 3.999f)];
    }
    if (r < 0.005f || r > 0.96f) {
      f.get("light.sun.in_map")[i] = u(rng) < 0.1f ? 0.0f : 1.0f;
      f.get("light.sun.occluder_id")[i] = u(rng) < 0.3f ? f.get("object_id")[i] : kCaster;
      f.get("light.sun.receiver_depth")[i] = 0.5f;
      f.get("light.sun.map_depth")[i] = u(rng) < 0.3f ? 0.4995f : 0.2f;
      f.get("light.sun.bias_depth")[i] = 0.001f;
      f.get("light.sun.bias_world")[i] = 0.01f;
      if (withMoments) {
        f.get("light.sun.moment_mean")[i] = 0.3f + 0.4f * u(rng);
        f.get("light.sun.moment_bound")[i] = u(rng);
      }
    }
  }
  return f;
}

void expectSameAsFull(const CompareContext& context, const Frame& reference, const Frame& raster,
                      const std::string& what) {
  Classification want, got;
  const std::string full = compareFrames(reference, raster, context.options(), &want).toJson().dump();
  const std::string fast = compareFrames(context, reference, raster, &got).toJson().dump();
  EXPECT_EQ(fast, full) << what;
  EXPECT_TRUE(got.classes == want.classes) << what;
  EXPECT_TRUE(got.referenceLit == want.referenceLit) << what;
  EXPECT_EQ(got.width, want.width);
  EXPECT_EQ(got.height, want.height);
  // Without a classification (the sweep's case) too.
  EXPECT_EQ(compareFrames(context, reference, raster).toJson().dump(), full) << what;
}

TEST(CompareContext, SameMetricsAsCompareFramesAcrossAGroup) {
  for (bool cascaded : {false, true}) {
    // 200 x 75: the last block of 16 rows is partial.
    const Group g = makeGroup(200, 75, cascaded, cascaded ? 11u : 12u);
    const CompareContext context(g.reference, configuration(g, 100, false));
    ASSERT_EQ(context.group(), g.raster.meta["evidence_group"].get<std::string>());
    uint64_t acne = 0, leak = 0, coverage = 0, aliasing = 0, other = 0;
    for (unsigned seed = 100; seed < 106; ++seed) {
      const Frame raster = configuration(g, seed, seed % 2 == 1);
      ASSERT_TRUE(context.appliesTo(g.reference, raster)) << seed;
      expectSameAsFull(context, g.reference, raster, "seed " + std::to_string(seed));
      const Metrics m = compareFrames(context, g.reference, raster);
      acne += m.count(PixelClass::Acne), leak += m.count(PixelClass::Leak);
      coverage += m.count(PixelClass::Coverage), aliasing += m.count(PixelClass::Aliasing);
      other += m.count(PixelClass::Other);
      EXPECT_EQ(m.cascades.size(), cascaded ? 3u : 0u);
      EXPECT_GT(m.mae, 0.0);
    }
    // Every kind of decision was exercised (the boundary distances for aliasing and other).
    EXPECT_GT(acne, 0u);
    EXPECT_GT(leak, 0u);
    EXPECT_GT(coverage, 0u);
    EXPECT_GT(aliasing, 50u);
    EXPECT_GT(other, 50u);
  }
}

// Another map size of the same camera: the group's m and cascades differ, its geometry (hit and
// object planes) and the reference do not, so its context shares the first one's decisions and
// still gives the full path's metrics; the same frames with one pixel's object changed, a copy of
// the reference or another light do not share them (and are still right).
TEST(CompareContext, SharesDecisionsWithAnotherGroupOfTheSameGeometry) {
  for (bool cascaded : {false, true}) {
    const Group g = makeGroup(200, 75, cascaded, 31);
    const CompareContext first(g.reference, configuration(g, 200, false));
    Group h = g;
    h.raster.meta["evidence_group"] = std::string("another map size") + (cascaded ? "c" : "");
    std::mt19937 rng(77);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    for (float& m : h.raster.get("light.sun.m")) m = 0.1f + 2.0f * u(rng);
    if (cascaded)
      for (size_t i = 0; i < h.raster.pixelCount(); ++i)
        h.raster.get("light.sun.cascade")[i] = float((i / size_t(h.width)) % 3);
    const Frame firstRow = configuration(h, 300, false);
    Metrics m;
    const CompareContext second(g.reference, firstRow, {}, &first, &m);
    EXPECT_TRUE(second.sharesPixelsWith(first));
    EXPECT_TRUE(first.sharesPixelsWith(second));
    EXPECT_EQ(second.group(), h.raster.meta["evidence_group"].get<std::string>());
    EXPECT_EQ(m.toJson().dump(), compareFrames(g.reference, firstRow).toJson().dump());
    for (unsigned seed = 300; seed < 304; ++seed) {
      const Frame raster = configuration(h, seed, seed % 2 == 1);
      ASSERT_TRUE(second.appliesTo(g.reference, raster));
      EXPECT_FALSE(first.appliesTo(g.reference, raster));  // another group
      expectSameAsFull(second, g.reference, raster, "shared, seed " + std::to_string(seed));
    }
    // The group's own m statistics, not the first group's.
    EXPECT_NE(compareFrames(second, g.reference, firstRow).mP95,
              compareFrames(first, g.reference, configuration(g, 300, false)).mP95);

    // One pixel of the raster's geometry differs (another object where both frames hit): the
    // decisions are not the first group's, so they are made anew.
    Group k = h;
    k.raster.meta["evidence_group"] = "one pixel's object differs";
    const size_t pixel = size_t(10) * size_t(k.width) + size_t(k.width / 2);
    ASSERT_EQ(k.raster.get("object_id")[pixel], kPlane);
    ASSERT_EQ(k.reference.get("object_id")[pixel], kPlane);
    k.raster.get("object_id")[pixel] = kCaster;
    const Frame kRow = configuration(k, 310, false);
    Metrics km;
    const CompareContext third(g.reference, kRow, {}, &first, &km);
    EXPECT_FALSE(third.sharesPixelsWith(first));
    EXPECT_EQ(km.toJson().dump(), compareFrames(g.reference, kRow).toJson().dump());
    expectSameAsFull(third, g.reference, configuration(k, 311, true), "one pixel's object differs");

    // A copy of the reference (equal contents, another object): not shared.
    const Frame referenceCopy = g.reference;
    const CompareContext fromCopy(referenceCopy, firstRow, {}, &first);
    EXPECT_FALSE(fromCopy.sharesPixelsWith(first));
    expectSameAsFull(fromCopy, referenceCopy, firstRow, "a copy of the reference");
  }
  // Another light of the same frames: its own decisions.
  const Group g = makeGroup(120, 60, false, 41);
  Frame twoLights = configuration(g, 5, false), referenceTwo = g.reference;
  twoLights.add("light.moon.vis", 1.0f);
  referenceTwo.add("light.moon.vis", 0.0f);
  const CompareContext sun(referenceTwo, twoLights);
  CompareOptions moon;
  moon.light = "moon";
  const CompareContext moonContext(referenceTwo, twoLights, moon, &sun);
  EXPECT_FALSE(moonContext.sharesPixelsWith(sun));
  expectSameAsFull(moonContext, referenceTwo, twoLights, "light moon after sun");
  // A context that applies to nothing shares nothing, and still hands back the full metrics.
  Frame noKey = twoLights;
  noKey.meta.erase("evidence_group");
  Metrics nm;
  const CompareContext none(referenceTwo, noKey, {}, &sun, &nm);
  EXPECT_FALSE(none.sharesPixelsWith(sun));
  EXPECT_EQ(nm.toJson().dump(), compareFrames(referenceTwo, noKey).toJson().dump());
}

// Options travel with the context: a wider boundary band moves pixels from other to aliasing.
TEST(CompareContext, KeepsItsOptions) {
  const Group g = makeGroup(120, 60, false, 7);
  CompareOptions wide;
  wide.boundaryTexels = 5.0f;
  const CompareContext narrowContext(g.reference, g.raster), wideContext(g.reference, g.raster, wide);
  const Frame raster = configuration(g, 3, false);
  expectSameAsFull(wideContext, g.reference, raster, "boundaryTexels 5");
  const Metrics narrow = compareFrames(narrowContext, g.reference, raster);
  const Metrics wider = compareFrames(wideContext, g.reference, raster);
  EXPECT_GT(wider.count(PixelClass::Aliasing), narrow.count(PixelClass::Aliasing));
}

// The guard: frames the context was not made for go through the full path (the right metrics),
// and appliesTo says so.
TEST(CompareContext, FallsBackWhereItDoesNotApply) {
  const Group g = makeGroup(120, 60, true, 21);
  const CompareContext context(g.reference, g.raster);
  const Frame good = configuration(g, 5, false);
  ASSERT_TRUE(context.appliesTo(g.reference, good));

  // Another group with the same size and channels, claiming to be another group: not applied.
  const Group other = makeGroup(120, 60, true, 22);
  const Frame otherFrame = configuration(other, 5, false);
  EXPECT_FALSE(context.appliesTo(other.reference, otherFrame));
  EXPECT_FALSE(context.appliesTo(g.reference, otherFrame));
  EXPECT_EQ(compareFrames(context, other.reference, otherFrame).toJson(),
            compareFrames(other.reference, otherFrame).toJson());
  // The right reference, a frame of another group (its m and geometry differ): the full path.
  EXPECT_EQ(compareFrames(context, g.reference, otherFrame).toJson(), compareFrames(g.reference, otherFrame).toJson());

  // A frame without the key (a full frame rendered without a selector, a frame built in code).
  Frame noKey = good;
  noKey.meta.erase("evidence_group");
  EXPECT_FALSE(context.appliesTo(g.reference, noKey));
  EXPECT_FALSE(CompareContext(g.reference, noKey).appliesTo(g.reference, noKey));  // nothing to key on
  EXPECT_EQ(CompareContext(g.reference, noKey).group(), "");

  // Another reference object, even with equal contents: the context holds its decisions, not a copy.
  const Frame referenceCopy = g.reference;
  EXPECT_FALSE(context.appliesTo(referenceCopy, good));
  EXPECT_EQ(compareFrames(context, referenceCopy, good).toJson(), compareFrames(referenceCopy, good).toJson());

  // The same key with another plane set: a frame without its cascade channel.
  Frame noCascade = good;
  const size_t k =
      size_t(std::find(noCascade.names.begin(), noCascade.names.end(), "light.sun.cascade") - noCascade.names.begin());
  ASSERT_LT(k, noCascade.names.size());
  noCascade.names.erase(noCascade.names.begin() + std::ptrdiff_t(k));
  noCascade.data.erase(noCascade.data.begin() + std::ptrdiff_t(k));
  EXPECT_FALSE(context.appliesTo(g.reference, noCascade));
  EXPECT_EQ(compareFrames(context, g.reference, noCascade).toJson(), compareFrames(g.reference, noCascade).toJson());

  // Another light named in the options: not the context's.
  Frame twoLights = good;
  twoLights.add("light.moon.vis", 1.0f);
  Frame referenceTwo = g.reference;
  referenceTwo.add("light.moon.vis", 1.0f);
  const CompareContext sunContext(referenceTwo, twoLights);
  EXPECT_TRUE(sunContext.appliesTo(referenceTwo, twoLights));
  CompareOptions moon;
  moon.light = "moon";
  const CompareContext moonContext(referenceTwo, twoLights, moon);
  EXPECT_NE(compareFrames(moonContext, referenceTwo, twoLights).toJson(),
            compareFrames(sunContext, referenceTwo, twoLights).toJson());
  expectSameAsFull(moonContext, referenceTwo, twoLights, "light moon");
  // A context that applies to nothing still compares with its options (the moon, not the sun).
  Frame twoLightsNoKey = twoLights;
  twoLightsNoKey.meta.erase("evidence_group");
  const CompareContext moonNoKey(referenceTwo, twoLightsNoKey, moon);
  EXPECT_FALSE(moonNoKey.appliesTo(referenceTwo, twoLightsNoKey));
  EXPECT_EQ(compareFrames(moonNoKey, referenceTwo, twoLightsNoKey).toJson(),
            compareFrames(referenceTwo, twoLightsNoKey, moon).toJson());
  EXPECT_NE(compareFrames(moonNoKey, referenceTwo, twoLightsNoKey).toJson(),
            compareFrames(referenceTwo, twoLightsNoKey).toJson());

  // A default context applies to nothing.
  EXPECT_FALSE(CompareContext().appliesTo(g.reference, good));
  EXPECT_EQ(compareFrames(CompareContext(), g.reference, good).toJson(), compareFrames(g.reference, good).toJson());
}

// Bad input throws as compareFrames does, when the context is made.
TEST(CompareContext, BadInputThrowsLikeCompareFrames) {
  const Group g = makeGroup(40, 30, false, 3);
  Frame small = emptyFrame(20, 30);
  EXPECT_THROW(CompareContext(g.reference, small), InputError);
}

}  // namespace
}  // namespace shadowlab::compare_metrics_context_test
