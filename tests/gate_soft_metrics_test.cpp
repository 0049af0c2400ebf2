// The gate reads the soft-shadow metrics (compare/METRICS.md "Soft shadows") with their built-in
// directions: the penumbra classes' counts and rates, the per-region mae / rmse and the signed
// over- and under-shadowing fail by rising; the region pixel counts by any move; within_uncertainty
// is reported, never failed. A region's mae and rmse are null where the row has no pixel of that
// region (a hard light's penumbra): both null pass, one null against a number is reported, and a
// null with pixels in the region is still a NaN. A baseline written before these metrics existed
// gates a current row that has them: they are new, the gate passes.
#include <gtest/gtest.h>

#include "shadowlab/compare/gate.h"
#include "shadowlab/scenes/error.h"

namespace shadowlab::gate_soft_metrics_test {
namespace {

ResultFile fileOf(const std::string& path, std::vector<ResultRow> rows) {
  ResultFile f;
  f.path = path;
  f.schema = "shadowlab.results/1";
  for (size_t i = 0; i < rows.size(); ++i) f.pointers.push_back("/rows/" + std::to_string(i));
  f.rows = std::move(rows);
  return f;
}

ResultRow row(const std::string& config, nlohmann::json metrics) {
  ResultRow r;
  r.scene = "penumbra";
  r.config = config;
  r.light = "sun";
  r.metrics = std::move(metrics);
  r.timings = nlohmann::json::object();
  return r;
}

const GateCheck& find(const GateResult& r, const std::string& metric) {
  for (const GateCheck& c : r.checks)
    if (c.metric == metric) return c;
  throw std::runtime_error("no check for " + metric);
}

TEST(GateSoftMetrics, BuiltInDirections) {
  for (const char* lower :
       {"penumbra_wide", "penumbra_wide_rate", "penumbra_hard", "penumbra_hard_rate", "lit_mae", "lit_rmse",
        "penumbra_mae", "penumbra_rmse", "umbra_mae", "umbra_rmse", "over_shadowing", "under_shadowing"}) {
    bool known = false;
    EXPECT_EQ(builtinDirection(lower, &known), Direction::LowerIsBetter) << lower;
    EXPECT_TRUE(known) << lower;
  }
  for (const char* equal : {"lit_pixels", "penumbra_pixels", "umbra_pixels"}) {
    bool known = false;
    EXPECT_EQ(builtinDirection(equal, &known), Direction::Equal) << equal;
    EXPECT_TRUE(known) << equal;
  }
  EXPECT_EQ(builtinDirection("within_uncertainty"), Direction::Ignore);
}

TEST(GateSoftMetrics, RisesFailFallsImproveUnderADefaultTolerance) {
  Tolerances t;
  t.fallback.absTolerance = 0.001;
  const nlohmann::json base = {{"pixels_compared", 100}, {"penumbra_pixels", 40},     {"penumbra_mae", 0.05},
                               {"over_shadowing", 0.02}, {"penumbra_hard_rate", 0.1}, {"within_uncertainty", 10}};
  nlohmann::json worse = base;
  worse["penumbra_mae"] = 0.06;
  worse["over_shadowing"] = 0.01;
  worse["penumbra_hard_rate"] = 0.2;
  worse["within_uncertainty"] = 30;
  GateResult r = runGate(fileOf("cur.json", {row("a", worse)}), fileOf("base.json", {row("a", base)}), t);
  EXPECT_EQ(find(r, "penumbra_mae").verdict, Verdict::Regressed);
  EXPECT_EQ(find(r, "penumbra_hard_rate").verdict, Verdict::Regressed);
  EXPECT_EQ(find(r, "over_shadowing").verdict, Verdict::Improved);
  EXPECT_EQ(find(r, "within_uncertainty").verdict, Verdict::Reported);
  EXPECT_EQ(r.regressions, 2);
  nlohmann::json moved = base;
  moved["penumbra_pixels"] = 41;
  GateResult m = runGate(fileOf("cur.json", {row("a", moved)}), fileOf("base.json", {row("a", base)}), t);
  EXPECT_EQ(find(m, "penumbra_pixels").verdict, Verdict::Regressed);
}

TEST(GateSoftMetrics, AnEmptyRegionsNullIsUndefinedNotNan) {
  const nlohmann::json hard = {{"pixels_compared", 100},   {"penumbra_pixels", 0}, {"penumbra_mae", nullptr},
                               {"penumbra_rmse", nullptr}, {"lit_pixels", 100},    {"lit_mae", 0.01}};
  GateResult same =
      runGate(fileOf("cur.json", {row("a", hard)}), fileOf("base.json", {row("a", hard)}), defaultTolerances());
  EXPECT_TRUE(same.passed());
  EXPECT_EQ(find(same, "penumbra_mae").verdict, Verdict::Pass);
  // The region appeared (a sized light now): reported with the pixel count's own check failing.
  nlohmann::json soft = hard;
  soft["penumbra_pixels"] = 30;
  soft["penumbra_mae"] = 0.04;
  soft["penumbra_rmse"] = 0.05;
  GateResult grew =
      runGate(fileOf("cur.json", {row("a", soft)}), fileOf("base.json", {row("a", hard)}), defaultTolerances());
  EXPECT_EQ(find(grew, "penumbra_mae").verdict, Verdict::Reported);
  EXPECT_EQ(find(grew, "penumbra_pixels").verdict, Verdict::Regressed);
  // A null where the region has pixels is a NaN: bad input naming the metric.
  nlohmann::json nan = soft;
  nan["penumbra_mae"] = nullptr;
  try {
    runGate(fileOf("cur.json", {row("a", nan)}), fileOf("base.json", {row("a", soft)}), defaultTolerances());
    ADD_FAILURE() << "a NaN passed";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("metric \"penumbra_mae\" is null (NaN)"), std::string::npos) << e.what();
  }
}

TEST(GateSoftMetrics, ABaselineWithoutThemPassesAsNewMetrics) {
  const nlohmann::json before = {{"pixels_compared", 100}, {"errors", 3}, {"error_rate", 0.03}};
  nlohmann::json now = before;
  for (const char* k : {"penumbra_wide", "penumbra_hard", "within_uncertainty", "penumbra_pixels"}) now[k] = 0;
  now["penumbra_mae"] = nullptr;
  now["over_shadowing"] = 0.01;
  GateResult r =
      runGate(fileOf("cur.json", {row("a", now)}), fileOf("base.json", {row("a", before)}), defaultTolerances());
  EXPECT_TRUE(r.passed());
  EXPECT_EQ(r.newMetrics, 6);
  EXPECT_EQ(find(r, "penumbra_mae").verdict, Verdict::New);
}

}  // namespace
}  // namespace shadowlab::gate_soft_metrics_test
