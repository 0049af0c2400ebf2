// `shadowlab gate` through the real binary: exit codes, the stderr lines CI shows, the table,
// JUnit XML (parsed, testcases and failures counted) and JSON, --update-baseline.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <OpenImageIO/detail/pugixml/pugixml.hpp>
#include <nlohmann/json.hpp>

namespace gate_cli_test {

namespace {

namespace fs = std::filesystem;

std::string slurp(const fs::path& p) {
  std::ifstream f(p);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

void spit(const fs::path& p, const std::string& text) { std::ofstream(p) << text; }

struct CliRun {
  int code = -1;
  std::string out, err;
};

// Two rows of a sweep, as `shadowlab sweep` writes them.
nlohmann::json baselineDoc() {
  return nlohmann::json::parse(R"({
    "schema": "shadowlab.results/1",
    "rows": [
      {"scene": "grazing", "config": "bias.slope=0", "light": "sun", "method": {"bias.slope": 0},
       "metrics": {"pixels_compared": 40000, "errors": 480, "acne": 480, "acne_rate": 0.012,
                   "leak_rate": 0.0, "shadow_iou": 0.95},
       "timings": {"shadow_gpu_ms": 0.4, "camera_gpu_ms": 2.0, "config_wall_ms": 20.0}},
      {"scene": "grazing", "config": "default", "light": "sun", "method": {},
       "metrics": {"pixels_compared": 40000, "errors": 40, "acne": 0, "acne_rate": 0.0,
                   "leak_rate": 0.001, "shadow_iou": 0.99},
       "timings": {"shadow_gpu_ms": 0.4, "camera_gpu_ms": 2.0, "config_wall_ms": 20.0}}
    ],
    "command_wall_seconds": 0.04, "configurations": 2
  })");
}

class GateCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("shadowlab_gate_cli_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    spit(dir_ / "base.json", baselineDoc().dump(2));
    spit(dir_ / "tol.json", R"(// The project's tolerances: acne may rise by half a percent of the pixels.
{
  "metrics": {
    "acne_rate": { "direction": "lower_is_better", "abs": 0.005 },
    "shadow_iou": { "abs": 0.01 }
  },
  "default": { "rel": 0.01 },
  "timing": "report"
})");
  }
  void TearDown() override {
    if (!HasFailure()) fs::remove_all(dir_);
  }

  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  // Writes a copy of the baseline with `edit` applied to it.
  std::string current(const std::string& name, const std::function<void(nlohmann::json&)>& edit) {
    nlohmann::json doc = baselineDoc();
    edit(doc);
    spit(dir_ / name, doc.dump(2));
    return path(name);
  }

  CliRun gate(const std::string& args) {
    CliRun r;
    std::string cmd =
        std::string(SHADOWLAB_BINARY) + " gate " + args + " >" + path("stdout.txt") + " 2>" + path("stderr.txt");
    int status = std::system(cmd.c_str());
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.out = slurp(dir_ / "stdout.txt");
    r.err = slurp(dir_ / "stderr.txt");
    return r;
  }

