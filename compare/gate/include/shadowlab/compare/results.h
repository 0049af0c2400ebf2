#pragma once
// Result rows: what `shadowlab run`/`compare` (metrics.json, one row) and `shadowlab sweep`
// (results.json, many rows; results.csv, the same flattened) write, and what `shadowlab gate` reads.
//
// metrics.json:  { "schema": "shadowlab.metrics/1", "scene": S, "config": C, "light": L,
//                  "method": {...}, "metrics": {...}, "timings": {...} }
// results.json:  { "schema": "shadowlab.results/1", "rows": [ {same keys as metrics.json minus schema} ],
//                  "command_wall_seconds": T, "configurations": N, ... }
// `config` names the configuration, the same way in every command (configName in
// compare/study/include/shadowlab/compare/config_name.h): its method keys off their defaults and its
// scene: values, sorted by key, "bias.slope=1,map.size=512" ("default" when there is none). Rows are
// matched by (scene, config, light).
// `metrics` holds Metrics::toJson(); `timings` holds the row timings of compare/TIMINGS.md
// (shadow_gpu_ms, camera_gpu_ms, readback_ms, render_wall_ms, compare_ms, config_wall_ms, ...; ms).
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace shadowlab {

struct ResultRow {
  std::string scene;
  std::string config;
  std::string light;
  nlohmann::json method = nlohmann::json::object();
  nlohmann::json metrics = nlohmann::json::object();
  nlohmann::json timings = nlohmann::json::object();

  std::string key() const { return scene + " | " + config + " | " + light; }
  nlohmann::json toJson() const;
  static ResultRow fromJson(const nlohmann::json& j, const std::string& origin);  // InputError on bad shape
};

// Reads a metrics.json (one row) or results.json (many rows). InputError naming the file and
// JSON pointer on anything malformed.
std::vector<ResultRow> loadResultRows(const std::string& path);
void writeMetricsJson(const std::string& path, const ResultRow& row);  // atomic

// A loaded metrics.json or results.json with what the gate needs to name places in it.
struct ResultFile {
  std::string path;
  std::string schema;  // "shadowlab.metrics/1" or "shadowlab.results/1"
  std::vector<ResultRow> rows;
  std::vector<std::string> pointers;  // JSON pointer of each row in the file ("" or "/rows/3")
  std::vector<std::string> rowPaths;  // the file of each row when merged from several; else empty
  std::vector<int> repeats;           // how many runs each row's timings are the median of; else empty
  nlohmann::json document;            // the whole file as read
  const std::string& pathOf(size_t row) const { return rowPaths.empty() ? path : rowPaths[row]; }
  int repeatsOf(size_t row) const { return repeats.empty() ? 1 : repeats[row]; }
};
ResultFile loadResultFile(const std::string& path);  // InputError naming file and pointer

}  // namespace shadowlab
