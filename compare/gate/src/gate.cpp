// The regression gate: tolerances as data, row matching, verdicts, and the three outputs (table,
// JSON, JUnit XML). compare/GATE.md is the user-facing description; keep the two in step.
#include "shadowlab/compare/gate.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <set>
#include <sstream>

#include "shadowlab/compare/classes.h"
#include "shadowlab/compare/timings.h"
#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/io.h"
#include "shadowlab/scenes/json_reader.h"

namespace shadowlab {
namespace {

constexpr const char* kTolerancesSchema = "shadowlab.tolerances/1";
constexpr const char* kGateSchema = "shadowlab.gate/1";

// %.6g reads well; when two different values would print the same (an exact-equality tolerance
// failing on the 9th digit), more digits until they differ, so a message never says "0.1 > 0.1".
std::string formatNumber(double v, int digits = 6) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*g", digits, v);
  return buf;
}
std::pair<std::string, std::string> formatPair(double a, double b) {
  for (int digits = 6; digits <= 17; ++digits) {
    std::string sa = formatNumber(a, digits), sb = formatNumber(b, digits);
    if (sa != sb || a == b) return {sa, sb};
  }
  return {formatNumber(a, 17), formatNumber(b, 17)};
}
std::string formatValue(const nlohmann::json& v) {
  if (v.is_number()) return formatNumber(v.get<double>());
  if (v.is_string()) return "\"" + v.get<std::string>() + "\"";
  return v.dump();
}

// Nested metric objects become dotted names ("per_object.3.acne"), so each leaf is one check.
void flatten(const nlohmann::json& j, const std::string& prefix, std::map<std::string, nlohmann::json>& out) {
  for (auto it = j.begin(); it != j.end(); ++it) {
    std::string name = prefix.empty() ? it.key() : prefix + "." + it.key();
    if (it.value().is_object()) flatten(it.value(), name, out);
    else out[name] = it.value();
  }
}
std::string metricPointer(const std::string& rowPointer, const std::string& group, const std::string& name) {
  // Dotted names came from nesting or contain a dot themselves; for the pointer use the top key
  // only when the name is nested, which is enough to find it in the file.
  return rowPointer + "/" + group + "/" + jsonPointerToken(name);
}

std::optional<Direction> parseDirection(const std::string& s) {
  if (s == "lower_is_better") return Direction::LowerIsBetter;
  if (s == "higher_is_better") return Direction::HigherIsBetter;
  if (s == "equal") return Direction::Equal;
  if (s == "ignore") return Direction::Ignore;
  return std::nullopt;
}

ToleranceSpec parseSpec(const nlohmann::json& j, const std::string& file, const std::string& pointer) {
  if (!j.is_object())
    throw InputError(formatError(
        file, pointer, "got " + jsonTypeName(j) + "; expected an object with \"direction\", \"abs\", \"rel\""));
  ToleranceSpec spec;
  for (auto it = j.begin(); it != j.end(); ++it) {
    std::string place = pointer + "/" + jsonPointerToken(it.key());
    const nlohmann::json& v = it.value();
    if (it.key() == "direction") {
      auto d = v.is_string() ? parseDirection(v.get<std::string>()) : std::nullopt;
      if (!d)
        throw InputError(formatError(file, place,
                                     "got " + describeJson(v) +
                                         "; expected \"lower_is_better\", \"higher_is_better\", "
                                         "\"equal\" or \"ignore\""));
      spec.direction = d;
    } else if (it.key() == "abs" || it.key() == "rel") {
      if (!v.is_number())
        throw InputError(formatError(file, place, "got " + jsonTypeName(v) + "; expected a number >= 0"));
      double x = v.get<double>();
      if (!(x >= 0) || !std::isfinite(x))
        throw InputError(formatError(file, place, "got " + describeJson(v) + "; expected a number >= 0 (a tolerance)"));
      (it.key() == "abs" ? spec.absTolerance : spec.relTolerance) = x;
    } else {
      throw InputError(
          formatError(file, place, "unknown key \"" + it.key() + "\"; expected \"direction\", \"abs\" or \"rel\""));
    }
  }
  return spec;
}

TimingTolerance parseTiming(const nlohmann::json& j, const std::string& file) {
  TimingTolerance t;
  auto mode = [&](const nlohmann::json& v, const std::string& place) {
    if (v == "report") return TimingMode::Report;
    if (v == "fail") return TimingMode::Fail;
    throw InputError(formatError(file, place, "got " + describeJson(v) + "; expected \"report\" or \"fail\""));
  };
  if (j.is_string()) {
    t.mode = mode(j, "/timing");
    return t;
  }
  if (!j.is_object())
    throw InputError(formatError(file, "/timing",
                                 "got " + jsonTypeName(j) +
                                     "; expected \"report\", \"fail\" or an object "
                                     "{\"mode\", \"max_ratio\", \"min_ms\"}"));
  for (auto it = j.begin(); it != j.end(); ++it) {
    std::string place = "/timing/" + jsonPointerToken(it.key());
    const nlohmann::json& v = it.value();
    if (it.key() == "mode") {
      t.mode = mode(v, place);
    } else if (it.key() == "max_ratio") {
      if (!v.is_number() || !(v.get<double>() >= 1.0))
        throw InputError(
            formatError(file, place, "got " + describeJson(v) + "; expected a number >= 1 (current/baseline time)"));
      t.maxRatio = v.get<double>();
    } else if (it.key() == "min_ms") {
      if (!v.is_number() || !(v.get<double>() >= 0.0))
        throw InputError(
            formatError(file, place, "got " + describeJson(v) + "; expected a number >= 0 (milliseconds)"));
      t.minMs = v.get<double>();
    } else {
      throw InputError(
          formatError(file, place, "unknown key \"" + it.key() + "\"; expected \"mode\", \"max_ratio\" or \"min_ms\""));
    }
  }
  return t;
}

int verdictRank(Verdict v) {
  switch (v) {
    case Verdict::Regressed: return 0;
    case Verdict::Improved: return 2;
    case Verdict::New: return 3;
    case Verdict::Pass: return 4;
    case Verdict::Reported: return 5;
  }
  return 6;
}

// Throws one InputError listing every problem (at most 20 lines): a CI log should show them all
// at once rather than one per run.
void throwProblems(const std::vector<std::string>& problems) {
  if (problems.empty()) return;
  std::string message;
  size_t shown = std::min<size_t>(problems.size(), 20);
  for (size_t i = 0; i < shown; ++i) message += (i ? "\n" : "") + problems[i];
  if (problems.size() > shown) message += "\n(" + std::to_string(problems.size() - shown) + " more problems not shown)";
  throw InputError(message);
}

void checkDuplicates(const ResultFile& f) {
  std::map<std::string, size_t> seen;
  for (size_t i = 0; i < f.rows.size(); ++i) {
    auto [it, fresh] = seen.emplace(f.rows[i].key(), i);
    if (!fresh) {
      // Name the first occurrence by pointer within the same file, by file (and pointer) across
      // merged files: the same metrics.json given twice has no pointer to tell them apart.
      size_t j = it->second;
      std::string first = f.pathOf(j) == f.pathOf(i) && !f.pointers[j].empty() ? f.pointers[j]
                          : f.pointers[j].empty()                              ? f.pathOf(j)
                                                                               : f.pathOf(j) + ": " + f.pointers[j];
      throw InputError(formatError(f.pathOf(i), f.pointers[i],
                                   "row \"" + f.rows[i].key() + "\" appears again (first at " + first +
                                       "); expected each (scene, config, light) once"));
    }
  }
}

GateCheck baseCheck(const ResultRow& row, const std::string& kind, const std::string& metric) {
  GateCheck c;
  c.rowKey = row.key();
  c.scene = row.scene;
  c.config = row.config;
  c.light = row.light;
  c.kind = kind;
  c.metric = metric;
  return c;
}

// A row whose comparison scored no pixel (compare/METRICS.md "Nothing compared"): its metrics
// say "nothing_compared": true, or (files written before that key) pixels_compared is 0.
bool comparesNothing(const ResultRow& row) {
  auto flag = row.metrics.find("nothing_compared");
  if (flag != row.metrics.end() && flag->is_boolean() && flag->get<bool>()) return true;
  auto count = row.metrics.find("pixels_compared");
  return count != row.metrics.end() && count->is_number() && count->get<double>() == 0.0;
}

// A null the row itself explains: the m statistics when every compared pixel's footprint hit the
// cap (m_capped == pixels_compared > 0); a region's mae and rmse when the region has no pixel
// (`<region>_pixels` == 0, e.g. the penumbra of a hard light). Any other null is a NaN, bad input.
bool undefinedByRow(const nlohmann::json& metrics, const std::string& name) {
  for (const VisRegionInfo& r : kVisRegions) {
    if (name != r.maeMetric && name != r.rmseMetric) continue;
    auto pixels = metrics.find(r.pixelsMetric);
    return pixels != metrics.end() && pixels->is_number() && pixels->get<double>() == 0.0;
  }
  if (name != "m_median" && name != "m_p95" && name != "m_max") return false;
  auto capped = metrics.find("m_capped"), compared = metrics.find("pixels_compared");
  return capped != metrics.end() && compared != metrics.end() && capped->is_number() && compared->is_number() &&
         compared->get<double>() > 0 && capped->get<double>() == compared->get<double>();
}

// Metric values the gate refuses as bad input: a built-in metric (one Metrics::toJson or
// stability.json writes) that is not a number, or a negative one, or a rate / IoU above 1. Each
// problem names the file and the JSON pointer; a corrupt baseline is not a regression.
void checkMetricValues(const ResultFile& f, std::vector<std::string>& problems) {
  static const std::set<std::string> kFlags = {"has_projector", "light_compared", "nothing_compared"};
  for (size_t r = 0; r < f.rows.size(); ++r) {
    std::map<std::string, nlohmann::json> flat;
    flatten(f.rows[r].metrics, "", flat);
    for (const auto& [name, v] : flat) {
      bool known = false;
      builtinDirection(name, &known);
      if (!known || v.is_null()) continue;  // null: NaN or undefined, judged with the row
      const std::string where = metricPointer(f.pointers[r], "metrics", name);
      const std::string shown = v.is_string() ? "the string " + describeJson(v) : describeJson(v);
      if (kFlags.count(name)) {
        if (!v.is_boolean())
          problems.push_back(
              formatError(f.pathOf(r), where, "metric \"" + name + "\" is " + shown + "; expected true or false"));
        continue;
      }
      const bool ratio = name.size() > 4 && (name.compare(name.size() - 4, 4, "_iou") == 0 ||
                                             (name.size() > 5 && name.compare(name.size() - 5, 5, "_rate") == 0));
      const char* expected = ratio ? "a number in [0, 1] (a fraction of compared pixels)" : "a number >= 0";
      if (!v.is_number() || !(v.get<double>() >= 0.0) || (ratio && v.get<double>() > 1.0))
        problems.push_back(
            formatError(f.pathOf(r), where, "metric \"" + name + "\" is " + shown + "; expected " + expected));
    }
  }
}

}  // namespace

