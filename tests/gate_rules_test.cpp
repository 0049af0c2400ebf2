// The gate's rules in memory: tolerance parsing, fallbacks, verdicts at and beyond the limits.
// The CLI end (exit codes, messages, files) is in gate_cli_test.cpp.
#include <gtest/gtest.h>

#include "shadowlab/compare/gate.h"
#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/json_reader.h"

namespace shadowlab::gate_rules_test {
namespace {

ResultFile fileOf(const std::string& path, std::vector<ResultRow> rows) {
  ResultFile f;
  f.path = path;
  f.schema = "shadowlab.results/1";
  for (size_t i = 0; i < rows.size(); ++i) f.pointers.push_back("/rows/" + std::to_string(i));
  f.rows = std::move(rows);
  return f;
}

ResultRow row(const std::string& config, nlohmann::json metrics, nlohmann::json timings = nlohmann::json::object()) {
  ResultRow r;
  r.scene = "grazing";
  r.config = config;
  r.light = "sun";
  r.metrics = std::move(metrics);
  r.timings = std::move(timings);
  return r;
}

const GateCheck& find(const GateResult& r, const std::string& metric, const std::string& config = "") {
  for (const GateCheck& c : r.checks)
    if (c.metric == metric && (config.empty() || c.config == config)) return c;
  throw std::runtime_error("no check for " + metric);
}

std::string inputErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no InputError)";
}

Tolerances tolerances(const std::string& text) { return parseTolerances(parseJsonText(text, "tol.json"), "tol.json"); }

TEST(GateRules, LowerIsBetterFailsOnlyBeyondMaxOfAbsAndRel) {
  // allowed = max(0.005, 0.1 * 0.012) = 0.005: 0.017 is the edge, 0.0171 is over it.
  Tolerances t = tolerances(R"({"metrics": {"acne_rate": {"abs": 0.005, "rel": 0.1}}})");
  ResultFile base = fileOf("base.json", {row("a", {{"acne_rate", 0.012}}), row("b", {{"acne_rate", 0.012}}),
                                         row("c", {{"acne_rate", 0.012}})});
  ResultFile cur = fileOf("cur.json", {row("a", {{"acne_rate", 0.017}}), row("b", {{"acne_rate", 0.0171}}),
                                       row("c", {{"acne_rate", 0.006}})});
  GateResult r = runGate(cur, base, t);
  EXPECT_EQ(find(r, "acne_rate", "a").verdict, Verdict::Pass);
  EXPECT_EQ(find(r, "acne_rate", "b").verdict, Verdict::Regressed);
  EXPECT_EQ(find(r, "acne_rate", "c").verdict, Verdict::Improved);
  EXPECT_EQ(r.regressions, 1);
  EXPECT_EQ(r.improvements, 1);
  EXPECT_FALSE(r.passed());
  EXPECT_EQ(find(r, "acne_rate", "b").message,
            "grazing | b | sun: metric \"acne_rate\" is 0.0171, above the baseline 0.012 + tolerance 0.005");
  // Regressions come first in the table order.
  EXPECT_EQ(r.checks.front().verdict, Verdict::Regressed);
}

TEST(GateRules, RelativeToleranceScalesWithTheBaseline) {
  // errors: allowed = max(0, 0.1 * 200) = 20 pixels.
  Tolerances t = tolerances(R"({"metrics": {"errors": {"rel": 0.1}}})");
  GateResult ok = runGate(fileOf("c", {row("a", {{"errors", 220}})}), fileOf("b", {row("a", {{"errors", 200}})}), t);
  GateResult bad = runGate(fileOf("c", {row("a", {{"errors", 221}})}), fileOf("b", {row("a", {{"errors", 200}})}), t);
  EXPECT_TRUE(ok.passed());
  EXPECT_FALSE(bad.passed());
}

