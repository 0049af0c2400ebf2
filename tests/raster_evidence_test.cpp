// Evidence on demand (Rasterizer::render with an EvidenceSelector; raster/METHODS.md): the frame
// made from the lookup pass, the kept planes of the group and the resolve of the listed pixels
// only (pass 5, resolve.frag with kSpecCompact) must hold, at every pixel listed for every channel,
// the full resolve's bits in every light channel (hw2x2's implicit LOD and the compact target's
// quads included); at every pixel listed for the occluder's evidence alone, and every fractional
// one (the lookup made compact), those bits in vis, in_map, occluder_id and occluder_prim and zeros
// in the other evidence channels; elsewhere the full frame's vis (exactly 0 or 1), hit, object_id,
// prim_id, m and cascade, and zeros in the other evidence channels. A partial frame reads the occluder's object
// from the map's stencil (the stencil ids): its occluder_id is the full frame's, its occluder_prim
// stays 0 (meta "occluder_prim": "unresolved").
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <string>

#include "shadowlab/raster/raster.h"
#include "shadowlab/scenes/loader.h"
#include "support/quad.h"
#include "support/raster_device.h"

namespace raster_evidence_test {

using namespace shadowlab;

namespace {

using RasterEvidence = shadowlab::testing::ValidatedRasterTest;

bool sameBits(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }

Scene smallScene(const std::string& name) {
  Scene s = loadScene(resolveScenePath(name));
  s.camera.width = 320;
  s.camera.height = 180;
  return s;
}

struct Check {
  size_t listed = 0, occluderListed = 0, fractional = 0, mismatches = 0;
  size_t changedBytes = 0;  // lookup bytes that differ between the acne frame and m's
  size_t occluded = 0;      // listed pixels whose map texel holds an object (occluder_id != 0)
  bool acnePartial = false;
  bool primUnresolved = false;  // the stencil ids
  std::string first;
};

// Renders `m` fully, then with a selector listing every 7th pixel, and compares the two frames.
// The first render with a selector keeps the group's planes (drawn by the planes pass when the
// group is new, then checked everywhere against the full frame's m and cascade);
// handed back, a partial frame's planes are reused, its evidence planes zeroed again only where it
// listed pixels (every 5th here, so a value left over would show at the 7th's unlisted pixels).
// Between the two, a partial frame of the same group with another bias (acne: no bias at all,
// listing every 3rd pixel) is handed back: the checked frame's vis plane is that frame's,
// rewritten only where the bytes changed.
// occluderOnly: the checked frame lists every pixel for the occluder's evidence alone, none for all.
Check renderBoth(Rasterizer& r, const Scene& s, const Method& m, bool* partial, uint32_t checkedStep = 7,
                 bool occluderOnly = false) {
  // Every step-th pixel for every channel, and the ones half a step later for the occluder's alone.
  auto everyNth = [](uint32_t step) {
    return EvidenceSelector([step](const uint8_t*, int width, int height, EvidenceRequest& request) {
      for (uint32_t i = 0; i < uint32_t(width * height); i += step) request.full.push_back(i);
      for (uint32_t i = step / 2; i < uint32_t(width * height); i += step) request.occluder.push_back(i);
    });
  };
  const EvidenceSelector every3rd = everyNth(3), every5th = everyNth(5),
                         every7th = occluderOnly ? EvidenceSelector([](const uint8_t*, int width, int height,
                                                                       EvidenceRequest& request) {
                           for (uint32_t i = 0; i < uint32_t(width * height); ++i) request.occluder.push_back(i);
                         })
                                                 : everyNth(checkedStep);
  r.recycle(r.render(s, m, "", nullptr, nullptr, &every5th));
  const std::vector<uint8_t> bytes = r.lookupVisibility();
  Method acne = m;
  acne.biasCompare = 0.0f;
  acne.biasSlope = 0.0f;
  acne.biasConstant = 0.0f;
  acne.biasNormal = 0.0f;
  acne.biasReceiverPlane = false;
  RasterTimings acneTimings;
  r.recycle(r.render(s, acne, "", &acneTimings, nullptr, &every3rd));
  const std::vector<uint8_t> acneBytes = r.lookupVisibility();
  Check c;
  c.acnePartial = acneTimings.partialEvidence;
  for (size_t i = 0; i < bytes.size() && i < acneBytes.size(); ++i) c.changedBytes += bytes[i] != acneBytes[i];
  const Frame full = r.render(s, m);
  RasterTimings t;
  Frame part = r.render(s, m, "", &t, nullptr, &every7th);
  *partial = t.partialEvidence;
  EXPECT_EQ(full.names, part.names);
  if (full.names != part.names) return c;
  const std::string p = "light." + s.lights.front().name + ".";
  const std::vector<float>& vis = full.get(p + "vis");
  const std::vector<float>& occluder = full.get(p + "occluder_id");
  c.primUnresolved = part.meta.value("occluder_prim", "") == "unresolved";
  for (size_t i = 0; i < full.pixelCount(); ++i) {
    const bool fractional = vis[i] > 0.0f && vis[i] < 1.0f;
    const bool listed = !occluderOnly && i % checkedStep == 0;  // every channel
    // The occluder's evidence alone (and the exact vis): listed so, or fractional.
    const bool occluderListed = !listed && (occluderOnly || i % checkedStep == checkedStep / 2 || fractional);
    c.listed += listed || occluderListed;
    c.occluderListed += occluderListed;
    c.fractional += fractional;
    c.occluded += (listed || occluderListed) && occluder[i] != 0.0f;
    for (size_t k = 0; k < full.names.size(); ++k) {
      const std::string& name = full.names[k];
      const bool everywhere = name == "hit" || name == "object_id" || name == "prim_id" || name == p + "vis" ||
                              name == p + "m" || name == p + "cascade";
      const bool occluderChannel =
          name == p + "in_map" || name == p + "occluder_id" || name == p + "occluder_prim";
      const bool unresolved = c.primUnresolved && name == p + "occluder_prim";
      const float want =
          (listed || everywhere || (occluderListed && occluderChannel)) && !unresolved ? full.data[k][i] : 0.0f;
      if (!sameBits(part.data[k][i], want) && c.mismatches++ == 0)
        c.first = name + " at pixel " + std::to_string(i) + ": " + std::to_string(part.data[k][i]) + ", full " +
                  std::to_string(full.data[k][i]);
    }
  }
  r.recycle(std::move(part));  // as a sweep does: the next case's frames reuse its planes
  return c;
}

}  // namespace

// Every filter path that reads the map differently (hw2x2's hardware blend with its implicit LOD,
// gathers, the moments, a blend band between cascades), the receiver plane and the normal offset;
// the stencil ids in every map format, with light-depth layers (tsm) and with alpha-tested casters.
TEST_F(RasterEvidence, ListedPixelsGetTheFullResolvesBits) {
  REQUIRE_DEVICE();
  const Scene sphere = smallScene("sphere_on_plane"), fence = smallScene("alpha_fence");
  struct Case {
    const char* what;
    const Scene* scene;
    Method m;
  };
  std::vector<Case> cases;
  auto add = [&](const char* what, auto edit, const Scene* scene = nullptr) {
    Method m;
    m.mapSize = 512;
    edit(m);
    cases.push_back({what, scene ? scene : &sphere, m});
  };
  add("none", [](Method&) {});
  add("hw2x2", [](Method& m) { m.filter = Filter::Hw2x2; });
  add("pcf 5, receiver plane, normal offset", [](Method& m) {
    m.filter = Filter::Pcf;
    m.filterSize = 5;
    m.biasReceiverPlane = true;
    m.biasNormal = 1.0f;
  });
  add("msm", [](Method& m) { m.filter = Filter::Msm; });
  add("cascades, blend, hw2x2", [](Method& m) {
    m.fit = Fit::Cascades;
    m.cascadeCount = 3;
    m.cascadeBlend = 0.3f;
    m.filter = Filter::Hw2x2;
  });
  add("d16, pcf 3", [](Method& m) {
    m.mapFormat = DepthFormat::D16;
    m.filter = Filter::Pcf;
  });
  add("d32f, hw2x2", [](Method& m) {
    m.mapFormat = DepthFormat::D32F;
    m.filter = Filter::Hw2x2;
  });
  add("tsm (light-depth layers)", [](Method& m) { m.fit = Fit::Tsm; });
  add(
      "alpha-tested fence, pcf 3", [](Method& m) { m.filter = Filter::Pcf; }, &fence);
  int partials = 0;
  for (const Case& c : cases) {
    bool partial = false;
    const Check k = renderBoth(*R, *c.scene, c.m, &partial);
    partials += partial;
    EXPECT_EQ(k.mismatches, 0u) << c.what << "; first: " << k.first;
    // The stencil ids were used; lavapipe has no D16_S8, so d16 keeps the id attachment there.
    if (c.m.mapFormat != DepthFormat::D16) {
      EXPECT_TRUE(k.primUnresolved) << c.what;
    }
    EXPECT_GT(k.occluded, 500u) << c.what;
    EXPECT_GT(k.listed, 1000u) << c.what;
    EXPECT_GT(k.occluderListed, 1000u) << c.what;
    EXPECT_TRUE(k.acnePartial) << c.what;
    EXPECT_GT(k.changedBytes, 500u) << c.what;
    if (c.m.filter != Filter::None) {
      EXPECT_GT(k.fractional, 0u) << c.what;
    }
  }
  EXPECT_EQ(partials, int(cases.size()));
}

// A list long enough that the evidence is scattered into the planes on two threads
// (kParallelScatter, 65536 pixels; rasterizer.cpp): every pixel of a 480x270 frame.
TEST_F(RasterEvidence, ALongListScattersToTheSameBits) {
  REQUIRE_DEVICE();
  Scene sphere = smallScene("sphere_on_plane");
  sphere.camera.width = 480;
  sphere.camera.height = 270;
  Method m;
  m.mapSize = 512;
  m.filter = Filter::Pcf;
  bool partial = false;
  const Check k = renderBoth(*R, sphere, m, &partial, 1);
  EXPECT_TRUE(partial);
  EXPECT_EQ(k.listed, size_t(480 * 270));
  EXPECT_EQ(k.occluderListed, 0u);
  EXPECT_EQ(k.mismatches, 0u) << "first: " << k.first;
  // The same for the occluder's list (the lookup made compact).
  const Check o = renderBoth(*R, sphere, m, &partial, 1, true);
  EXPECT_TRUE(partial);
  EXPECT_EQ(o.occluderListed, size_t(480 * 270));
  EXPECT_GT(o.occluded, 10000u);
  EXPECT_EQ(o.mismatches, 0u) << "first: " << o.first;
}

// More objects than the stencil's 8 bits tell apart: the partial frames keep the id attachment
// (occluder_prim resolved) and still hold the full resolve's bits.
TEST_F(RasterEvidence, ManyObjectsKeepTheIdAttachment) {
  REQUIRE_DEVICE();
  Scene s = smallScene("sphere_on_plane");
  for (uint32_t k = 0; k < 300; ++k)  // a grid of small tiles floating over the ground
    shadowlab::testing::addQuad(s, 1000 + k, {-3.0f + 0.3f * float(k % 20), 0.6f, -2.0f + 0.3f * float(k / 20)},
                                {0.2f, 0.0f, 0.0f}, {0.0f, 0.0f, 0.2f});
  s.hash.clear();
  Method m;
  m.mapSize = 512;
  bool partial = false;
  const Check k = renderBoth(*R, s, m, &partial);
  EXPECT_TRUE(partial);
  EXPECT_FALSE(k.primUnresolved);
  EXPECT_EQ(k.mismatches, 0u) << k.first;
  EXPECT_GT(k.occluded, 500u);
}

// Without a selector, with a scene that has projectors, or a selector that is empty: the full frame.
TEST_F(RasterEvidence, FullFrameWhereOnDemandDoesNotApply) {
  REQUIRE_DEVICE();
  EvidenceSelector none = [](const uint8_t*, int, int, EvidenceRequest&) {};
  Method m;
  m.mapSize = 256;
  const Scene projector = smallScene("projector");
  RasterTimings t;
  for (int i = 0; i < 2; ++i) {
    const Frame f = R->render(projector, m, "", &t, nullptr, &none);
    EXPECT_FALSE(t.partialEvidence);
    EXPECT_FALSE(f.meta.contains("evidence"));
  }
  const Scene sphere = smallScene("sphere_on_plane");
  R->render(sphere, m, "", &t, nullptr, &none);  // keeps the group
  const Frame f = R->render(sphere, m, "", &t, nullptr, &none);
  EXPECT_TRUE(t.partialEvidence);
  EXPECT_EQ(f.meta.value("evidence", ""), "partial");
  EXPECT_EQ(f.meta.value("evidence_pixels", uint64_t(0)), t.evidencePixels);
  EXPECT_LT(t.evidencePixels, f.pixelCount() / 10);
  R->render(sphere, m, "", &t);
  EXPECT_FALSE(t.partialEvidence);
  EXPECT_EQ(t.evidencePixels, uint64_t(sphere.camera.width) * uint64_t(sphere.camera.height));
}

}  // namespace raster_evidence_test