std::string toString(Direction d) {
  switch (d) {
    case Direction::LowerIsBetter: return "lower_is_better";
    case Direction::HigherIsBetter: return "higher_is_better";
    case Direction::Equal: return "equal";
    case Direction::Ignore: return "ignore";
  }
  return "?";
}

std::string toString(Verdict v) {
  switch (v) {
    case Verdict::Regressed: return "REGRESSED";
    case Verdict::New: return "new";
    case Verdict::Improved: return "improved";
    case Verdict::Pass: return "pass";
    case Verdict::Reported: return "report";
  }
  return "?";
}

double MetricTolerance::allowed(double baseline) const {
  return std::max(absTolerance, relTolerance * std::fabs(baseline));
}

Direction builtinDirection(const std::string& metric, bool* known) {
  // The names Metrics::toJson writes (compare/METRICS.md). Counts and rates of wrong pixels, the
  // mean errors and Lloyd's texel footprint m only get better by going down. The per-class counts
  // and rates, and their directions, come from the class table (classes.h).
  static const std::map<std::string, Direction> kBuiltin = [] {
    std::map<std::string, Direction> m = {
        {"pixels_compared", Direction::Equal},
        {"errors", Direction::LowerIsBetter},
        {"error_rate", Direction::LowerIsBetter},
        {"shadow_iou", Direction::HigherIsBetter},
        {"mae", Direction::LowerIsBetter},
        {"rmse", Direction::LowerIsBetter},
        {"m_median", Direction::LowerIsBetter},
        {"m_p95", Direction::LowerIsBetter},
        {"m_max", Direction::LowerIsBetter},
        {"m_capped", Direction::LowerIsBetter},
        {"nothing_compared", Direction::Equal},
        {"light_compared", Direction::Equal},
        {"has_projector", Direction::Equal},
        {"projector_coverage_iou", Direction::HigherIsBetter},
        {"reverse_projection_pixels", Direction::LowerIsBetter},
        {"projector_color_mae", Direction::LowerIsBetter},
        // stability.json (compare/METRICS.md, "Temporal stability"): shimmer and the per-frame error
        // rate's statistics only get better by going down; the path's frame count must not move.
        {"frames", Direction::Equal},
        {"shimmer_rate", Direction::LowerIsBetter},
        {"error_rate_mean", Direction::LowerIsBetter},
        {"error_rate_max", Direction::LowerIsBetter},
        {"error_rate_std", Direction::LowerIsBetter},
        {"error_jump_max", Direction::LowerIsBetter},
        // Soft shadows (compare/METRICS.md): the signed visibility errors only get better by going
        // down; within_uncertainty says how much the truth's noise decided, neither better nor worse.
        {"over_shadowing", Direction::LowerIsBetter},
        {"under_shadowing", Direction::LowerIsBetter},
        {"within_uncertainty", Direction::Ignore},
    };
    // The regions of the truth (classes.h): their pixel counts depend on the reference alone.
    for (const VisRegionInfo& r : kVisRegions) {
      m[r.pixelsMetric] = Direction::Equal;
      m[r.maeMetric] = Direction::LowerIsBetter;
      m[r.rmseMetric] = Direction::LowerIsBetter;
    }
    for (const PixelClassInfo& c : kPixelClasses) {
      const Direction d = c.better == MetricBetter::Lower ? Direction::LowerIsBetter : Direction::HigherIsBetter;
      if (c.countMetric) m[c.countMetric] = d;
      if (c.rateMetric) m[c.rateMetric] = d;
    }
    return m;
  }();
  auto it = kBuiltin.find(metric);
  if (known) *known = it != kBuiltin.end();
  if (it != kBuiltin.end()) return it->second;
  // Unknown metrics follow the naming convention when they can; otherwise any move is a change.
  auto endsWith = [&](const char* suffix) {
    std::string s = suffix;
    return metric.size() >= s.size() && metric.compare(metric.size() - s.size(), s.size(), s) == 0;
  };
  if (endsWith("_iou")) return Direction::HigherIsBetter;
  if (endsWith("_rate") || endsWith("_mae") || endsWith("_rmse")) return Direction::LowerIsBetter;
  return Direction::Equal;
}