TEST(GateRules, HigherIsBetterAndEqualAndIgnore) {
  Tolerances t = tolerances(R"({
    "metrics": {"shadow_iou": {"abs": 0.01}, "pixels_compared": {"abs": 2}, "m_max": {"direction": "ignore"}}
  })");
  ResultFile base = fileOf("b", {row("a", {{"shadow_iou", 0.95}, {"pixels_compared", 1000}, {"m_max", 3.0}})});
  ResultFile worse = fileOf("c", {row("a", {{"shadow_iou", 0.93}, {"pixels_compared", 997}, {"m_max", 90.0}})});
  ResultFile better = fileOf("c", {row("a", {{"shadow_iou", 0.99}, {"pixels_compared", 1002}, {"m_max", 0.5}})});
  GateResult w = runGate(worse, base, t);
  EXPECT_EQ(find(w, "shadow_iou").verdict, Verdict::Regressed);
  EXPECT_EQ(find(w, "shadow_iou").message,
            "grazing | a | sun: metric \"shadow_iou\" is 0.93, below the baseline 0.95 - tolerance 0.01");
  EXPECT_EQ(find(w, "pixels_compared").verdict, Verdict::Regressed);  // equal: either way fails
  EXPECT_EQ(find(w, "m_max").verdict, Verdict::Reported);
  EXPECT_EQ(w.regressions, 2);
  GateResult b = runGate(better, base, t);
  EXPECT_EQ(find(b, "shadow_iou").verdict, Verdict::Improved);
  EXPECT_EQ(find(b, "pixels_compared").verdict, Verdict::Pass);  // moved by 2, tolerance 2
  EXPECT_TRUE(b.passed());
}

TEST(GateRules, ListedMetricsUseTheirEntryOnlyUnlistedUseTheDefault) {
  Tolerances t = tolerances(R"({"default": {"abs": 0.5, "rel": 0.1}, "metrics": {"acne_rate": {"rel": 0.2}}})");
  MetricTolerance acne = t.forMetric("acne_rate");
  EXPECT_EQ(acne.direction, Direction::LowerIsBetter);  // built-in
  EXPECT_DOUBLE_EQ(acne.relTolerance, 0.2);
  EXPECT_DOUBLE_EQ(acne.absTolerance, 0.0);         // left out of the entry: 0, not the default's 0.5
  MetricTolerance leak = t.forMetric("leak_rate");  // not listed: the default
  EXPECT_EQ(leak.direction, Direction::LowerIsBetter);
  EXPECT_DOUBLE_EQ(leak.absTolerance, 0.5);
  EXPECT_DOUBLE_EQ(leak.relTolerance, 0.1);
  EXPECT_EQ(t.forMetric("shadow_iou").direction, Direction::HigherIsBetter);
  EXPECT_EQ(t.forMetric("pixels_compared").direction, Direction::Equal);
  EXPECT_EQ(t.forMetric("some_new_thing").direction, Direction::Equal);
  EXPECT_EQ(t.forMetric("thing_rate").direction, Direction::LowerIsBetter);
  Tolerances all = tolerances(R"({"default": {"direction": "ignore"}})");
  EXPECT_EQ(all.forMetric("acne_rate").direction, Direction::Ignore);
  // Defaults: exact up to 1e-9 relative.
  Tolerances d = defaultTolerances();
  EXPECT_DOUBLE_EQ(d.forMetric("acne_rate").allowed(0.5), 0.5e-9);
  EXPECT_EQ(d.timing.mode, TimingMode::Report);
}

TEST(GateRules, DefaultToleranceFailsAnyRiseAndPassesEqual) {
  ResultFile base = fileOf("b", {row("a", {{"acne_rate", 0.012}, {"shadow_iou", 0.9}})});
  ResultFile same = fileOf("c", {row("a", {{"acne_rate", 0.012}, {"shadow_iou", 0.9}})});
  ResultFile rise = fileOf("c", {row("a", {{"acne_rate", 0.0121}, {"shadow_iou", 0.9}})});
  EXPECT_TRUE(runGate(same, base, defaultTolerances()).passed());
  GateResult r = runGate(rise, base, defaultTolerances());
  EXPECT_EQ(r.regressions, 1);
  EXPECT_EQ(find(r, "acne_rate").verdict, Verdict::Regressed);
}

