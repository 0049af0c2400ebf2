// Result rows: metrics.json (one row) and results.json (rows) in and out. The gate reads these
// files from CI artifacts and user checkouts, so every shape error names the file and the JSON
// pointer of the offending value.
#include "shadowlab/compare/results.h"

#include <set>

#include "shadowlab/compare/timings.h"
#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/io.h"
#include "shadowlab/scenes/json_reader.h"

namespace shadowlab {
namespace {

constexpr const char* kMetricsSchema = "shadowlab.metrics/1";
constexpr const char* kResultsSchema = "shadowlab.results/1";
// stability.json (`shadowlab stability`): one result row at the top level, like metrics.json, beside
// its per-frame numbers (compare/METRICS.md, "Temporal stability").
constexpr const char* kStabilitySchema = "shadowlab.stability/1";

ResultRow rowFromJson(const nlohmann::json& j, const std::string& file, const std::string& pointer,
                      timing::TimingSource source) {
  auto fail = [&](const std::string& place, const std::string& what) {
    throw InputError(formatError(file, place, what));  // "" = the whole document
  };
  if (!j.is_object()) fail(pointer, "got " + jsonTypeName(j) + "; expected a result row (an object)");
  ResultRow row;
  auto text = [&](const char* key, std::string& out) {
    auto it = j.find(key);
    if (it == j.end()) fail(pointer, std::string("missing \"") + key + "\"; expected a string");
    if (!it->is_string()) fail(pointer + "/" + key, "got " + jsonTypeName(*it) + "; expected a string");
    out = it->get<std::string>();
  };
  text("scene", row.scene);
  text("config", row.config);
  text("light", row.light);
  if (row.scene.empty()) fail(pointer + "/scene", "got an empty string; expected the scene name");
  if (row.config.empty())
    fail(pointer + "/config", "got an empty string; expected a config (\"default\" when nothing was swept)");
  auto object = [&](const char* key, nlohmann::json& out, bool required) {
    auto it = j.find(key);
    if (it == j.end()) {
      if (required) fail(pointer, std::string("missing \"") + key + "\"; expected an object");
      return;
    }
    if (!it->is_object()) fail(pointer + "/" + key, "got " + jsonTypeName(*it) + "; expected an object");
    out = *it;
  };
  object("method", row.method, false);
  object("metrics", row.metrics, true);
  object("timings", row.timings, false);
  // Timings are milliseconds; anything else there would make the ratio rule meaningless. A name
  // older builds wrote is refused: `total_ms` meant another quantity in each file, so gating it
  // against a current run would compare two different things under one name.
  for (auto it = row.timings.begin(); it != row.timings.end(); ++it) {
    if (const char* renamed = timing::renamedTiming(it.key(), source))
      fail(pointer + "/timings/" + jsonPointerToken(it.key()), timing::renamedTimingMessage(it.key(), renamed));
    if (!it.value().is_number() && !it.value().is_null())
      fail(pointer + "/timings/" + jsonPointerToken(it.key()),
           "got " + jsonTypeName(it.value()) + "; expected a number (milliseconds)");
  }
  return row;
}

}  // namespace

nlohmann::json ResultRow::toJson() const {
  nlohmann::json j = nlohmann::json::object();
  j["scene"] = scene;
  j["config"] = config;
  j["light"] = light;
  j["method"] = method;
  j["metrics"] = metrics;
  j["timings"] = timings;
  return j;
}

ResultRow ResultRow::fromJson(const nlohmann::json& j, const std::string& origin) {
  return rowFromJson(j, origin, "", timing::TimingSource::ResultRow);
}

ResultFile loadResultFile(const std::string& path) {
  ResultFile file;
  file.path = path;
  file.document = readJsonFile(path);
  const nlohmann::json& doc = file.document;
  if (!doc.is_object())
    throw InputError(formatError(path, "", "got " + jsonTypeName(doc) + "; expected an object with \"schema\""));
  auto schema = doc.find("schema");
  if (schema == doc.end())
    throw InputError(formatError(path, "",
                                 std::string("missing \"schema\"; expected \"") + kMetricsSchema +
                                     "\" (metrics.json), \"" + kResultsSchema + "\" (results.json) or \"" +
                                     kStabilitySchema + "\" (stability.json)"));
  if (!schema->is_string() || (*schema != kMetricsSchema && *schema != kResultsSchema && *schema != kStabilitySchema))
    throw InputError(formatError(path, "/schema",
                                 "got " + schema->dump() + "; expected \"" + kMetricsSchema + "\", \"" +
                                     kResultsSchema + "\" or \"" + kStabilitySchema + "\""));
  file.schema = schema->get<std::string>();
  if (file.schema == kMetricsSchema || file.schema == kStabilitySchema) {
    file.rows.push_back(rowFromJson(
        doc, path, "",
        file.schema == kStabilitySchema ? timing::TimingSource::StabilityRow : timing::TimingSource::ResultRow));
    file.pointers.push_back("");
    return file;
  }
  auto rows = doc.find("rows");
  if (rows == doc.end()) throw InputError(formatError(path, "", "missing \"rows\"; expected an array of result rows"));
  if (!rows->is_array())
    throw InputError(formatError(path, "/rows", "got " + jsonTypeName(*rows) + "; expected an array of result rows"));
  for (size_t i = 0; i < rows->size(); ++i) {
    std::string pointer = "/rows/" + std::to_string(i);
    file.rows.push_back(rowFromJson((*rows)[i], path, pointer, timing::TimingSource::ResultRow));
    file.pointers.push_back(pointer);
  }
  return file;
}

std::vector<ResultRow> loadResultRows(const std::string& path) { return loadResultFile(path).rows; }

void writeMetricsJson(const std::string& path, const ResultRow& row) {
  nlohmann::json j = row.toJson();
  j["schema"] = kMetricsSchema;
  writeJsonAtomic(path, j);
}

}  // namespace shadowlab