  fs::path dir_;
};

TEST_F(GateCli, DoctoredAcneRateFailsAndNamesTheMetric) {
  std::string cur = current("cur.json", [](nlohmann::json& d) { d["rows"][0]["metrics"]["acne_rate"] = 0.031; });
  CliRun r = gate(cur + " --baseline " + path("base.json") + " --tolerances " + path("tol.json") + " --junit " +
                  path("gate.xml") + " --json " + path("gate.json"));
  EXPECT_EQ(r.code, 1) << r.out << r.err;
  EXPECT_EQ(r.err,
            "shadowlab gate: error: grazing | bias.slope=0 | sun: metric \"acne_rate\" is 0.031, above the baseline "
            "0.012 + tolerance 0.005\n");
  EXPECT_NE(r.out.find("FAIL: 1 regression,"), std::string::npos) << r.out;
  // Regressions first: the first table line after the header is the regression.
  std::istringstream lines(r.out);
  std::string header, first;
  std::getline(lines, header);
  std::getline(lines, first);
  EXPECT_EQ(first.rfind("REGRESSED", 0), 0u) << r.out;
  EXPECT_NE(first.find("acne_rate"), std::string::npos);
  EXPECT_NE(first.find("0.031"), std::string::npos);

  // JUnit: 2 rows x (6 metrics + 3 timings) testcases, one failure naming the metric and values.
  OIIO::pugi::xml_document xml;
  auto parsed = xml.load_file(path("gate.xml").c_str());
  ASSERT_TRUE(parsed) << parsed.description();
  auto suites = xml.child("testsuites");
  ASSERT_TRUE(suites);
  EXPECT_STREQ(suites.attribute("tests").value(), "18");
  EXPECT_STREQ(suites.attribute("failures").value(), "1");
  int testcases = 0, failures = 0, suiteCount = 0;
  std::string failureMessage;
  for (auto suite : suites.children("testsuite")) {
    ++suiteCount;
    for (auto tc : suite.children("testcase")) {
      ++testcases;
      for (auto f : tc.children("failure")) {
        ++failures;
        failureMessage = f.attribute("message").value();
        EXPECT_STREQ(tc.attribute("name").value(), "acne_rate");
      }
    }
  }
  EXPECT_EQ(suiteCount, 2);
  EXPECT_EQ(testcases, 18);
  EXPECT_EQ(failures, 1);
  EXPECT_EQ(failureMessage,
            "grazing | bias.slope=0 | sun: metric \"acne_rate\" is 0.031, above the baseline 0.012 + tolerance 0.005");

  nlohmann::json j = nlohmann::json::parse(slurp(dir_ / "gate.json"));
  EXPECT_EQ(j["schema"], "shadowlab.gate/1");
  EXPECT_EQ(j["passed"], false);
  EXPECT_EQ(j["counts"]["regressions"], 1);
  EXPECT_EQ(j["checks"][0]["metric"], "acne_rate");
  EXPECT_EQ(j["checks"][0]["verdict"], "REGRESSED");
  EXPECT_DOUBLE_EQ(j["checks"][0]["current"].get<double>(), 0.031);
  EXPECT_DOUBLE_EQ(j["checks"][0]["baseline"].get<double>(), 0.012);
}

TEST_F(GateCli, RiseWithinTolerancePasses) {
  std::string cur = current("cur.json", [](nlohmann::json& d) { d["rows"][0]["metrics"]["acne_rate"] = 0.017; });
  CliRun r = gate(cur + " --baseline " + path("base.json") + " --tolerances " + path("tol.json"));
  EXPECT_EQ(r.code, 0) << r.out << r.err;
  EXPECT_EQ(r.err, "");
}

TEST_F(GateCli, ImprovementPasses) {
  std::string cur = current("cur.json", [](nlohmann::json& d) {
    d["rows"][0]["metrics"]["acne_rate"] = 0.002;
    d["rows"][0]["metrics"]["shadow_iou"] = 0.99;
  });
  CliRun r = gate(cur + " --baseline " + path("base.json") + " --tolerances " + path("tol.json"));
  EXPECT_EQ(r.code, 0) << r.out << r.err;
  EXPECT_EQ(r.err, "");
  EXPECT_NE(r.out.find("PASS: 0 regressions, 2 improved"), std::string::npos) << r.out;
}

TEST_F(GateCli, EqualPassesWithAndWithoutTolerances) {
  CliRun r = gate(path("base.json") + " --baseline " + path("base.json"));
  EXPECT_EQ(r.code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("PASS: 0 regressions, 0 improved, 12 within tolerance, 6 reported only, 0 new metrics; 2 rows "
                       "compared"),
            std::string::npos)
      << r.out;
  CliRun t = gate(path("base.json") + " --baseline " + path("base.json") + " --tolerances " + path("tol.json"));
  EXPECT_EQ(t.code, 0) << t.out << t.err;
}

TEST_F(GateCli, SlowerTimingsAreReportedNotFailedByDefault) {
  std::string cur = current("cur.json", [](nlohmann::json& d) { d["rows"][1]["timings"]["config_wall_ms"] = 80.0; });
  CliRun r = gate(cur + " --baseline " + path("base.json"));
  EXPECT_EQ(r.code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("80 (4.00x)"), std::string::npos) << r.out;
  // ... and fail when the tolerance file asks for it.
  spit(dir_ / "strict.json", R"({"timing": {"mode": "fail", "max_ratio": 2}})");
  CliRun s = gate(cur + " --baseline " + path("base.json") + " --tolerances " + path("strict.json"));
  EXPECT_EQ(s.code, 1) << s.out << s.err;
  EXPECT_EQ(
      s.err,
      "shadowlab gate: error: grazing | default | sun: timing \"config_wall_ms\" is 80 ms, 4.00x the baseline 20 ms, "
      "above the limit 2.00x\n");
}

TEST_F(GateCli, MetricsJsonAgainstResultsJson) {
  // A one-row metrics.json (shadowlab run) gates against the matching row of a results.json.
  nlohmann::json row = baselineDoc()["rows"][1];
  row["schema"] = "shadowlab.metrics/1";
  spit(dir_ / "metrics.json", row.dump(2));
  nlohmann::json one = baselineDoc();
  one["rows"].erase(0);
  spit(dir_ / "one.json", one.dump(2));
  CliRun r = gate(path("metrics.json") + " --baseline " + path("one.json"));
  EXPECT_EQ(r.code, 0) << r.out << r.err;
  // Against the two-row baseline the run's row is compared and the other counted as not run
  // (compare/GATE.md); a run matching no row of it is bad input, not a pass.
  CliRun m = gate(path("metrics.json") + " --baseline " + path("base.json"));
  EXPECT_EQ(m.code, 0) << m.out << m.err;
  EXPECT_NE(m.out.find("1 row compared, 0 new, 1 baseline row not run"), std::string::npos) << m.out;
  row["config"] = "map.size=7";
  spit(dir_ / "other.json", row.dump(2));
  CliRun none = gate(path("other.json") + " --baseline " + path("base.json"));
  EXPECT_EQ(none.code, 2) << none.out << none.err;
  EXPECT_NE(none.err.find("matches none of the 2 rows of the baseline"), std::string::npos) << none.err;
}

TEST_F(GateCli, MissingBaselineExits2AndWritesNothing) {
  CliRun r = gate(path("base.json") + " --baseline " + path("nope.json") + " --json " + path("gate.json") +
                  " --junit " + path("gate.xml"));
  EXPECT_EQ(r.code, 2) << r.out << r.err;
  EXPECT_EQ(
      r.err,
      path("nope.json") +
          ": error: baseline file not found; expected a metrics.json, results.json or stability.json (create it on "
          "purpose with --update-baseline)\n");
  EXPECT_FALSE(fs::exists(dir_ / "gate.json"));
  EXPECT_FALSE(fs::exists(dir_ / "gate.xml"));
}

TEST_F(GateCli, MissingRowExits2) {
  std::string cur = current("cur.json", [](nlohmann::json& d) { d["rows"].erase(1); });
  CliRun r = gate(cur + " --baseline " + path("base.json") + " --json " + path("gate.json"));
  EXPECT_EQ(r.code, 2) << r.out << r.err;
  EXPECT_EQ(r.err, path("base.json") +
                       ": /rows/1: error: row \"grazing | default | sun\" is in the baseline but "
                       "missing from " +
                       cur + "; expected every baseline row in the current results\n");
  EXPECT_FALSE(fs::exists(dir_ / "gate.json"));
}

TEST_F(GateCli, NewRowIsReportedAndPasses) {
  std::string cur = current("cur.json", [](nlohmann::json& d) {
    nlohmann::json extra = d["rows"][1];
    extra["config"] = "filter=pcf,filter.size=5";
    d["rows"].push_back(extra);
  });
  CliRun r = gate(cur + " --baseline " + path("base.json") + " --brief");
  EXPECT_EQ(r.code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("\nnew      grazing | filter=pcf,filter.size=5 | sun  (row)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("2 rows compared, 1 new"), std::string::npos) << r.out;
}

TEST_F(GateCli, MalformedToleranceFilesExit2) {
  std::string cur = path("base.json");
  spit(dir_ / "syntax.json", "{\n  \"metrics\": {\n    \"acne_rate\": { \"abs\": 0.005, }\n  }\n}\n");
  CliRun s = gate(cur + " --baseline " + cur + " --tolerances " + path("syntax.json"));
  EXPECT_EQ(s.code, 2) << s.out << s.err;
  EXPECT_EQ(s.err,
            path("syntax.json") +
                ":3:34: error: syntax error while parsing object key; unexpected '}'; expected string literal\n");
  EXPECT_EQ(s.out, "");  // no table: the gate did not run

  spit(dir_ / "negative.json", R"({"metrics": {"acne_rate": {"abs": -0.005}}})");
  CliRun n = gate(cur + " --baseline " + cur + " --tolerances " + path("negative.json"));
  EXPECT_EQ(n.code, 2);
  EXPECT_EQ(n.err, path("negative.json") +
                       ": /metrics/acne_rate/abs: error: got -0.005; expected a number >= 0 (a tolerance)\n");

  spit(dir_ / "unknown.json", R"({"metrics": {"acne_rate": {"abs": 0.1}}, "timings": "report"})");
  CliRun u = gate(cur + " --baseline " + cur + " --tolerances " + path("unknown.json"));
  EXPECT_EQ(u.code, 2);
  EXPECT_NE(u.err.find("/timings: error: unknown key \"timings\""), std::string::npos) << u.err;

  CliRun missing = gate(cur + " --baseline " + cur + " --tolerances " + path("absent.json"));
  EXPECT_EQ(missing.code, 2);
  EXPECT_NE(missing.err.find(path("absent.json")), std::string::npos) << missing.err;
}

// Timing names from before the glossary (compare/TIMINGS.md) are refused, naming the new one:
// `total_ms` meant another quantity in each file, so gating it would compare unlike things.
TEST_F(GateCli, RenamedTimingNamesExit2NamingTheNewName) {
  const std::string bad = std::string(SHADOWLAB_SOURCE_DIR) + "/tests/bad_input/";
  CliRun baseline = gate(path("base.json") + " --baseline " + bad + "timing_renamed_results.json");
  EXPECT_EQ(baseline.code, 2) << baseline.out << baseline.err;
  EXPECT_EQ(baseline.err, bad +
                              "timing_renamed_results.json: /rows/1/timings/camera_ms: error: \"camera_ms\" was "
                              "renamed; use \"camera_gpu_ms\" (timing names: compare/TIMINGS.md)\n");
  EXPECT_EQ(baseline.out, "");

  CliRun current = gate(bad + "timing_renamed_results.json --baseline " + path("base.json"));
  EXPECT_EQ(current.code, 2) << current.out << current.err;
  EXPECT_NE(current.err.find("/rows/1/timings/camera_ms: error:"), std::string::npos) << current.err;

  // In a stability.json, total_ms was the whole command.
  CliRun stability = gate(bad + "timing_renamed_stability.json --baseline " + bad + "timing_renamed_stability.json");
  EXPECT_EQ(stability.code, 2) << stability.out << stability.err;
  EXPECT_EQ(stability.err, bad +
                               "timing_renamed_stability.json: /timings/total_ms: error: \"total_ms\" was renamed; "
                               "use \"command_wall_ms\" (timing names: compare/TIMINGS.md)\n");

  CliRun tolerances = gate(path("base.json") + " --baseline " + path("base.json") + " --tolerances " + bad +
                           "timing_renamed_tolerances.json");
  EXPECT_EQ(tolerances.code, 2) << tolerances.out << tolerances.err;
  EXPECT_EQ(tolerances.err, bad +
                                "timing_renamed_tolerances.json: /metrics/total_ms: error: \"total_ms\" was "
                                "renamed; use \"config_wall_ms\" (timing names: compare/TIMINGS.md)\n");

  CliRun asMetric = gate(path("base.json") + " --baseline " + path("base.json") + " --tolerances " + bad +
                         "timing_as_metric_tolerances.json");
  EXPECT_EQ(asMetric.code, 2) << asMetric.out << asMetric.err;
  EXPECT_EQ(asMetric.err, bad +
                              "timing_as_metric_tolerances.json: /metrics/config_wall_ms: error: \"config_wall_ms\" "
                              "is a timing, not a metric; expected timings under \"timing\" (compare/GATE.md)\n");
}

TEST_F(GateCli, NanExits2) {
  // nlohmann writes NaN as null; the gate must not treat it as a pass.
  std::string cur = current("cur.json", [](nlohmann::json& d) { d["rows"][1]["metrics"]["acne_rate"] = nullptr; });
  CliRun r = gate(cur + " --baseline " + path("base.json"));
  EXPECT_EQ(r.code, 2) << r.out << r.err;
  EXPECT_EQ(r.err, cur + ": /rows/1/metrics/acne_rate: error: metric \"acne_rate\" is null (NaN); expected a number\n");
}

TEST_F(GateCli, MalformedResultFileExits2) {
  spit(dir_ / "bad.json", R"({"schema": "shadowlab.results/1", "rows": [{"scene": "grazing", "config": "default",
                             "light": 7, "metrics": {}}]})");
  CliRun r = gate(path("bad.json") + " --baseline " + path("base.json"));
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(r.err, path("bad.json") + ": /rows/0/light: error: got a number; expected a string\n");
}

