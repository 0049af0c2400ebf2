// Failure frontiers: where along a scene parameter each method configuration starts failing.
#include "shadowlab/compare/sweep_frontier.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <utility>

namespace shadowlab {

Frontier findFrontier(const std::vector<double>& metrics, double threshold) {
  Frontier f;
  for (size_t i = 0; i < metrics.size(); ++i) {
    if (metrics[i] > threshold) {
      f.holds = false;
      f.breakIndex = i;
      // A later value back under the threshold does not move the frontier (the first failure is what
      // a user must avoid) but is reported: the error is not monotone along the parameter.
      for (size_t k = i + 1; k < metrics.size(); ++k)
        if (metrics[k] <= threshold) f.recovers = true;
      return f;
    }
  }
  return f;
}

namespace {

bool parseNumber(const std::string& s, double& out) {
  if (s.empty()) return false;
  char* end = nullptr;
  out = std::strtod(s.c_str(), &end);
  return end && *end == '\0' && std::isfinite(out);
}

std::string pct(double rate) {
  char b[64];
  std::snprintf(b, sizeof b, "%.3g%%", rate * 100.0);
  return b;
}

// The last segment of a JSON pointer, for sentences ("/lights/0/elevation_deg" -> "elevation_deg");
// an array index keeps its array's name ("/objects/1/size/0" -> "size/0").
std::string shortName(const std::string& key) {
  std::string p = key.substr(std::string(kSceneKeyPrefix).size());
  size_t slash = p.rfind('/');
  if (slash == std::string::npos) return p;
  const std::string last = p.substr(slash + 1);
  if (slash > 0 && !last.empty() && last.find_first_not_of("0123456789") == std::string::npos) {
    size_t before = p.rfind('/', slash - 1);
    return p.substr(before == std::string::npos ? 0 : before + 1);
  }
  return last;
}

}  // namespace

nlohmann::json computeFrontiers(const SweepPlan& plan, const std::vector<ResultRow>& rows, const std::string& metric,
                                double threshold) {
  nlohmann::json out = nlohmann::json::array();
  const std::string prefix = kSceneKeyPrefix;
  // Axes with a single value are constants: they name no frontier and are left out of labels.
  std::vector<const SweepAxis*> walked;
  std::map<std::string, bool> singleValued;
  const std::vector<SweepAxis> axes = sweptAxes(plan);  // one per key, also for a union of grids
  for (const auto& axis : axes) {
    singleValued[axis.key] = axis.values.size() < 2;
    if (axis.key.rfind(prefix, 0) == 0 && axis.values.size() >= 2) walked.push_back(&axis);
  }
  if (walked.empty()) return out;

  std::map<std::pair<std::string, std::string>, const ResultRow*> byKey;
  for (const auto& r : rows) byKey[{r.scene, r.config}] = &r;

  for (size_t s = 0; s < plan.sceneNames.size(); ++s) {
    const std::string& scene = plan.sceneNames[s];
    const Scene* declared = nullptr;
    for (const auto& job : plan.jobs)
      if (job.sceneIndex == s) {
        declared = &plan.variants[job.variantIndex];
        break;
      }
    for (const SweepAxis* axis : walked) {
      std::string pointer = axis->key.substr(prefix.size());
      // scene:failure is this scene's declared failure pointer.
      if (axis->key == kSceneFailureKey && declared) pointer = declared->failurePointer;
      // Direction: the declared failure list goes from easy to hard; values are walked numerically in
      // that direction, so swept values need not be among the declared ones.
      int harder = 0;  // +1: larger is harder, -1: smaller is harder, 0: grid order
      if (declared && declared->failurePointer == pointer && declared->failureValues.size() >= 2) {
        double a = declared->failureValues.front(), b = declared->failureValues.back();
        harder = b > a ? 1 : (b < a ? -1 : 0);
      }
      // Group this scene's configurations by everything except this axis (the method configuration).
      struct Point {
        double value = 0;
        bool numeric = false;
        size_t gridOrder = 0;
        std::string text, config;
        const ResultRow* row = nullptr;
      };
      std::vector<std::pair<std::string, std::vector<Point>>> groups;  // label -> points, first-seen order
      for (const auto& cfg : plan.configs) {
        // Only the configurations this scene runs that carry the parameter (a grid of a union may
        // sweep it on its own scenes only).
        if (!cfg.runsOn(plan.scenePaths[s])) continue;
        if (std::none_of(cfg.values.begin(), cfg.values.end(), [&](const auto& kv) { return kv.first == axis->key; }))
          continue;
        std::string label, valueText;
        for (const auto& [k, v] : cfg.values) {
          if (k == axis->key) {
            valueText = v;
            continue;
          }
          if (singleValued[k]) continue;
          label += (label.empty() ? "" : ",") + k + "=" + v;
        }
        if (label.empty()) label = "default";
        Point p;
        p.text = valueText;
        p.config = cfg.config;
        p.numeric = parseNumber(valueText, p.value);
        for (size_t i = 0; i < axis->values.size(); ++i)
          if (canonicalValueText(axis->values[i]) == valueText) p.gridOrder = i;
        auto it = byKey.find({scene, cfg.config});
        p.row = it == byKey.end() ? nullptr : it->second;
        auto g = std::find_if(groups.begin(), groups.end(), [&](const auto& e) { return e.first == label; });
        if (g == groups.end()) {
          groups.push_back({label, {}});
          g = groups.end() - 1;
        }
        g->second.push_back(p);
      }
      for (auto& [label, points] : groups) {
        bool allNumeric = std::all_of(points.begin(), points.end(), [](const Point& p) { return p.numeric; });
        int dir = allNumeric ? harder : 0;
        std::stable_sort(points.begin(), points.end(), [&](const Point& a, const Point& b) {
          if (dir > 0) return a.value < b.value;
          if (dir < 0) return a.value > b.value;
          return a.gridOrder < b.gridOrder;
        });
        std::vector<double> metrics;
        nlohmann::json walkedPoints = nlohmann::json::array(), missing = nlohmann::json::array();
        std::vector<const Point*> used;
        for (const auto& p : points) {
          const nlohmann::json* m = nullptr;
          if (p.row && p.row->metrics.contains(metric)) m = &p.row->metrics.at(metric);
          if (!m || !m->is_number() || !std::isfinite(m->get<double>())) {
            missing.push_back(p.text);
            continue;
          }
          metrics.push_back(m->get<double>());
          used.push_back(&p);
          nlohmann::json v = p.numeric ? nlohmann::json(p.value) : nlohmann::json(p.text);
          walkedPoints.push_back({{"value", v}, {"config", p.config}, {"metric", metrics.back()}});
        }
        if (metrics.empty()) continue;
        Frontier f = findFrontier(metrics, threshold);
        auto valueJson = [&](size_t i) {
          return used[i]->numeric ? nlohmann::json(used[i]->value) : nlohmann::json(used[i]->text);
        };
        nlohmann::json e;
        e["scene"] = scene;
        e["parameter"] = axis->key;
        e["pointer"] = pointer;
        e["direction"] = dir > 0 ? "increasing" : (dir < 0 ? "decreasing" : "grid order");
        e["declared"] = dir != 0;
        e["method"] = label;
        e["metric"] = metric;
        e["threshold"] = threshold;
        e["points"] = walkedPoints;
        e["missing"] = missing;
        e["holds"] = f.holds;
        e["recovers"] = f.recovers;
        e["breaks_at"] = f.holds ? nlohmann::json(nullptr) : valueJson(f.breakIndex);
        // The last value that still passed before the frontier (null: the easiest value already fails).
        e["holds_to"] = f.holds ? valueJson(used.size() - 1)
                                : (f.breakIndex == 0 ? nlohmann::json(nullptr) : valueJson(f.breakIndex - 1));
        const std::string name = shortName(prefix + pointer);
        std::string sentence = label + ": ";
        if (f.holds) {
          sentence += "holds to " + name + "=" + used.back()->text + " (" + metric + " at most " +
                      pct(*std::max_element(metrics.begin(), metrics.end())) + ")";
        } else {
          sentence += "breaks at " + name + "=" + used[f.breakIndex]->text + " (" + metric + " " +
                      pct(metrics[f.breakIndex]) + " > " + pct(threshold) + ")";
          if (f.breakIndex > 0) sentence += ", holds to " + used[f.breakIndex - 1]->text;
          else sentence += ", already at the easiest value";
          if (f.recovers) sentence += "; not monotone: back under the threshold further on";
        }
        e["sentence"] = sentence;
        out.push_back(std::move(e));
      }
    }
  }
  return out;
}

}  // namespace shadowlab