MetricTolerance Tolerances::forMetric(const std::string& metric) const {
  MetricTolerance t;
  auto it = metrics.find(metric);
  if (it != metrics.end()) {
    // A listed metric's entry is complete by itself: {"abs": 50} means 50 and no relative part,
    // whatever "default" says (a default leaking into an entry surprises whoever reads the file).
    const ToleranceSpec& entry = it->second;
    t.direction = entry.direction.value_or(builtinDirection(metric));
    t.absTolerance = entry.absTolerance.value_or(0.0);
    t.relTolerance = entry.relTolerance.value_or(0.0);
    return t;
  }
  t.direction = fallback.direction ? *fallback.direction : builtinDirection(metric);
  t.absTolerance = fallback.absTolerance.value_or(0.0);
  t.relTolerance = fallback.relTolerance.value_or(0.0);
  return t;
}

Tolerances defaultTolerances() {
  Tolerances t;
  // The pipeline is deterministic for any thread count: metrics must match. 1e-9 relative only
  // absorbs a decimal round trip through another tool.
  t.fallback.absTolerance = 0.0;
  t.fallback.relTolerance = 1e-9;
  return t;
}

Tolerances parseTolerances(const nlohmann::json& j, const std::string& file) {
  Tolerances t = defaultTolerances();
  t.origin = file;
  if (!j.is_object())
    throw InputError(formatError(file, "", "got " + jsonTypeName(j) + "; expected an object (a tolerance file)"));
  for (auto it = j.begin(); it != j.end(); ++it) {
    const std::string& key = it.key();
    std::string place = "/" + jsonPointerToken(key);
    if (key == "schema") {
      if (it.value() != kTolerancesSchema)
        throw InputError(
            formatError(file, place, "got " + describeJson(it.value()) + "; expected \"" + kTolerancesSchema + "\""));
    } else if (key == "default") {
      ToleranceSpec spec = parseSpec(it.value(), file, place);
      if (spec.direction) t.fallback.direction = spec.direction;
      if (spec.absTolerance) t.fallback.absTolerance = spec.absTolerance;
      if (spec.relTolerance) t.fallback.relTolerance = spec.relTolerance;
    } else if (key == "metrics") {
      if (!it.value().is_object())
        throw InputError(formatError(
            file, place, "got " + jsonTypeName(it.value()) + "; expected an object of metric name -> tolerance"));
      for (auto m = it.value().begin(); m != it.value().end(); ++m) {
        const std::string mplace = place + "/" + jsonPointerToken(m.key());
        // A timing listed as a metric would never be checked (timings follow "timing"): say so
        // rather than let the file look as if it gated it; a retired timing name gets its new one.
        if (const char* renamed = timing::renamedTiming(m.key(), timing::TimingSource::ResultRow))
          throw InputError(formatError(file, mplace, timing::renamedTimingMessage(m.key(), renamed)));
        if (timing::isTimingName(m.key()))
          throw InputError(formatError(file, mplace,
                                       "\"" + m.key() +
                                           "\" is a timing, not a metric; expected "
                                           "timings under \"timing\" (compare/GATE.md)"));
        t.metrics[m.key()] = parseSpec(m.value(), file, mplace);
      }
    } else if (key == "timing") {
      t.timing = parseTiming(it.value(), file);
    } else {
      throw InputError(formatError(
          file, place, "unknown key \"" + key + "\"; expected \"schema\", \"default\", \"metrics\" or \"timing\""));
    }
  }
  return t;
}

