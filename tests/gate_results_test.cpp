// Result rows on disk: metrics.json round trip, results.json rows, and the errors that name the
// file and JSON pointer of a malformed value.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "shadowlab/compare/gate.h"
#include "shadowlab/compare/results.h"
#include "shadowlab/scenes/error.h"

namespace shadowlab::gate_results_test {
namespace {

namespace fs = std::filesystem;

class Results : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("shadowlab_gate_results_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string write(const std::string& name, const std::string& text) {
    std::ofstream((dir_ / name)) << text;
    return (dir_ / name).string();
  }
  std::string errorOf(const std::string& path) {
    try {
      loadResultRows(path);
    } catch (const InputError& e) {
      return e.what();
    }
    return "(no InputError)";
  }
  fs::path dir_;
};

TEST_F(Results, MetricsJsonRoundTrips) {
  ResultRow row;
  row.scene = "contact";
  row.config = "bias.slope=0,map.size=512";
  row.light = "sun";
  row.method = {{"bias.slope", 0.0}, {"map.size", 512}};
  row.metrics = {{"acne_rate", 0.0123456789012345}, {"pixels_compared", 40000u}, {"shadow_iou", 0.9}};
  row.timings = {{"config_wall_ms", 12.5}};
  std::string path = (dir_ / "metrics.json").string();
  writeMetricsJson(path, row);
  ResultFile f = loadResultFile(path);
  EXPECT_EQ(f.schema, "shadowlab.metrics/1");
  ASSERT_EQ(f.rows.size(), 1u);
  EXPECT_EQ(f.pointers[0], "");
  const ResultRow& back = f.rows[0];
  EXPECT_EQ(back.key(), "contact | bias.slope=0,map.size=512 | sun");
  EXPECT_EQ(back.method, row.method);
  EXPECT_EQ(back.metrics, row.metrics);  // doubles survive the decimal round trip bit for bit
  EXPECT_EQ(back.timings, row.timings);
  EXPECT_EQ(ResultRow::fromJson(row.toJson(), "mem").toJson(), row.toJson());
}

TEST_F(Results, ResultsJsonRowsKeepOrderAndPointers) {
  std::string path = write("results.json", R"({
    // sweeps may add summary keys; rows are what the gate reads
    "schema": "shadowlab.results/1", "command_wall_seconds": 1.5, "configurations": 2,
    "rows": [
      {"scene": "a", "config": "default", "light": "sun", "metrics": {"acne_rate": 0.1}},
      {"scene": "a", "config": "filter=pcf", "light": "sun", "metrics": {"acne_rate": 0.0}, "timings": {"config_wall_ms": 3}}
    ]})");
  ResultFile f = loadResultFile(path);
  ASSERT_EQ(f.rows.size(), 2u);
  EXPECT_EQ(f.rows[1].config, "filter=pcf");
  EXPECT_EQ(f.pointers[1], "/rows/1");
  EXPECT_DOUBLE_EQ(f.rows[1].timings["config_wall_ms"].get<double>(), 3.0);
  EXPECT_EQ(f.document["configurations"], 2);
}

TEST_F(Results, MalformedFilesNameFileAndPlace) {
  std::string noSchema = write("a.json", R"({"scene": "a", "config": "default", "light": "sun", "metrics": {}})");
  EXPECT_EQ(errorOf(noSchema), noSchema +
                                   ": error: missing \"schema\"; expected \"shadowlab.metrics/1\" "
                                   "(metrics.json), \"shadowlab.results/1\" (results.json) or "
                                   "\"shadowlab.stability/1\" (stability.json)");
  std::string badSchema = write("b.json", R"({"schema": "shadowlab.results/2", "rows": []})");
  EXPECT_EQ(errorOf(badSchema), badSchema +
                                    ": /schema: error: got \"shadowlab.results/2\"; expected "
                                    "\"shadowlab.metrics/1\", \"shadowlab.results/1\" or "
                                    "\"shadowlab.stability/1\"");
  std::string noMetrics = write("c.json", R"({"schema": "shadowlab.results/1", "rows": [
      {"scene": "a", "config": "default", "light": "sun"}]})");
  EXPECT_EQ(errorOf(noMetrics), noMetrics + ": /rows/0: error: missing \"metrics\"; expected an object");
  std::string badTiming = write("d.json", R"({"schema": "shadowlab.metrics/1", "scene": "a", "config": "default",
      "light": "sun", "metrics": {}, "timings": {"config_wall_ms": "fast"}})");
  EXPECT_EQ(errorOf(badTiming),
            badTiming + ": /timings/config_wall_ms: error: got a string; expected a number (milliseconds)");
  std::string syntax = write("e.json", "{\"schema\": \"shadowlab.results/1\",\n \"rows\": [ 1 2 ]}");
  EXPECT_EQ(errorOf(syntax).rfind(syntax + ":2:14: error: syntax error while parsing array", 0), 0u) << errorOf(syntax);
  std::string missing = (dir_ / "absent.json").string();
  EXPECT_NE(errorOf(missing).find(missing), std::string::npos);
  EXPECT_NE(errorOf(missing), "(no InputError)");
}

// Every retired timing name is refused with its successor; `total_ms` gets the one its file meant.
TEST_F(Results, RenamedTimingNamesAreRefusedWithTheNewName) {
  auto metricsWith = [&](const std::string& name, const std::string& key, const char* schema) {
    return write(name, std::string(R"({"schema": ")") + schema +
                           R"(", "scene": "a", "config": "default", "light": "sun", "metrics": {}, "timings": {")" +
                           key + R"(": 1.0}})");
  };
  const std::pair<const char*, const char*> renames[] = {{"shadow_ms", "shadow_gpu_ms"},
                                                         {"camera_ms", "camera_gpu_ms"},
                                                         {"camera_visibility_ms", "visibility_gpu_ms"},
                                                         {"raster_ms", "render_wall_ms"},
                                                         {"total_ms", "config_wall_ms"}};
  for (const auto& [from, to] : renames) {
    std::string path = metricsWith(std::string(from) + ".json", from, "shadowlab.metrics/1");
    EXPECT_EQ(errorOf(path), path + ": /timings/" + from + ": error: \"" + from + "\" was renamed; use \"" + to +
                                 "\" (timing names: compare/TIMINGS.md)");
  }
  std::string stability = metricsWith("stability.json", "total_ms", "shadowlab.stability/1");
  EXPECT_EQ(errorOf(stability), stability +
                                    ": /timings/total_ms: error: \"total_ms\" was renamed; use "
                                    "\"command_wall_ms\" (timing names: compare/TIMINGS.md)");
  // A sweep journal line goes through ResultRow::fromJson: an old journal is refused the same way.
  nlohmann::json old = {{"scene", "a"},
                        {"config", "default"},
                        {"light", "sun"},
                        {"metrics", nlohmann::json::object()},
                        {"timings", {{"total_ms", 3.0}}}};
  try {
    ResultRow::fromJson(old, "rows.jsonl:4");
    ADD_FAILURE() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(),
                 "rows.jsonl:4: /timings/total_ms: error: \"total_ms\" was renamed; use \"config_wall_ms\" "
                 "(timing names: compare/TIMINGS.md)");
  }
  // The current names load.
  std::string fine = metricsWith("fine.json", "config_wall_ms", "shadowlab.metrics/1");
  EXPECT_EQ(errorOf(fine), "(no InputError)");
}

}  // namespace
}  // namespace shadowlab::gate_results_test