TEST_F(GateCli, RepeatedRunsAreGatedByTheirMedianTiming) {
  // Three runs of the same sweep: config_wall_ms of row 0 is 20, 80 and 22 ms. The median (22) passes a
  // 1.5x timing gate that the one slow run alone would fail.
  auto runWith = [&](const std::string& name, double configWallMs) {
    return current(name, [&](nlohmann::json& d) { d["rows"][0]["timings"]["config_wall_ms"] = configWallMs; });
  };
  std::string runs = runWith("r1.json", 20.0) + " " + runWith("r2.json", 80.0) + " " + runWith("r3.json", 22.0);
  spit(dir_ / "strict.json", R"({"timing": {"mode": "fail", "max_ratio": 1.5}})");
  CliRun slowAlone =
      gate(path("r2.json") + " --baseline " + path("base.json") + " --tolerances " + path("strict.json"));
  EXPECT_EQ(slowAlone.code, 1) << slowAlone.out << slowAlone.err;
  CliRun median = gate(runs + " --baseline " + path("base.json") + " --tolerances " + path("strict.json"));
  EXPECT_EQ(median.code, 0) << median.out << median.err;
  EXPECT_NE(median.out.find("median of 3: 22 (1.10x)"), std::string::npos) << median.out;
}

TEST_F(GateCli, UsageErrorExits2) {
  CliRun r = gate(path("base.json"));  // no --baseline
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--baseline"), std::string::npos) << r.err;
}