Tolerances loadTolerances(const std::string& path) { return parseTolerances(readJsonFile(path), path); }

std::string GateResult::summary() const {
  std::ostringstream s;
  s << (passed() ? "PASS" : "FAIL") << ": " << regressions << (regressions == 1 ? " regression" : " regressions")
    << ", " << improvements << " improved, " << passes << " within tolerance, " << reported << " reported only, "
    << newMetrics << (newMetrics == 1 ? " new metric; " : " new metrics; ") << rowsCompared
    << (rowsCompared == 1 ? " row" : " rows") << " compared, " << rowsNew << " new";
  if (rowsNotRun > 0) s << ", " << rowsNotRun << " baseline " << (rowsNotRun == 1 ? "row" : "rows") << " not run";
  return s.str();
}

GateResult runGate(const ResultFile& current, const ResultFile& baseline, const Tolerances& tolerances) {
  checkDuplicates(current);
  checkDuplicates(baseline);
  // An empty baseline would pass anything: every current row would merely be "new".
  if (baseline.rows.empty())
    throw InputError(formatError(baseline.path, "/rows",
                                 "the baseline has no rows; expected at least one (create it with --update-baseline)"));

  // A tolerance for a metric no row has is a typo that would otherwise never apply.
  {
    std::set<std::string> present;
    for (const ResultFile* f : {&current, &baseline})
      for (const ResultRow& row : f->rows) {
        std::map<std::string, nlohmann::json> flat;
        flatten(row.metrics, "", flat);
        for (auto& [name, value] : flat) present.insert(name);
      }
    for (auto& [name, spec] : tolerances.metrics) {
      bool known = false;
      builtinDirection(name, &known);
      if (!known && !present.count(name)) {
        std::string names;
        for (auto& p : present) names += (names.empty() ? "" : ", ") + p;
        throw InputError(formatError(tolerances.origin, "/metrics/" + jsonPointerToken(name),
                                     "no row has a metric \"" + name + "\"; expected one of: " + names));
      }
    }
  }

  std::map<std::string, size_t> currentIndex;
  for (size_t i = 0; i < current.rows.size(); ++i) currentIndex[current.rows[i].key()] = i;

  GateResult result;
  std::vector<std::string> problems;
  checkMetricValues(baseline, problems);
  if (&baseline != &current) checkMetricValues(current, problems);
  throwProblems(problems);
  // A baseline that compared nothing accepts anything (every rate null): bad input, never a pass.
  for (size_t b = 0; b < baseline.rows.size(); ++b)
    if (comparesNothing(baseline.rows[b]))
      problems.push_back(formatError(baseline.path, metricPointer(baseline.pointers[b], "metrics", "pixels_compared"),
                                     "row \"" + baseline.rows[b].key() +
                                         "\" compares nothing (pixels_compared 0); expected a baseline whose camera "
                                         "sees a surface both renderers agree on"));
  // A baseline row with no metric gates nothing: every current metric would merely be "new".
  for (size_t b = 0; b < baseline.rows.size(); ++b) {
    std::map<std::string, nlohmann::json> flat;
    flatten(baseline.rows[b].metrics, "", flat);
    if (flat.empty())
      problems.push_back(formatError(baseline.pathOf(b), baseline.pointers[b] + "/metrics",
                                     "row \"" + baseline.rows[b].key() +
                                         "\" has no metrics (got {}); expected the metrics of a run to gate against"));
  }
  throwProblems(problems);
  // A current row that compared nothing fails, whatever the baseline says: no pixel is no pass.
  auto nothingCompared = [&](size_t i, const nlohmann::json& baselineCount) {
    const ResultRow& row = current.rows[i];
    GateCheck c = baseCheck(row, "row", "pixels_compared");
    c.baseline = baselineCount;
    c.current = 0;
    c.tolerance = "> 0";
    c.verdict = Verdict::Regressed;
    const std::string& pointer = current.pointers[i];
    c.message = row.key() + ": nothing was compared in " + current.pathOf(i) + (pointer.empty() ? "" : " " + pointer) +
                " (pixels_compared 0: the camera sees no surface both renderers agree on); expected compared pixels" +
                (baselineCount.is_number() ? ", " + formatValue(baselineCount) + " in the baseline" : "");
    result.checks.push_back(std::move(c));
  };
  // One run gated against a sweep: its row is one of the sweep's configurations (configuration
  // names are the same in every command), the sweep's other rows were not run here.
  const bool oneRun = current.schema == "shadowlab.metrics/1" && baseline.schema == "shadowlab.results/1";
  std::set<std::string> matched;
  for (size_t b = 0; b < baseline.rows.size(); ++b) {
    const ResultRow& base = baseline.rows[b];
    auto found = currentIndex.find(base.key());
    if (found == currentIndex.end() && oneRun) {
      ++result.rowsNotRun;
      continue;
    }
    if (found == currentIndex.end()) {
      problems.push_back(formatError(baseline.path, baseline.pointers[b],
                                     "row \"" + base.key() + "\" is in the baseline but missing from " + current.path +
                                         "; expected every baseline row in the current results"));
      continue;
    }
    matched.insert(base.key());
    const ResultRow& cur = current.rows[found->second];
    const std::string& curPointer = current.pointers[found->second];
    const std::string& curPath = current.pathOf(found->second);
    ++result.rowsCompared;
    // A technique file (method key technique) edited since the baseline: the same row key, other
    // code. Refused, naming both (stem@hash), rather than gated as if it were the same technique.
    const auto baseTechnique = base.method.find("technique.hash"), curTechnique = cur.method.find("technique.hash");
    if (!tolerances.techniqueChanged && baseTechnique != base.method.end() && curTechnique != cur.method.end() &&
        *baseTechnique != *curTechnique)
      problems.push_back(
          formatError(curPath, curPointer + "/method/technique.hash",
                      "row \"" + base.key() + "\" was measured with technique " + curTechnique->dump() +
                          " but the baseline " + baseline.path + " with " + baseTechnique->dump() +
                          "; expected the same technique file (--technique-changed gates the edited one against it)"));
    if (comparesNothing(cur)) {  // its rates are null: one failing check instead of one per metric
      nothingCompared(found->second, base.metrics.value("pixels_compared", nlohmann::json()));
      continue;
    }

    std::map<std::string, nlohmann::json> baseMetrics, curMetrics;
    flatten(base.metrics, "", baseMetrics);
    flatten(cur.metrics, "", curMetrics);
    for (auto& [name, bv] : baseMetrics) {
      auto ci = curMetrics.find(name);
      if (ci == curMetrics.end()) {
        problems.push_back(formatError(curPath, curPointer + "/metrics",
                                       "row \"" + base.key() + "\" has no metric \"" + name +
                                           "\"; expected it, as in the baseline " + baseline.path));
        continue;
      }
      const nlohmann::json& cv = ci->second;
      const bool baseUndefined = bv.is_null() && undefinedByRow(base.metrics, name);
      const bool curUndefined = cv.is_null() && undefinedByRow(cur.metrics, name);
      const bool nan = (bv.is_null() && !baseUndefined) || (cv.is_null() && !curUndefined);
      if (!nan && (baseUndefined || curUndefined)) {
        // m statistics of a row whose every pixel hit the footprint cap: m_capped carries the
        // change; both undefined is the same result.
        GateCheck c = baseCheck(base, "metric", name);
        c.baseline = bv;
        c.current = cv;
        c.tolerance = "undefined";
        c.verdict = baseUndefined && curUndefined ? Verdict::Pass : Verdict::Reported;
        result.checks.push_back(std::move(c));
        continue;
      }
      // JSON has no NaN: nlohmann writes a NaN as null. A NaN can never pass a gate silently.
      if (bv.is_null())
        problems.push_back(formatError(baseline.path, metricPointer(baseline.pointers[b], "metrics", name),
                                       "metric \"" + name + "\" is null (NaN); expected a number"));
      if (cv.is_null())
        problems.push_back(formatError(curPath, metricPointer(curPointer, "metrics", name),
                                       "metric \"" + name + "\" is null (NaN); expected a number"));
      if (bv.is_null() || cv.is_null()) continue;

      GateCheck c = baseCheck(base, "metric", name);
      c.baseline = bv;
      c.current = cv;
      MetricTolerance tol = tolerances.forMetric(name);
      const std::string prefix = base.key() + ": metric \"" + name + "\" is ";
      if (tol.direction == Direction::Ignore) {
        c.tolerance = "ignore";
        c.verdict = Verdict::Reported;
      } else if (bv.is_number() && cv.is_number()) {
        double bd = bv.get<double>(), cd = cv.get<double>();
        double allowed = tol.allowed(bd);
        std::string allowedText = formatNumber(allowed);
        // The table shows a rounding-only tolerance (the built-in 1e-9 relative) as 0, not as
        // "+4.76802e-14"; messages keep the exact number.
        const std::string shown = tol.absTolerance == 0 && tol.relTolerance <= 1e-6 ? std::string("0") : allowedText;
        auto [cs, bs] = formatPair(cd, bd);
        switch (tol.direction) {
          case Direction::LowerIsBetter:
            c.tolerance = "+" + shown;
            if (cd > bd + allowed) {
              c.verdict = Verdict::Regressed;
              c.message = prefix + cs + ", above the baseline " + bs + " + tolerance " + allowedText;
            } else if (cd < bd - allowed) {
              c.verdict = Verdict::Improved;
            }
            break;
          case Direction::HigherIsBetter:
            c.tolerance = "-" + shown;
            if (cd < bd - allowed) {
              c.verdict = Verdict::Regressed;
              c.message = prefix + cs + ", below the baseline " + bs + " - tolerance " + allowedText;
            } else if (cd > bd + allowed) {
              c.verdict = Verdict::Improved;
            }
            break;
          default:
            c.tolerance = "+/-" + shown;
            if (std::fabs(cd - bd) > allowed) {
              c.verdict = Verdict::Regressed;
              c.message = prefix + cs + ", not the baseline " + bs + " +/- tolerance " + allowedText;
            }
        }
      } else {
        c.tolerance = "equal";
        if (bv != cv) {
          c.verdict = Verdict::Regressed;
          c.message = prefix + formatValue(cv) + ", not the baseline " + formatValue(bv);
        }
      }
      result.checks.push_back(std::move(c));
    }
    for (auto& [name, cv] : curMetrics) {
      if (baseMetrics.count(name)) continue;
      GateCheck c = baseCheck(cur, "metric", name);
      c.current = cv;
      c.verdict = Verdict::New;
      c.tolerance = "-";
      result.checks.push_back(std::move(c));
    }

    for (auto it = base.timings.begin(); it != base.timings.end(); ++it) {
      const std::string& name = it.key();
      GateCheck c = baseCheck(base, "timing", name);
      c.baseline = it.value();
      auto ct = cur.timings.find(name);
      if (ct == cur.timings.end() || ct->is_null() || it.value().is_null()) {
        // Timings are not part of the metric contract: a missing one is reported, not failed,
        // unless the tolerance file asks for timings to gate.
        if (ct != cur.timings.end()) c.current = *ct;
        c.tolerance = "report";
        c.verdict = tolerances.timing.mode == TimingMode::Fail ? Verdict::Regressed : Verdict::Reported;
        if (c.verdict == Verdict::Regressed)
          c.message = base.key() + ": timing \"" + name + "\" has no value in the current results; expected one";
        result.checks.push_back(std::move(c));
        continue;
      }
      c.current = *ct;
      c.samples = current.repeatsOf(found->second);
      double bms = it.value().get<double>(), cms = ct->get<double>();
      double ratio = bms > 0 ? cms / bms : (cms > 0 ? INFINITY : 1.0);
      char ratioText[32];
      std::snprintf(ratioText, sizeof ratioText, "%.2fx", ratio);
      if (tolerances.timing.mode == TimingMode::Report) {
        c.tolerance = "report";
        c.verdict = Verdict::Reported;
      } else if (bms < tolerances.timing.minMs) {
        c.tolerance = "report (< " + formatNumber(tolerances.timing.minMs) + " ms)";
        c.verdict = Verdict::Reported;
      } else {
        char limit[32];
        std::snprintf(limit, sizeof limit, "<= %.2fx", tolerances.timing.maxRatio);
        c.tolerance = limit;
        if (ratio > tolerances.timing.maxRatio) {
          c.verdict = Verdict::Regressed;
          char maxText[32];
          std::snprintf(maxText, sizeof maxText, "%.2fx", tolerances.timing.maxRatio);
          std::string median = c.samples > 1 ? " (median of " + std::to_string(c.samples) + " runs)" : "";
          c.message = base.key() + ": timing \"" + name + "\" is " + formatNumber(cms) + " ms" + median + ", " +
                      ratioText + " the baseline " + formatNumber(bms) + " ms, above the limit " + maxText;
        }
      }
      result.checks.push_back(std::move(c));
    }
  }
  if (oneRun && result.rowsCompared == 0 && !current.rows.empty())
    problems.push_back(formatError(current.path, current.pointers[0],
                                   "row \"" + current.rows[0].key() + "\" matches none of the " +
                                       std::to_string(baseline.rows.size()) + " rows of the baseline " +
                                       baseline.path + "; expected a row of the same scene, light and configuration"));
  for (size_t i = 0; i < current.rows.size(); ++i) {
    if (matched.count(current.rows[i].key())) continue;
    ++result.rowsNew;
    if (comparesNothing(current.rows[i])) nothingCompared(i, nlohmann::json());
    GateCheck c = baseCheck(current.rows[i], "row", "(row)");
    c.verdict = Verdict::New;
    c.tolerance = "-";
    c.message = current.rows[i].key() + ": new row (not in the baseline " + baseline.path + ")";
    result.checks.push_back(std::move(c));
  }
  throwProblems(problems);

  std::stable_sort(result.checks.begin(), result.checks.end(), [](const GateCheck& a, const GateCheck& b) {
    return verdictRank(a.verdict) < verdictRank(b.verdict);
  });
  for (const GateCheck& c : result.checks) {
    switch (c.verdict) {
      case Verdict::Regressed: ++result.regressions; break;
      case Verdict::Improved: ++result.improvements; break;
      case Verdict::Pass: ++result.passes; break;
      case Verdict::Reported: ++result.reported; break;
      case Verdict::New: result.newMetrics += c.kind == "metric"; break;
    }
  }
  return result;
}

