// The floor of the blind rule's agreement with the full one (compare/METRICS.md "Frames from other
// renderers"): the main job's sweep (compare/report/default_sweep.json, 497 rows over every bundled
// scene) at half each camera's size, rastered, classified with all the raster's evidence and as a
// frame from another renderer (vis alone, the light layers and map size declared). At least 94 % of
// the wrong pixels get the same class, and no class loses more than 20 % of its pixels to one
// other class. bench/blind_agreement_bench.cpp prints the whole matrix (the same loop).
#include <string>

#include <gtest/gtest.h>

#include "shadowlab/compare/blind_agreement.h"
#include "shadowlab/compare/sweep.h"
#include "shadowlab/reference/reference.h"
#include "support/raster_device.h"

namespace shadowlab::compare_blind_agreement_test {
namespace {

TEST(BlindAgreement, TheMainJobsWrongPixelsGetTheFullRulesClass) {
  REQUIRE_DEVICE();
  SweepSpec spec;
  loadSweepFile(std::string(SHADOWLAB_SOURCE_DIR) + "/compare/report/default_sweep.json", spec);
  const SweepPlan plan = planSweep(spec);
  ClassConfusion total;
  size_t lastVariant = size_t(-1);
  std::string lastLight;
  Scene scene;
  Frame truth;
  for (const SweepJob& job : plan.jobs) {
    if (job.variantIndex != lastVariant || job.light != lastLight) {
      scene = plan.variants[job.variantIndex];
      scene.camera.width /= 2;
      scene.camera.height /= 2;
      ReferenceOptions ro;
      ro.channels = ReferenceChannels::All;
      ro.lightSamples = spec.lightSamples;
      truth = renderReference(scene, ro);
      lastVariant = job.variantIndex;
      lastLight = job.light;
    }
    const Method& method = plan.configs[job.configIndex].method;
    const Frame raster = R->render(scene, method, job.light);
    CompareOptions options;
    options.light = job.light;
    addBlindAgreement(truth, raster, declaredByRaster(*R, method), total, options);
  }
  ASSERT_GT(total.wrong(), 100000u) << "the main job has wrong pixels to classify";
  const double same = double(total.agreeing()) / double(total.wrong());
  PixelClass full = PixelClass::Other, blind = PixelClass::Other;
  const double worst = total.worstConfusion(&full, &blind);
  EXPECT_GE(same, 0.94) << total.markdown();
  EXPECT_LE(worst, 0.20) << classInfo(full).key << " read as " << classInfo(blind).key << "\n" << total.markdown();
}

}  // namespace
}  // namespace shadowlab::compare_blind_agreement_test