TEST_F(GateCli, UpdateBaselineCreatesThenRewritesOnPurpose) {
  CliRun create = gate(path("base.json") + " --baseline " + path("golden.json") + " --update-baseline");
  EXPECT_EQ(create.code, 0) << create.out << create.err;
  EXPECT_NE(create.out.find("created baseline"), std::string::npos) << create.out;
  EXPECT_NE(create.out.find("+ grazing | default | sun: new row"), std::string::npos) << create.out;
  EXPECT_EQ(gate(path("base.json") + " --baseline " + path("golden.json")).code, 0);

  std::string cur = current("cur.json", [](nlohmann::json& d) { d["rows"][0]["metrics"]["acne_rate"] = 0.031; });
  EXPECT_EQ(gate(cur + " --baseline " + path("golden.json")).code, 1);
  CliRun update = gate(cur + " --baseline " + path("golden.json") + " --update-baseline");
  EXPECT_EQ(update.code, 0) << update.out << update.err;
  EXPECT_NE(update.out.find("~ grazing | bias.slope=0 | sun: metric \"acne_rate\" 0.012 -> 0.031"), std::string::npos)
      << update.out;
  EXPECT_EQ(gate(cur + " --baseline " + path("golden.json")).code, 0);

  // A current file with NaN never becomes a baseline; the old one stays as it was.
  std::string before = slurp(dir_ / "golden.json");
  std::string nan = current("nan.json", [](nlohmann::json& d) { d["rows"][0]["metrics"]["acne_rate"] = nullptr; });
  EXPECT_EQ(gate(nan + " --baseline " + path("golden.json") + " --update-baseline").code, 2);
  EXPECT_EQ(slurp(dir_ / "golden.json"), before);
}