std::string formatGateTable(const GateResult& result, bool brief) {
  std::vector<std::array<std::string, 6>> lines;
  lines.push_back({"verdict", "row", "metric", "baseline", "current", "tolerance"});
  for (const GateCheck& c : result.checks) {
    if (brief && (c.verdict == Verdict::Pass || c.verdict == Verdict::Reported)) continue;
    std::string metric = c.kind == "timing" ? c.metric + " (ms)" : c.metric;
    std::string bs = c.baseline.is_null() ? "-" : formatValue(c.baseline);
    std::string cs = c.current.is_null() ? "-" : formatValue(c.current);
    if (c.baseline.is_number() && c.current.is_number()) {
      auto [b2, c2] = formatPair(c.baseline.get<double>(), c.current.get<double>());
      bs = b2;
      cs = c2;
      if (c.kind == "timing" && c.baseline.get<double>() > 0) {
        char ratio[32];
        std::snprintf(ratio, sizeof ratio, " (%.2fx)", c.current.get<double>() / c.baseline.get<double>());
        cs += ratio;
      }
      if (c.kind == "timing" && c.samples > 1) cs = "median of " + std::to_string(c.samples) + ": " + cs;
    }
    lines.push_back({toString(c.verdict), c.rowKey, metric, bs, cs, c.tolerance});
  }
  std::array<size_t, 6> width{};
  for (auto& l : lines)
    for (size_t i = 0; i < 6; ++i) width[i] = std::max(width[i], l[i].size());
  std::string out;
  for (auto& l : lines) {
    std::string line;
    for (size_t i = 0; i < 6; ++i) {
      std::string cell = l[i];
      // Numbers right-aligned, words left-aligned.
      if (i == 3 || i == 4) cell = std::string(width[i] - cell.size(), ' ') + cell;
      else if (i < 5) cell += std::string(width[i] - cell.size(), ' ');
      line += (i ? "  " : "") + cell;
    }
    out += line + "\n";
  }
  if (brief && lines.size() == 1) out += "(no regressions, improvements or new entries)\n";
  return out;
}