TEST(GateRules, TimingsReportByDefaultAndFailOnlyWhenAsked) {
  ResultFile base = fileOf("b", {row("a", {{"acne_rate", 0.0}}, {{"config_wall_ms", 20.0}, {"compare_ms", 0.2}})});
  ResultFile slow = fileOf("c", {row("a", {{"acne_rate", 0.0}}, {{"config_wall_ms", 45.0}, {"compare_ms", 0.9}})});
  GateResult reported = runGate(slow, base, defaultTolerances());
  EXPECT_TRUE(reported.passed());
  EXPECT_EQ(find(reported, "config_wall_ms").verdict, Verdict::Reported);
  Tolerances fail = tolerances(R"({"timing": {"mode": "fail", "max_ratio": 2.0}})");
  GateResult failed = runGate(slow, base, fail);
  EXPECT_EQ(find(failed, "config_wall_ms").verdict, Verdict::Regressed);  // 2.25x > 2.00x
  EXPECT_EQ(find(failed, "config_wall_ms").message,
            "grazing | a | sun: timing \"config_wall_ms\" is 45 ms, 2.25x the baseline 20 ms, above the limit 2.00x");
  EXPECT_EQ(find(failed, "compare_ms").verdict, Verdict::Reported);  // 4.5x, but under min_ms 1
  EXPECT_EQ(failed.regressions, 1);
  Tolerances lenient = tolerances(R"({"timing": {"mode": "fail", "max_ratio": 2.5}})");
  EXPECT_TRUE(runGate(slow, base, lenient).passed());
}

TEST(GateRules, NonNumericMetricsMustBeEqual) {
  ResultFile base = fileOf("b", {row("a", {{"has_projector", true}})});
  ResultFile cur = fileOf("c", {row("a", {{"has_projector", false}})});
  GateResult r = runGate(cur, base, defaultTolerances());
  EXPECT_EQ(find(r, "has_projector").verdict, Verdict::Regressed);
}

TEST(GateRules, NestedMetricsAreComparedLeafByLeaf) {
  ResultFile base = fileOf("b", {row("a", {{"per_light", {{"sun", {{"acne_rate", 0.01}}}}}})});
  ResultFile cur = fileOf("c", {row("a", {{"per_light", {{"sun", {{"acne_rate", 0.02}}}}}})});
  GateResult r = runGate(cur, base, defaultTolerances());
  EXPECT_EQ(find(r, "per_light.sun.acne_rate").verdict, Verdict::Regressed);
}

TEST(GateRules, MissingRowMissingMetricNanAndDuplicatesAreInputErrors) {
  ResultFile base = fileOf("base.json", {row("a", {{"acne_rate", 0.01}}), row("b", {{"acne_rate", 0.01}})});
  std::string missingRow = inputErrorOf([&] {
    runGate(fileOf("cur.json", {row("a", {{"acne_rate", 0.01}})}), base, defaultTolerances());
  });
  EXPECT_EQ(missingRow,
            "base.json: /rows/1: error: row \"grazing | b | sun\" is in the baseline but missing from cur.json; "
            "expected every baseline row in the current results");
  std::string missingMetric = inputErrorOf([&] {
    runGate(fileOf("cur.json", {row("a", {{"acne_rate", 0.01}}), row("b", {{"leak_rate", 0.0}})}), base,
            defaultTolerances());
  });
  EXPECT_NE(missingMetric.find("cur.json: /rows/1/metrics: error: row \"grazing | b | sun\" has no metric "
                               "\"acne_rate\""),
            std::string::npos)
      << missingMetric;
  std::string nan = inputErrorOf([&] {
    runGate(fileOf("cur.json", {row("a", {{"acne_rate", 0.01}}), row("b", {{"acne_rate", nullptr}})}), base,
            defaultTolerances());
  });
  EXPECT_EQ(nan, "cur.json: /rows/1/metrics/acne_rate: error: metric \"acne_rate\" is null (NaN); expected a number");
  std::string dup = inputErrorOf([&] {
    runGate(fileOf("cur.json", {row("a", {{"acne_rate", 0.01}}), row("a", {{"acne_rate", 0.01}})}), base,
            defaultTolerances());
  });
  EXPECT_NE(dup.find("cur.json: /rows/1: error: row \"grazing | a | sun\" appears again (first at /rows/0)"),
            std::string::npos)
      << dup;
}