TEST_F(GateCli, CorruptBaselineMetricIsBadInputNotARegression) {
  // A string, a negative count, a rate above 1: each is exit 2 naming the file and the pointer,
  // whichever side holds it; before, the string and the negative rate read as "REGRESSED" (exit 1).
  struct Case {
    const char* metric;
    nlohmann::json value;
    std::string expected;
  };
  const Case cases[] = {
      {"acne_rate", "0.1", "is the string \"0.1\"; expected a number in [0, 1] (a fraction of compared pixels)"},
      {"acne_rate", -0.5, "is -0.5; expected a number in [0, 1] (a fraction of compared pixels)"},
      {"shadow_iou", 1.5, "is 1.5; expected a number in [0, 1] (a fraction of compared pixels)"},
      {"errors", -3, "is -3; expected a number >= 0"},
  };
  for (const Case& c : cases) {
    const std::string doctored =
        current("doctored.json", [&](nlohmann::json& d) { d["rows"][1]["metrics"][c.metric] = c.value; });
    const std::string message =
        doctored + ": /rows/1/metrics/" + c.metric + ": error: metric \"" + c.metric + "\" " + c.expected + "\n";
    CliRun asBaseline = gate(path("base.json") + " --baseline " + doctored);
    EXPECT_EQ(asBaseline.code, 2) << c.metric << asBaseline.out << asBaseline.err;
    EXPECT_EQ(asBaseline.err, message);
    EXPECT_EQ(asBaseline.out, "");
    CliRun asCurrent = gate(doctored + " --baseline " + path("base.json"));
    EXPECT_EQ(asCurrent.code, 2) << c.metric << asCurrent.out << asCurrent.err;
    EXPECT_EQ(asCurrent.err, message);
  }
}