nlohmann::json gateToJson(const GateResult& result, const ResultFile& current, const ResultFile& baseline,
                          const Tolerances& tolerances) {
  nlohmann::json j;
  j["schema"] = kGateSchema;
  j["passed"] = result.passed();
  j["summary"] = result.summary();
  j["current"] = current.path;
  j["baseline"] = baseline.path;
  j["tolerances"] = tolerances.origin;
  j["counts"] = {
      {"regressions", result.regressions}, {"improvements", result.improvements},  {"passes", result.passes},
      {"reported", result.reported},       {"rows_compared", result.rowsCompared}, {"rows_new", result.rowsNew},
      {"rows_not_run", result.rowsNotRun},
      {"new_metrics", result.newMetrics}};
  nlohmann::json checks = nlohmann::json::array();
  for (const GateCheck& c : result.checks) {
    nlohmann::json k = {{"row", c.rowKey},          {"scene", c.scene},
                        {"config", c.config},       {"light", c.light},
                        {"kind", c.kind},           {"metric", c.metric},
                        {"baseline", c.baseline},   {"current", c.current},
                        {"tolerance", c.tolerance}, {"verdict", toString(c.verdict)}};
    if (c.kind == "timing") k["samples"] = c.samples;
    if (!c.message.empty()) k["message"] = c.message;
    checks.push_back(std::move(k));
  }
  j["checks"] = std::move(checks);
  return j;
}