TEST(GateRules, RepeatedRunsGateTheMedianTiming) {
  // Three runs of the same configuration (one per file): timings 30, 90, 33 ms -> median 33, so
  // one noisy run does not fail a 1.5x timing gate against a 30 ms baseline.
  auto run = [](const std::string& path, double configWallMs) {
    return fileOf(path, {row("a", {{"acne_rate", 0.01}}, {{"config_wall_ms", configWallMs}})});
  };
  ResultFile merged = mergeResultFiles({run("r1.json", 30.0), run("r2.json", 90.0), run("r3.json", 33.0)});
  ASSERT_EQ(merged.rows.size(), 1u);
  EXPECT_EQ(merged.repeatsOf(0), 3);
  EXPECT_DOUBLE_EQ(merged.rows[0].timings["config_wall_ms"].get<double>(), 33.0);
  Tolerances fail = tolerances(R"({"timing": {"mode": "fail", "max_ratio": 1.5}})");
  GateResult r = runGate(merged, run("base.json", 30.0), fail);
  EXPECT_TRUE(r.passed());
  EXPECT_EQ(find(r, "config_wall_ms").samples, 3);
  // Even count: the mean of the middle two.
  ResultFile two = mergeResultFiles({run("r1.json", 30.0), run("r2.json", 90.0)});
  EXPECT_DOUBLE_EQ(two.rows[0].timings["config_wall_ms"].get<double>(), 60.0);
  GateResult slow = runGate(two, run("base.json", 30.0), fail);
  EXPECT_EQ(find(slow, "config_wall_ms").verdict, Verdict::Regressed);
  EXPECT_EQ(find(slow, "config_wall_ms").message,
            "grazing | a | sun: timing \"config_wall_ms\" is 60 ms (median of 2 runs), 2.00x the baseline 30 ms, above "
            "the limit 1.50x");
}

TEST(GateRules, RepeatedRunsMustAgreeOnMetrics) {
  ResultFile a = fileOf("r1.json", {row("a", {{"acne_rate", 0.01}})});
  ResultFile b = fileOf("r2.json", {row("a", {{"acne_rate", 0.02}})});
  EXPECT_EQ(inputErrorOf([&] {
              mergeResultFiles({a, b});
            }),
            "r2.json: /rows/0/metrics/acne_rate: error: row \"grazing | a | sun\" repeats the run in r1.json but "
            "metric \"acne_rate\" is 0.02 here and 0.01 there; expected repeated runs to agree (the pipeline is "
            "deterministic)");
  // Twice in one file is not a repeat but a malformed file.
  ResultFile dup = fileOf("r3.json", {row("a", {{"acne_rate", 0.01}}), row("a", {{"acne_rate", 0.01}})});
  EXPECT_NE(inputErrorOf([&] {
              mergeResultFiles({a, dup});
            })
                .find("r3.json: /rows/1: error: row \"grazing | a | sun\" "
                      "appears again (first at /rows/0)"),
            std::string::npos);
  // Distinct rows from several files are simply concatenated, each naming its own file.
  ResultFile c = fileOf("r4.json", {row("z", {{"acne_rate", 0.01}})});
  ResultFile merged = mergeResultFiles({a, c});
  ASSERT_EQ(merged.rows.size(), 2u);
  EXPECT_EQ(merged.pathOf(1), "r4.json");
  EXPECT_EQ(merged.repeatsOf(1), 1);
}

TEST(GateRules, EmptyBaselineIsAnInputError) {
  ResultFile empty = fileOf("base.json", {});
  EXPECT_EQ(inputErrorOf([&] {
              runGate(fileOf("c", {row("a", {{"acne_rate", 0.01}})}), empty, defaultTolerances());
            }),
            "base.json: /rows: error: the baseline has no rows; expected at least one (create it with "
            "--update-baseline)");
}

TEST(GateRules, NewRowsAndMetricsAreReportedNotFailed) {
  ResultFile base = fileOf("b", {row("a", {{"acne_rate", 0.01}})});
  ResultFile cur = fileOf("c", {row("a", {{"acne_rate", 0.01}, {"leak_rate", 0.5}}), row("z", {{"acne_rate", 0.9}})});
  GateResult r = runGate(cur, base, defaultTolerances());
  EXPECT_TRUE(r.passed());
  EXPECT_EQ(r.rowsNew, 1);
  EXPECT_EQ(r.rowsCompared, 1);
  EXPECT_EQ(find(r, "leak_rate").verdict, Verdict::New);
  // The new metric is in the summary's counts, not in none of them.
  EXPECT_EQ(r.newMetrics, 1);
  EXPECT_NE(r.summary().find("1 new metric;"), std::string::npos) << r.summary();
}

