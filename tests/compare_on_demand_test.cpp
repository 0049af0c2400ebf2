// Evidence on demand end to end (raster/METHODS.md "Evidence on demand", compare/SWEEPS.md): on
// every bundled scene at 160x90, under a third each of a method set covering every filter, cascades with a blend
// band, lispsm, psm, tsm, the receiver plane, adaptive and normal-offset biases, d32f, a spot and a point
// light, the metrics of compareFrames on the on-demand frame (the sweep's selector,
// disagreementSelector) equal those of the full frame exactly, class by class (timings are not
// metrics). A selector that drops the disagreeing pixels must change them.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "shadowlab/compare/compare.h"
#include "shadowlab/compare/run_pipeline.h"
#include "shadowlab/raster/raster.h"
#include "shadowlab/reference/reference.h"
#include "shadowlab/scenes/loader.h"
#include "support/raster_device.h"
#include "support/tiny_scenes.h"

namespace compare_on_demand_test {

using namespace shadowlab;

namespace {

using OnDemand = shadowlab::testing::ValidatedRasterTest;

using shadowlab::testing::tinyScene;
using shadowlab::testing::withLight;

struct Case {
  std::string what;
  int light = 0;  // 0 the scene's, 1 spot, 2 point
  Method method;
};

// Groups of configurations that share the light's layers (a group's first frame draws the planes
// the others reuse): the default fit with every filter and bias, cascades, lispsm, psm, tsm, the spot, the point.
std::vector<Case> cases() {
  std::vector<Case> out;
  auto add = [&](std::string what, int light, auto edit) {
    Method m;
    m.mapSize = 512;
    edit(m);
    out.push_back({std::move(what), light, m});
  };
  add("none", 0, [](Method&) {});
  add("none, slope 0, compare 0 (acne)", 0, [](Method& m) {
    m.biasSlope = 0.0f;
    m.biasCompare = 0.0f;
  });
  add("hw2x2", 0, [](Method& m) { m.filter = Filter::Hw2x2; });
  add("bilinear4", 0, [](Method& m) { m.filter = Filter::Bilinear4; });
  add("pcf 5", 0, [](Method& m) {
    m.filter = Filter::Pcf;
    m.filterSize = 5;
  });
  add("poisson", 0, [](Method& m) { m.filter = Filter::Poisson; });
  add("vsm", 0, [](Method& m) { m.filter = Filter::Vsm; });
  add("msm", 0, [](Method& m) { m.filter = Filter::Msm; });
  add("pcf 3, receiver plane", 0, [](Method& m) {
    m.filter = Filter::Pcf;
    m.biasReceiverPlane = true;
  });
  add("adaptive", 0, [](Method& m) {
    m.biasAdaptive = true;
    m.biasSlope = 0.0f;
    m.biasCompare = 0.0f;
  });
  add("normal bias 1.5", 0, [](Method& m) { m.biasNormal = 1.5f; });
  add("d32f, hw2x2", 0, [](Method& m) {
    m.mapFormat = DepthFormat::D32F;
    m.filter = Filter::Hw2x2;
  });
  for (Filter f : {Filter::None, Filter::Pcf})
    add(std::string("cascades 3, blend 0.2, ") + toString(f), 0, [f](Method& m) {
      m.fit = Fit::Cascades;
      m.cascadeCount = 3;
      m.cascadeBlend = 0.2f;
      m.filter = f;
    });
  for (Filter f : {Filter::None, Filter::Hw2x2})
    add(std::string("lispsm, ") + toString(f), 0, [f](Method& m) {
      m.fit = Fit::Lispsm;
      m.filter = f;
    });
  for (Fit fit : {Fit::Psm, Fit::Tsm})
    for (Filter f : {Filter::None, Filter::Pcf})
      add(std::string(toString(fit)) + ", " + toString(f), 0, [fit, f](Method& m) {
        m.fit = fit;
        m.filter = f;
      });
  for (int light : {1, 2})
    for (Filter f : {Filter::None, Filter::Hw2x2, Filter::Pcf})
      add(std::string(light == 1 ? "spot, " : "point, ") + toString(f), light, [f](Method& m) { m.filter = f; });
  return out;
}

nlohmann::json metricsOf(const Frame& reference, const Frame& raster, const std::string& light) {
  CompareOptions o;
  o.light = light;
  return compareFrames(reference, raster, o).toJson();
}

}  // namespace

// Every case runs on every third bundled scene (case i on scene j where (i + j) % 3 == 0), so each
// scene meets a third of the cases and each case four or more scenes: the property is the same on
// every pair, and the whole product took 95 s of the suite for no more coverage of either side.
TEST_F(OnDemand, SameMetricsAsTheFullFrameOnEveryBundledScene) {
  REQUIRE_DEVICE();
  const std::vector<Case> all = cases();
  int partial = 0, frames = 0, expectedPartial = 0;
  std::map<std::string, int> scenesPerCase;
  size_t sceneIndex = 0;
  for (const std::string& name : bundledSceneNames()) {
    const Scene base = tinyScene(name);
    if (base.lights.empty()) continue;  // a projector-only scene: the full path (tested in raster_evidence)
    const size_t j = sceneIndex++;
    auto runs = [&](size_t i) { return (i + j) % 3 == 0; };
    // Seven groups of light layers (the default fit, cascades, lispsm, psm, tsm, the spot, the
    // point): each group's first frame draws and keeps its planes (the planes pass) and is partial
    // like the rest. Projectors: every frame full.
    for (int light = 0; light < 3; ++light) {
      bool any = false;
      for (size_t i = 0; i < all.size(); ++i) any = any || (all[i].light == light && runs(i));
      if (!any) continue;
      const Scene s = withLight(base, light);
      const std::string lightName = s.lights.front().name;
      const Frame reference = renderReference(s, ReferenceOptions{});
      const EvidenceSelector select = disagreementSelector(reference, lightName);
      ASSERT_TRUE(bool(select)) << name;
      for (size_t i = 0; i < all.size(); ++i) {
        const Case& c = all[i];
        if (c.light != light || !runs(i)) continue;
        ++scenesPerCase[c.what];
        if (base.projectors.empty()) ++expectedPartial;
        RasterTimings t;
        Frame onDemand = R->render(s, c.method, "", &t, nullptr, &select);
        const nlohmann::json got = metricsOf(reference, onDemand, lightName);
        partial += t.partialEvidence;
        ++frames;
        // Handed back as a sweep does: the kept planes return, the evidence planes are zeroed
        // again where they held values, and the next frames reuse them.
        R->recycle(std::move(onDemand));
        Frame full = R->render(s, c.method);
        const nlohmann::json want = metricsOf(reference, full, lightName);
        R->recycle(std::move(full));
        EXPECT_EQ(got, want) << name << ", " << c.what << (t.partialEvidence ? " (partial)" : " (full)");
      }
    }
  }
  EXPECT_EQ(partial, expectedPartial) << "of " << frames << " frames";
  EXPECT_GT(partial, frames / 2);
  ASSERT_EQ(scenesPerCase.size(), all.size()) << "every case ran";
  for (const auto& [what, n] : scenesPerCase) EXPECT_GE(n, 3) << what;
}

// A selector that drops the disagreeing pixels (the rasterizer still resolves the fractional
// ones): their evidence is 0, in_map 0 classifies them as coverage, and the metrics differ.
TEST_F(OnDemand, ABrokenSelectorIsCaught) {
  REQUIRE_DEVICE();
  const Scene s = tinyScene("grazing");
  const std::string lightName = s.lights.front().name;
  const Frame reference = renderReference(s, ReferenceOptions{});
  const EvidenceSelector honest = disagreementSelector(reference, lightName);
  const EvidenceSelector broken = [](const uint8_t*, int, int, EvidenceRequest&) {};
  Method m;
  m.mapSize = 512;
  m.biasSlope = 0.0f;
  m.biasCompare = 0.0f;                                        // acne on the grazing ground
  R->recycle(R->render(s, m, "", nullptr, nullptr, &honest));  // keeps the group
  const nlohmann::json want = metricsOf(reference, R->render(s, m), lightName);
  ASSERT_GT(want["acne"].get<uint64_t>(), 100u);
  RasterTimings t;
  Frame frame = R->render(s, m, "", &t, nullptr, &honest);
  const nlohmann::json good = metricsOf(reference, frame, lightName);
  EXPECT_TRUE(t.partialEvidence);
  EXPECT_EQ(good, want);
  R->recycle(std::move(frame));  // hands the kept planes back, as a sweep does
  const nlohmann::json bad = metricsOf(reference, R->render(s, m, "", &t, nullptr, &broken), lightName);
  EXPECT_TRUE(t.partialEvidence);
  EXPECT_NE(bad, want);
  EXPECT_EQ(bad["acne"].get<uint64_t>(), 0u);
  EXPECT_EQ(bad["errors"], want["errors"]);  // the decisions are the same: only the classes move
}

}  // namespace compare_on_demand_test