std::string gateToJunitXml(const GateResult& result) {
  // One <testsuite> per row, one <testcase> per metric or timing of that row; regressions carry a
  // <failure> whose message names the metric and both values.
  std::map<std::string, std::vector<const GateCheck*>> byRow;
  std::vector<std::string> order;
  for (const GateCheck& c : result.checks) {
    if (!byRow.count(c.rowKey)) order.push_back(c.rowKey);
    byRow[c.rowKey].push_back(&c);
  }
  std::sort(order.begin(), order.end());
  std::ostringstream x;
  size_t tests = result.checks.size();
  x << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  x << "<testsuites name=\"shadowlab gate\" tests=\"" << tests << "\" failures=\"" << result.regressions
    << "\" errors=\"0\">\n";
  for (const std::string& row : order) {
    const auto& checks = byRow[row];
    size_t failures = 0;
    for (auto* c : checks) failures += c->verdict == Verdict::Regressed;
    x << "  <testsuite name=\"" << escapeMarkup(row) << "\" tests=\"" << checks.size() << "\" failures=\"" << failures
      << "\" errors=\"0\" skipped=\"0\">\n";
    for (auto* c : checks) {
      std::string name = c->kind == "timing" ? "timing." + c->metric : c->metric;
      x << "    <testcase classname=\"" << escapeMarkup(row) << "\" name=\"" << escapeMarkup(name) << "\">";
      if (c->verdict == Verdict::Regressed) {
        x << "\n      <failure message=\"" << escapeMarkup(c->message) << "\" type=\"regression\">"
          << escapeMarkup("baseline " + formatValue(c->baseline) + ", current " + formatValue(c->current) +
                          ", tolerance " + c->tolerance)
          << "</failure>\n    ";
      } else if (c->verdict != Verdict::Pass) {
        std::string note = toString(c->verdict) + ": baseline " +
                           (c->baseline.is_null() ? std::string("-") : formatValue(c->baseline)) + ", current " +
                           (c->current.is_null() ? std::string("-") : formatValue(c->current));
        x << "<system-out>" << escapeMarkup(note) << "</system-out>";
      }
      x << "</testcase>\n";
    }
    x << "  </testsuite>\n";
  }
  x << "</testsuites>\n";
  return x.str();
}

