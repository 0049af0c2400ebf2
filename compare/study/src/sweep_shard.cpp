// Sharded sweeps (--shard I/N, `shadowlab merge`): the shard argument, the plan fingerprint that
// ties shards of one sweep together, and the spec recorded in each shard's shard.json so the merge
// plans the same sweep again without its arguments.
#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <filesystem>

#include "shadowlab/compare/sweep.h"
#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/io.h"

namespace shadowlab {
namespace {

namespace fs = std::filesystem;

// A non-negative decimal integer with nothing around it ("07" is fine, "+1", " 1", "1e3" are not).
bool parseCount(const std::string& text, size_t& out) {
  if (text.empty() || text.size() > 9) return false;
  for (char c : text)
    if (c < '0' || c > '9') return false;
  out = size_t(std::strtoul(text.c_str(), nullptr, 10));
  return true;
}

std::string absolutePath(const std::string& p) {
  if (p.empty()) return p;
  std::error_code ec;
  fs::path a = fs::absolute(fs::path(p), ec);
  return ec ? p : a.lexically_normal().string();
}

}  // namespace

SweepShard parseShardArgument(const std::string& text) {
  const std::string where = "--shard " + text;
  const size_t slash = text.find('/');
  SweepShard s;
  if (slash == std::string::npos || !parseCount(text.substr(0, slash), s.index) ||
      !parseCount(text.substr(slash + 1), s.count))
    throw InputError(formatError(where, "", "got \"" + text + "\"; expected I/N with integers 0 <= I < N (e.g. 0/4)"));
  if (s.count < 1) throw InputError(formatError(where, "", "N is 0; expected at least 1 shard"));
  if (s.index >= s.count)
    throw InputError(formatError(where, "",
                                 "I is " + std::to_string(s.index) + "; expected 0 <= I < N = " +
                                     std::to_string(s.count) + " (shards are numbered from 0)"));
  return s;
}

std::string shardDir(const std::string& outDir, const SweepShard& shard) {
  std::string base = outDir.empty() || outDir.back() == '/' ? outDir : outDir + "/";
  return base + "shards/" + std::to_string(shard.index) + "-of-" + std::to_string(shard.count);
}

std::string planFingerprint(const SweepPlan& plan) {
  nlohmann::json jobs = nlohmann::json::array();
  for (const auto& job : plan.jobs)
    jobs.push_back(
        {job.key(), plan.variants[job.variantIndex].hash, methodToJson(plan.configs[job.configIndex].method)});
  nlohmann::json fp = {{"jobs", jobs},
                       {"spp", plan.spec.spp},
                       {"light_samples", plan.spec.lightSamples},
                       {"light", plan.spec.light},
                       {"frontier", {plan.spec.frontierMetric, plan.spec.frontierThreshold}},
                       {"method_file_content", ""}};
  if (!plan.spec.methodFile.empty()) fp["method_file_content"] = readFile(plan.spec.methodFile);
  const std::string text = fp.dump();
  return hashHex(fnv1a64(text.data(), text.size()));
}

nlohmann::json sweepSpecToJson(const SweepPlan& plan) {
  const SweepSpec& spec = plan.spec;
  nlohmann::json j = nlohmann::json::object();
  nlohmann::json scenes = nlohmann::json::array();
  for (const auto& p : plan.scenePaths) scenes.push_back(absolutePath(p));
  j["scenes"] = scenes;
  nlohmann::json grid = nlohmann::json::array();
  for (const auto& a : spec.grid)
    grid.push_back({{"key", a.key},
                    {"values", a.values},
                    {"origin", a.origin},
                    {"value_origins", a.valueOrigins},
                    {"block", a.block}});
  j["grid"] = grid;
  nlohmann::json fixed = nlohmann::json::array();
  for (const auto& s : spec.fixed) fixed.push_back({{"key", s.key}, {"value", s.value}, {"origin", s.origin}});
  j["set"] = fixed;
  j["method_file"] = absolutePath(spec.methodFile);
  j["light"] = spec.light;
  j["spp"] = spec.spp;
  j["light_samples"] = spec.lightSamples;
  j["keep_images"] = spec.keepImages;
  j["frontier_metric"] = spec.frontierMetric;
  j["frontier_threshold"] = spec.frontierThreshold;
  return j;
}

SweepSpec sweepSpecFromJson(const nlohmann::json& j, const std::string& origin) {
  // shard.json is this program's own output: a shape error names the file, not each field.
  try {
    SweepSpec spec;
    spec.scenes = j.at("scenes").get<std::vector<std::string>>();
    for (const auto& a : j.at("grid")) {
      SweepAxis axis;
      axis.key = a.at("key").get<std::string>();
      axis.values = a.at("values").get<std::vector<nlohmann::json>>();
      axis.origin = a.at("origin").get<std::string>();
      axis.valueOrigins = a.at("value_origins").get<std::vector<std::string>>();
      axis.block = a.value("block", -1);
      spec.grid.push_back(std::move(axis));
    }
    for (const auto& s : j.at("set"))
      spec.fixed.push_back({s.at("key").get<std::string>(), s.at("value"), s.at("origin").get<std::string>()});
    spec.methodFile = j.at("method_file").get<std::string>();
    spec.light = j.at("light").get<std::string>();
    spec.spp = j.at("spp").get<int>();
    spec.lightSamples = j.value("light_samples", spec.lightSamples);
    spec.keepImages = j.at("keep_images").get<bool>();
    spec.frontierMetric = j.at("frontier_metric").get<std::string>();
    spec.frontierThreshold = j.at("frontier_threshold").get<double>();
    return spec;
  } catch (const nlohmann::json::exception&) {
    throw InputError(formatError(origin, "/spec",
                                 "damaged sweep description; expected the \"spec\" a sharded "
                                 "sweep writes (run the shard again)"));
  }
}

SweepSpec loadShardedSpec(const std::string& outDir) {
  const fs::path shards = fs::path(outDir) / "shards";
  std::vector<std::string> found;
  std::error_code ec;
  if (fs::is_directory(shards, ec))
    for (const auto& e : fs::directory_iterator(shards, ec))
      if (fs::is_regular_file(e.path() / "shard.json", ec)) found.push_back((e.path() / "shard.json").string());
  if (found.empty())
    throw InputError(formatError(shards.string(), "",
                                 "no shard folder with a shard.json; expected the output of "
                                 "`shadowlab sweep ... --shard I/N -o " +
                                     outDir + "`"));
  std::sort(found.begin(), found.end());
  const nlohmann::json j = nlohmann::json::parse(readFile(found.front()), nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded() || !j.is_object() || !j.contains("spec"))
    throw InputError(formatError(found.front(), "", "not a shard description; expected JSON with \"spec\""));
  return sweepSpecFromJson(j.at("spec"), found.front());
}

}  // namespace shadowlab