TEST(GateRules, MalformedTolerancesNameFileAndPlace) {
  EXPECT_EQ(inputErrorOf([] { tolerances(R"({"metrics": {"acne_rate": {"abs": -0.1}}})"); }),
            "tol.json: /metrics/acne_rate/abs: error: got -0.1; expected a number >= 0 (a tolerance)");
  EXPECT_EQ(inputErrorOf([] { tolerances(R"({"metrics": {"acne_rate": {"abs": "0.1"}}})"); }),
            "tol.json: /metrics/acne_rate/abs: error: got a string; expected a number >= 0");
  EXPECT_EQ(inputErrorOf([] { tolerances(R"({"metrics": {"acne_rate": {"direction": "down"}}})"); }),
            "tol.json: /metrics/acne_rate/direction: error: got \"down\"; expected \"lower_is_better\", "
            "\"higher_is_better\", \"equal\" or \"ignore\"");
  EXPECT_EQ(inputErrorOf([] { tolerances(R"({"metrics": {"acne_rate": {"absolute": 1}}})"); }),
            "tol.json: /metrics/acne_rate/absolute: error: unknown key \"absolute\"; expected \"direction\", "
            "\"abs\" or \"rel\"");
  EXPECT_EQ(inputErrorOf([] { tolerances(R"({"timings": "report"})"); }),
            "tol.json: /timings: error: unknown key \"timings\"; expected \"schema\", \"default\", \"metrics\" or "
            "\"timing\"");
  EXPECT_EQ(inputErrorOf([] { tolerances(R"({"timing": {"mode": "fail", "max_ratio": 0.5}})"); }),
            "tol.json: /timing/max_ratio: error: got 0.5; expected a number >= 1 (current/baseline time)");
  EXPECT_EQ(inputErrorOf([] { tolerances(R"({"timing": "sometimes"})"); }),
            "tol.json: /timing: error: got \"sometimes\"; expected \"report\" or \"fail\"");
  // Syntax errors carry line:col (comments are fine, a trailing comma is not).
  EXPECT_EQ(inputErrorOf([] { tolerances("// ok\n{\n  \"metrics\": {},\n}\n"); }),
            "tol.json:4:1: error: syntax error while parsing object key; unexpected '}'; expected string literal");
  // A tolerance for a metric no row has (a typo) is caught when gating.
  Tolerances typo = tolerances(R"({"metrics": {"acne_rat": {"abs": 1}}})");
  ResultFile f = fileOf("b", {row("a", {{"acne_rate", 0.01}})});
  EXPECT_EQ(inputErrorOf([&] { runGate(f, f, typo); }),
            "tol.json: /metrics/acne_rat: error: no row has a metric \"acne_rat\"; expected one of: acne_rate");
}

TEST(GateRules, MessagesNeverPrintTwoDifferentValuesAlike) {
  // Exact default tolerance failing in the 9th digit: the message must show the difference.
  ResultFile base = fileOf("b", {row("a", {{"mae", 0.1}})});
  ResultFile cur = fileOf("c", {row("a", {{"mae", 0.10000001}})});
  GateResult r = runGate(cur, base, defaultTolerances());
  ASSERT_EQ(r.regressions, 1);
  EXPECT_NE(find(r, "mae").message.find("is 0.10000001, above the baseline 0.1 +"), std::string::npos)
      << find(r, "mae").message;
}

TEST(GateRules, JunitCountsTestcasesAndFailures) {
  Tolerances t = tolerances(R"({"metrics": {"acne_rate": {"abs": 0.005}}})");
  ResultFile base = fileOf("b", {row("a", {{"acne_rate", 0.01}, {"shadow_iou", 0.9}}, {{"config_wall_ms", 3.0}}),
                                 row("b", {{"acne_rate", 0.01}})});
  ResultFile cur = fileOf("c", {row("a", {{"acne_rate", 0.02}, {"shadow_iou", 0.9}}, {{"config_wall_ms", 3.1}}),
                                row("b", {{"acne_rate", 0.01}})});
  GateResult r = runGate(cur, base, t);
  std::string xml = gateToJunitXml(r);
  auto count = [&](const std::string& needle) {
    size_t n = 0;
    for (size_t p = xml.find(needle); p != std::string::npos; p = xml.find(needle, p + 1)) ++n;
    return n;
  };
  EXPECT_EQ(count("<testcase "), 4u);  // 3 metrics + 1 timing
  EXPECT_EQ(count("<failure "), 1u);
  EXPECT_EQ(count("<testsuite "), 2u);
  EXPECT_NE(xml.find("<testsuites name=\"shadowlab gate\" tests=\"4\" failures=\"1\""), std::string::npos);
  EXPECT_NE(xml.find("metric &quot;acne_rate&quot; is 0.02, above the baseline 0.01 + tolerance 0.005"),
            std::string::npos)
      << xml;
}

}  // namespace
}  // namespace shadowlab::gate_rules_test