ResultFile mergeResultFiles(const std::vector<ResultFile>& files) {
  if (files.size() == 1) return files.front();
  ResultFile merged;
  merged.schema = "shadowlab.results/1";
  std::map<std::string, size_t> index;                              // row key -> merged row
  std::vector<std::map<std::string, std::vector<double>>> samples;  // merged row -> timing -> runs
  for (const ResultFile& f : files) {
    checkDuplicates(f);
    merged.path += (merged.path.empty() ? "" : " + ") + f.path;
    for (size_t i = 0; i < f.rows.size(); ++i) {
      const ResultRow& row = f.rows[i];
      auto [it, fresh] = index.emplace(row.key(), merged.rows.size());
      if (fresh) {
        merged.rows.push_back(row);
        merged.pointers.push_back(f.pointers[i]);
        merged.rowPaths.push_back(f.pathOf(i));
        merged.repeats.push_back(1);
        samples.emplace_back();
      } else {
        // A repeated run: metrics must agree exactly; only timings may differ.
        const size_t m = it->second;
        std::map<std::string, nlohmann::json> a, b;
        flatten(merged.rows[m].metrics, "", a);
        flatten(row.metrics, "", b);
        for (auto& [name, value] : b) {
          auto other = a.find(name);
          std::string was = other == a.end() ? std::string("absent") : formatValue(other->second);
          if (other == a.end() || other->second != value)
            throw InputError(formatError(f.pathOf(i), metricPointer(f.pointers[i], "metrics", name),
                                         "row \"" + row.key() + "\" repeats the run in " + merged.rowPaths[m] +
                                             " but metric \"" + name + "\" is " + formatValue(value) + " here and " +
                                             was +
                                             " there; expected repeated runs to agree (the pipeline is "
                                             "deterministic)"));
        }
        for (auto& [name, value] : a)
          if (!b.count(name))
            throw InputError(formatError(f.pathOf(i), f.pointers[i] + "/metrics",
                                         "row \"" + row.key() + "\" repeats the run in " + merged.rowPaths[m] +
                                             " but has no metric \"" + name + "\"; expected the same metrics"));
        ++merged.repeats[it->second];
      }
      for (auto t = row.timings.begin(); t != row.timings.end(); ++t)
        if (t.value().is_number()) samples[it->second][t.key()].push_back(t.value().get<double>());
    }
  }
  for (size_t m = 0; m < merged.rows.size(); ++m) {
    if (merged.repeats[m] == 1) continue;
    for (auto& [name, values] : samples[m]) {
      std::sort(values.begin(), values.end());
      size_t n = values.size();
      merged.rows[m].timings[name] = n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
    }
  }
  merged.document = baselineDocument(merged);
  return merged;
}

nlohmann::json baselineDocument(const ResultFile& f) {
  // One metrics.json or stability.json stays one row of its kind (the row only: a stability
  // baseline keeps no per-frame numbers).
  if ((f.schema == "shadowlab.metrics/1" || f.schema == "shadowlab.stability/1") && f.rows.size() == 1) {
    nlohmann::json j = f.rows[0].toJson();
    j["schema"] = f.schema;
    return j;
  }
  nlohmann::json rows = nlohmann::json::array();
  for (const ResultRow& r : f.rows) rows.push_back(r.toJson());
  return {{"schema", "shadowlab.results/1"}, {"rows", std::move(rows)}};
}

std::vector<std::string> describeBaselineUpdate(const ResultFile& current, const ResultFile& baseline) {
  std::vector<std::string> lines;
  std::map<std::string, const ResultRow*> baseIndex, curIndex;
  for (auto& r : baseline.rows) baseIndex[r.key()] = &r;
  for (auto& r : current.rows) curIndex[r.key()] = &r;
  for (auto& r : current.rows) {
    auto b = baseIndex.find(r.key());
    if (b == baseIndex.end()) {
      lines.push_back("+ " + r.key() + ": new row");
      continue;
    }
    std::map<std::string, nlohmann::json> bm, cm;
    flatten(b->second->metrics, "", bm);
    flatten(r.metrics, "", cm);
    for (auto& [name, cv] : cm) {
      auto bi = bm.find(name);
      if (bi == bm.end()) lines.push_back("~ " + r.key() + ": metric \"" + name + "\" added: " + formatValue(cv));
      else if (bi->second != cv) {
        std::string bs = formatValue(bi->second), cs = formatValue(cv);
        if (bi->second.is_number() && cv.is_number())
          std::tie(bs, cs) = formatPair(bi->second.get<double>(), cv.get<double>());
        lines.push_back("~ " + r.key() + ": metric \"" + name + "\" " + bs + " -> " + cs);
      }
    }
    for (auto& [name, bv] : bm)
      if (!cm.count(name))
        lines.push_back("~ " + r.key() + ": metric \"" + name + "\" removed (was " + formatValue(bv) + ")");
    if (b->second->method != r.method) lines.push_back("~ " + r.key() + ": method changed");
  }
  for (auto& r : baseline.rows)
    if (!curIndex.count(r.key())) lines.push_back("- " + r.key() + ": row removed");
  return lines;
}

}  // namespace shadowlab