TEST_F(GateCli, NewMetricIsCountedInTheSummary) {
  const std::string cur = current("cur.json", [](nlohmann::json& d) { d["rows"][0]["metrics"]["m_capped"] = 12; });
  CliRun r = gate(cur + " --baseline " + path("base.json") + " --json " + path("gate.json"));
  EXPECT_EQ(r.code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("new      grazing | bias.slope=0 | sun  m_capped"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("reported only, 1 new metric; 2 rows compared, 0 new"), std::string::npos) << r.out;
  EXPECT_EQ(nlohmann::json::parse(slurp(dir_ / "gate.json"))["counts"]["new_metrics"], 1);
}

// The metrics of a row that compared nothing, as Metrics::toJson writes them.
void compareNothing(nlohmann::json& row) {
  nlohmann::json& m = row["metrics"];
  m = {{"pixels_compared", 0}, {"nothing_compared", true}, {"errors", 0},          {"acne", 0},
       {"acne_rate", nullptr}, {"leak_rate", nullptr},     {"shadow_iou", nullptr}};
}

TEST_F(GateCli, CurrentRowThatComparedNothingFails) {
  const std::string cur = current("cur.json", [](nlohmann::json& d) { compareNothing(d["rows"][1]); });
  CliRun r = gate(cur + " --baseline " + path("base.json") + " --junit " + path("gate.xml"));
  EXPECT_EQ(r.code, 1) << r.out << r.err;
  EXPECT_EQ(r.err, "shadowlab gate: error: grazing | default | sun: nothing was compared in " + cur +
                       " /rows/1 (pixels_compared 0: the camera sees no surface both renderers agree on); expected "
                       "compared pixels, 40000 in the baseline\n");
  EXPECT_NE(r.out.find("REGRESSED  grazing | default | sun"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("FAIL: 1 regression"), std::string::npos) << r.out;
  EXPECT_TRUE(fs::exists(dir_ / "gate.xml"));

  // A file of today's older writers says only pixels_compared 0 (rates 0, IoU 1): the same failure.
  const std::string old = current("old.json", [](nlohmann::json& d) {
    d["rows"][1]["metrics"] = {{"pixels_compared", 0}, {"errors", 0},      {"acne", 0},
                               {"acne_rate", 0.0},     {"leak_rate", 0.0}, {"shadow_iou", 1.0}};
  });
  CliRun o = gate(old + " --baseline " + path("base.json"));
  EXPECT_EQ(o.code, 1) << o.out << o.err;
  EXPECT_NE(o.err.find("nothing was compared in " + old), std::string::npos) << o.err;

  // A new row that compared nothing fails too: a new row is no pass by default when it scored nothing.
  const std::string added = current("added.json", [](nlohmann::json& d) {
    nlohmann::json row = d["rows"][1];
    row["config"] = "map.size=64";
    compareNothing(row);
    d["rows"].push_back(row);
  });
  CliRun n = gate(added + " --baseline " + path("base.json"));
  EXPECT_EQ(n.code, 1) << n.out << n.err;
  EXPECT_EQ(n.err, "shadowlab gate: error: grazing | map.size=64 | sun: nothing was compared in " + added +
                       " /rows/2 (pixels_compared 0: the camera sees no surface both renderers agree on); expected "
                       "compared pixels\n");
}

TEST_F(GateCli, BaselineThatComparesNothingExits2) {
  const std::string empty = current("empty.json", [](nlohmann::json& d) { compareNothing(d["rows"][0]); });
  CliRun r = gate(path("base.json") + " --baseline " + empty);
  EXPECT_EQ(r.code, 2) << r.out << r.err;
  EXPECT_EQ(r.err, empty +
                       ": /rows/0/metrics/pixels_compared: error: row \"grazing | bias.slope=0 | sun\" compares "
                       "nothing (pixels_compared 0); expected a baseline whose camera sees a surface both renderers "
                       "agree on\n");
  // Nor does such a file become a baseline.
  CliRun update = gate(empty + " --baseline " + path("new_base.json") + " --update-baseline");
  EXPECT_EQ(update.code, 2) << update.out << update.err;
  EXPECT_FALSE(fs::exists(dir_ / "new_base.json"));
}

TEST_F(GateCli, BaselineRowWithNoMetricsExits2) {
  // A baseline row with "metrics": {} compares nothing: every current metric would be "new" and the
  // gate would pass whatever the current run measured.
  const std::string empty =
      current("empty.json", [](nlohmann::json& d) { d["rows"][1]["metrics"] = nlohmann::json::object(); });
  CliRun r = gate(path("base.json") + " --baseline " + empty);
  EXPECT_EQ(r.code, 2) << r.out << r.err;
  EXPECT_EQ(r.err, empty +
                       ": /rows/1/metrics: error: row \"grazing | default | sun\" has no metrics (got {}); expected "
                       "the metrics of a run to gate against\n");
  EXPECT_EQ(r.out.find("PASS"), std::string::npos) << r.out;
  // Nor does such a file become a baseline.
  CliRun update = gate(empty + " --baseline " + path("new_base.json") + " --update-baseline");
  EXPECT_EQ(update.code, 2) << update.out << update.err;
  EXPECT_FALSE(fs::exists(dir_ / "new_base.json"));
}

TEST_F(GateCli, AllFootprintsCappedLeavesTheStatisticsUndefinedNotNan) {
  // Every compared pixel's m at the cap: m_median/m_p95/m_max are null by definition, which is
  // no NaN; null in both passes, m_capped gates the change.
  auto capped = [](nlohmann::json& row) {
    nlohmann::json& m = row["metrics"];
    m["m_capped"] = m["pixels_compared"];
    for (const char* k : {"m_median", "m_p95", "m_max"}) m[k] = nullptr;
  };
  const std::string both = current("both.json", [&](nlohmann::json& d) { capped(d["rows"][0]); });
  CliRun r = gate(both + " --baseline " + both);
  EXPECT_EQ(r.code, 0) << r.out << r.err;
  // A null m_p95 without every pixel capped is a NaN as before.
  const std::string nan = current("nan.json", [&](nlohmann::json& d) {
    capped(d["rows"][0]);
    d["rows"][0]["metrics"]["m_capped"] = 7;
  });
  CliRun n = gate(nan + " --baseline " + nan);
  EXPECT_EQ(n.code, 2) << n.out << n.err;
  EXPECT_NE(n.err.find("/rows/0/metrics/m_max: error: metric \"m_max\" is null (NaN)"), std::string::npos) << n.err;
}

TEST_F(GateCli, UpdateBaselineCreatesItsFolder) {
  // The first baseline of a fresh checkout: --baseline out/base/metrics.json, out/base missing.
  CliRun r = gate(path("base.json") + " --baseline " + path("out/base/metrics.json") + " --update-baseline");
  EXPECT_EQ(r.code, 0) << r.out << r.err;
  EXPECT_EQ(nlohmann::json::parse(slurp(dir_ / "out/base/metrics.json"))["rows"].size(), 2u);
  EXPECT_EQ(gate(path("base.json") + " --baseline " + path("out/base/metrics.json")).code, 0);
  // A refused update leaves no folder behind.
  const std::string nan =
      current("nan.json", [](nlohmann::json& d) { d["rows"][0]["metrics"]["acne_rate"] = nullptr; });
  EXPECT_EQ(gate(nan + " --baseline " + path("other/base/metrics.json") + " --update-baseline").code, 2);
  EXPECT_FALSE(fs::exists(dir_ / "other"));
}

}  // namespace

}  // namespace gate_cli_test
