// `shadowlab tune`: the searches (compare/TUNE.md, "The search") and their bookkeeping. Every
// configuration is evaluated through runSweep with writeResults off, so each row lands in the
// sweep journal (DIR/rows.jsonl) exactly as a sweep writes it: a tune run again finds its rows
// there and walks the same deterministic path without rendering anything.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <optional>
#include <set>

#include "shadowlab/compare/classes.h"
#include "shadowlab/compare/tune.h"
#include "json_number.h"
#include "tune_output.h"
#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/io.h"
#include "shadowlab/scenes/number_text.h"

namespace shadowlab {
namespace {

namespace fs = std::filesystem;

struct Interrupted {};

using Point = std::vector<size_t>;  // one value index per TunePlan::keys entry
using CostKey = std::pair<double, double>;

struct Score {
  double objective = std::numeric_limits<double>::infinity();  // lower is better
  bool feasible = false;
};

class Engine {
 public:
  Engine(TunePlan& plan, SweepRunner& runner, const TuneOptions& options, TuneResult& result)
      : plan_(plan), runner_(runner), options_(options), result_(result) {
    sceneJobs_ = plan.sweep.jobs;  // one per scene: its variant and light
    journal_ = readSweepJournal((fs::path(options.outDir) / "rows.jsonl").string());
    baseConfig_ = plan.sweep.configs.at(0);
    for (size_t k = 0; k < plan.keys.size(); ++k) {
      if (plan.keys[k].role == TuneRole::Monotone) sizeKey_ = long(k);
      if (plan.keys[k].role == TuneRole::Bias) biasKeys_.push_back(k);
      if (plan.keys[k].role == TuneRole::Categorical) catKeys_.push_back(k);
    }
    // Bias searches start at the base method's value (the nearest candidate); later searches start
    // where the last feasible point was.
    warm_.assign(plan.keys.size(), 0);
    const nlohmann::json base = methodToJson(plan.base);
    for (size_t k : biasKeys_) {
      const double b = base.at(plan.keys[k].key).get<double>();
      double bestDist = std::numeric_limits<double>::infinity();
      for (size_t i = 0; i < plan.keys[k].values.size(); ++i) {
        const double d = std::fabs(std::strtod(plan.keys[k].values[i].c_str(), nullptr) - b);
        if (d < bestDist) {
          bestDist = d;
          warm_[k] = i;
        }
      }
    }
  }

  TuneChoice search(const std::string& scope, const std::vector<size_t>& scenes) {
    asked_.clear();
    runNow_ = 0;
    TuneChoice c;
    c.scope = scope;
    c.scenes = scenes;
    std::optional<Point> chosen;
    if (!std::isnan(plan_.spec.maxError)) chosen = searchMaxError(scenes);
    else chosen = searchBudget(scenes);
    c.met = chosen.has_value();
    if (chosen) {
      c.evaluation = long(evaluation(*chosen));
    } else {
      // The best found: the lowest objective among configurations run on every scene of the scope
      // (looking at rows other searches ran does not count them as this search's).
      const auto asked = asked_;
      double bestObj = std::numeric_limits<double>::infinity();
      for (size_t e = 0; e < result_.evaluations.size(); ++e) {
        if (!hasRows(e, scenes)) continue;
        const double o = score(e, scenes).objective;
        if (o < bestObj) {
          bestObj = o;
          c.evaluation = long(e);
        }
      }
      asked_ = asked;
    }
    if (c.evaluation >= 0) {
      const TuneEvaluation& e = result_.evaluations[size_t(c.evaluation)];
      c.worstError = -1;
      for (size_t s : scenes) {
        const double err = numberAt(e.rows.at(s).metrics, "error_rate");
        if (err > c.worstError) {
          c.worstError = err;
          c.worstScene = plan_.sweep.sceneNames[s];
        }
        c.measuredMs = std::max(c.measuredMs, methodMs(e.rows.at(s)));
      }
      std::tie(c.costMs, c.mapBytes) = tuneCost(e, scenes);
    }
    c.rowsAsked = asked_.size();
    c.rowsRun = runNow_;
    return c;
  }

 private:
  // ---- configurations and rows ----------------------------------------------------------------
  std::string valueOf(const Point& p, const std::string& key) const {
    for (size_t k = 0; k < plan_.keys.size(); ++k)
      if (plan_.keys[k].key == key) return plan_.keys[k].values[p[k]];
    return canonicalValueText(methodToJson(plan_.base).at(key));
  }

  // A key that does not matter at this point (filter.size without pcf) is held at its first value,
  // so the same configuration has one name.
  Point normalize(Point p) const {
    for (size_t k = 0; k < plan_.keys.size(); ++k) {
      const TuneKey& t = plan_.keys[k];
      if (!t.onlyWithKey.empty() && valueOf(p, t.onlyWithKey) != t.onlyWithValue) p[k] = 0;
    }
    return p;
  }

  size_t evaluation(const Point& raw) {
    const Point p = normalize(raw);
    std::vector<std::pair<std::string, std::string>> values;
    for (size_t k = 0; k < plan_.keys.size(); ++k) values.emplace_back(plan_.keys[k].key, plan_.keys[k].values[p[k]]);
    Method method = plan_.base;
    for (const auto& [k, v] : values) applyMethodSetting(method, k, v, "shadowlab tune");
    // The one name of a configuration (config_name.h), as run and sweep name it: the fixed scene:
    // values are part of it.
    const std::string config = configName(method, baseConfig_.sceneOverrides);
    auto found = byConfig_.find(config);
    if (found != byConfig_.end()) return found->second;
    TuneEvaluation e;
    e.config = config;
    e.values = values;
    e.method = method;
    validateMethod(e.method, "shadowlab tune: configuration " + config);
    for (const auto& job : sceneJobs_)
      e.cost.push_back(estimateMethodCost(plan_.sweep.variants[job.variantIndex], e.method, job.light));
    result_.evaluations.push_back(std::move(e));
    points_.push_back(p);
    byConfig_[config] = result_.evaluations.size() - 1;
    return result_.evaluations.size() - 1;
  }

  bool hasRows(size_t e, const std::vector<size_t>& scenes) const {
    for (size_t s : scenes)
      if (!result_.evaluations[e].rows.count(s)) return false;
    return true;
  }

  // Runs the rows of `e` that are missing on `scenes` (one runSweep: journal, resume, device check).
  void ensure(size_t e, const std::vector<size_t>& scenes) {
    TuneEvaluation& ev = result_.evaluations[e];
    std::vector<size_t> missing;
    for (size_t s : scenes) {
      asked_.insert({e, s});
      if (!ev.rows.count(s)) missing.push_back(s);
    }
    if (missing.empty()) return;
    // Rows an earlier run (or a sweep of the same configurations) left in the journal, read once
    // at the start: runSweep would find them too, but reads the whole journal on every call.
    const nlohmann::json methodJson = methodToJson(ev.method);
    for (auto it = missing.begin(); it != missing.end();) {
      const SweepJob& job = sceneJobs_[*it];
      ResultRow probe;
      probe.scene = job.sceneName;
      probe.config = ev.config;
      probe.light = job.light;
      auto found = journal_.find(probe.key());
      if (found != journal_.end() && found->second.sceneHash == plan_.sweep.variants[job.variantIndex].hash &&
          found->second.row.method == methodJson && found->second.device == device()) {
        ev.rows[*it] = found->second.row;
        ++result_.rowsResumed;
        it = missing.erase(it);
      } else {
        ++it;
      }
    }
    if (missing.empty()) {
      checkTargetsConstrain(ev);
      progressLine(e, scenes, false);
      return;
    }
    SweepConfig config = baseConfig_;
    config.config = ev.config;
    config.values = ev.values;
    config.method = ev.method;
    plan_.sweep.configs = {config};
    plan_.sweep.jobs.clear();
    for (size_t s : missing) {
      SweepJob job = sceneJobs_[s];
      job.configIndex = 0;
      job.config = ev.config;
      plan_.sweep.jobs.push_back(job);
    }
    SweepOptions o;
    o.outDir = options_.outDir;
    o.progress = nullptr;
    o.stop = options_.stop;
    o.writeResults = false;
    o.writeReport = false;
    const SweepSummary summary = runSweep(plan_.sweep, runner_, o);
    for (size_t i = 0; i < missing.size(); ++i)
      if (i < summary.rows.size() && !summary.rows[i].scene.empty()) ev.rows[missing[i]] = summary.rows[i];
    result_.rowsRun += summary.ran;
    result_.rowsResumed += summary.resumed;
    runNow_ += summary.ran;
    if (summary.interrupted) throw Interrupted{};
    checkTargetsConstrain(ev);
    progressLine(e, scenes, summary.ran > 0);
  }

  // A --max target on a region (penumbra_mae, ...) constrains no scene whose truth has no pixel of
  // that region (tuneTargetVacuous): one that constrains none of the scenes would be met by any
  // configuration, a target in name only, so it is refused; one that skips some scenes is said.
  // The regions are the truth's, the same for every configuration: the first configuration with a
  // row on every scene decides, before the search spends more rows.
  void checkTargetsConstrain(const TuneEvaluation& ev) {
    if (targetsChecked_ || ev.rows.size() < sceneJobs_.size()) return;
    targetsChecked_ = true;
    for (const auto& [key, limit] : plan_.spec.maxRates) {
      std::string skipped, pixels;
      size_t count = 0;
      for (const auto& r : kVisRegions)
        if (key == r.maeMetric || key == r.rmseMetric) pixels = r.pixelsMetric;
      for (const auto& [s, row] : ev.rows)
        if (tuneTargetVacuous(row.metrics, key)) skipped += (count++ ? ", " : "") + plan_.sweep.sceneNames[s];
      if (count == 0) continue;
      const std::string why = " (" + pixels + " 0: their truth has no pixel of that region)";
      if (count == ev.rows.size())
        throw InputError("--max " + key + "=" + numberText(limit) +
                         ": error: constrains none of the scenes: " + skipped + why +
                         "; expected a target some scene measures (a penumbra needs a sized light, scenes/FORMAT.md)");
      notes_.push_back("--max " + key + " constrains nothing on " + skipped + why + ": met there by definition");
    }
  }

  void progressLine(size_t e, const std::vector<size_t>& scenes, bool ran) {
    const TuneEvaluation& ev = result_.evaluations[e];
    if (options_.progress) {
      const Score sc = score(e, scenes);
      double worst = 0;
      std::string worstScene;
      for (size_t s : scenes) {
        const double err = numberAt(ev.rows.at(s).metrics, "error_rate");
        if (err >= worst) {
          worst = err;
          worstScene = plan_.sweep.sceneNames[s];
        }
      }
      // An outside renderer has no cost model: its own measured frame time instead.
      double rendererMs = 0;
      for (size_t s : scenes) rendererMs = std::max(rendererMs, methodMs(ev.rows.at(s)));
      char cost[64];
      if (ev.method.renderer.empty()) std::snprintf(cost, sizeof cost, "estimated %.2f ms", tuneCost(ev, scenes).first);
      else std::snprintf(cost, sizeof cost, "renderer_frame_ms %.2f", rendererMs);
      std::fprintf(options_.progress, "tune: %s: worst error_rate %.3g (%s), %s%s%s\n", ev.config.c_str(), worst,
                   worstScene.c_str(), cost,
                   sc.feasible ? (std::isnan(plan_.spec.maxError) ? ", within the budget" : ", meets the target") : "",
                   ran ? "" : " (from rows.jsonl)");
      std::fflush(options_.progress);
    }
  }

  const std::string& device() {
    if (!deviceKnown_) {
      device_ = runner_.deviceName();
      deviceKnown_ = true;
    }
    return device_;
  }

  Score score(size_t e, const std::vector<size_t>& scenes) {
    ensure(e, scenes);
    const TuneEvaluation& ev = result_.evaluations[e];
    Score s;
    if (!std::isnan(plan_.spec.maxError)) {
      // Normalized excess over the tightest limit: <= 0 everywhere means the target is met, and
      // with error_rate alone it orders configurations as the worst error_rate does.
      double worst = -std::numeric_limits<double>::infinity();
      auto excess = [&](double rate, double limit) {
        if (!std::isfinite(rate)) return std::numeric_limits<double>::infinity();
        return (rate - limit) / std::max(limit, 1e-9);
      };
      for (size_t sc : scenes) {
        const nlohmann::json& m = ev.rows.at(sc).metrics;
        worst = std::max(worst, excess(numberAt(m, "error_rate"), plan_.spec.maxError));
        for (const auto& [key, limit] : plan_.spec.maxRates)
          if (!tuneTargetVacuous(m, key)) worst = std::max(worst, excess(numberAt(m, key.c_str()), limit));
      }
      s.objective = worst;
      s.feasible = worst <= 0;
    } else {
      double worst = 0;
      for (size_t sc : scenes) worst = std::max(worst, numberAt(ev.rows.at(sc).metrics, "error_rate"));
      s.objective = std::isfinite(worst) ? worst : std::numeric_limits<double>::infinity();
      s.feasible = tuneCost(ev, scenes).first <= plan_.spec.budgetMs;
    }
    return s;
  }

  CostKey costOf(const Point& p, const std::vector<size_t>& scenes) {
    return tuneCost(result_.evaluations[evaluation(p)], scenes);
  }

  // ---- bias: U-curves ----------------------------------------------------------------------------
  // Minimizes the objective along key k (a U-curve: acne falls and leaks rise with the bias). The
  // start p[k] first (where the last feasible point was: often feasible again, one evaluation),
  // then golden-section over the whole range (not a local descent: at small images the curve has
  // plateaus a local walk stops on), then the best point's neighbours. With `stopWhenFeasible`,
  // returns as soon as a point meets the target.
  Point lineSearch(Point p, size_t k, const std::vector<size_t>& scenes, bool stopWhenFeasible, bool& feasibleSeen) {
    const long n = long(plan_.keys[k].values.size());
    std::map<long, double> seen;
    long bestI = long(p[k]);
    double bestF = std::numeric_limits<double>::infinity();
    auto f = [&](long i) {
      auto it = seen.find(i);
      if (it != seen.end()) return it->second;
      Point q = p;
      q[k] = size_t(i);
      const Score s = score(evaluation(q), scenes);
      seen[i] = s.objective;
      if (s.objective < bestF || (s.objective == bestF && i < bestI)) {
        bestF = s.objective;
        bestI = i;
      }
      if (s.feasible) feasibleSeen = true;
      return s.objective;
    };
    auto done = [&] { return stopWhenFeasible && feasibleSeen; };
    auto result = [&] {
      Point q = p;
      q[k] = size_t(bestI);
      return q;
    };
    f(long(p[k]));
    if (done() || n == 1) return result();
    // Golden-section on the integers of [lo, hi].
    constexpr double kInvPhi = 0.6180339887498949;
    long lo = 0, hi = n - 1;
    while (hi - lo > 3) {
      long c = hi - long(std::lround((hi - lo) * kInvPhi));
      long d = lo + long(std::lround((hi - lo) * kInvPhi));
      if (c >= d) d = c + 1;
      const double fc = f(c);
      if (done()) return result();
      const double fd = f(d);
      if (done()) return result();
      if (fc <= fd) hi = d;
      else lo = c;
    }
    for (long i = lo; i <= hi; ++i) {
      f(i);
      if (done()) return result();
    }
    for (long i : {bestI - 1, bestI + 1})
      if (i >= 0 && i < n) {
        f(i);
        if (done()) return result();
      }
    return result();
  }

  // Coordinate descent over the bias keys (each by lineSearch), at most three rounds.
  Point optimizeBias(Point p, const std::vector<size_t>& scenes, bool stopWhenFeasible, bool& feasible) {
    feasible = false;
    if (biasKeys_.empty()) {
      feasible = score(evaluation(p), scenes).feasible;
      return p;
    }
    for (int round = 0; round < 3; ++round) {
      bool changed = false;
      for (size_t k : biasKeys_) {
        bool seen = false;
        Point q = lineSearch(p, k, scenes, stopWhenFeasible, seen);
        if (q != p) changed = true;
        p = q;
        if (stopWhenFeasible && seen) {
          // The line's best objective is <= that of the feasible point seen (<= 0): feasible too.
          feasible = true;
          return p;
        }
      }
      if (!changed || biasKeys_.size() == 1) break;
    }
    feasible = score(evaluation(p), scenes).feasible;
    return p;
  }

  // ---- structure: categorical keys x map size ---------------------------------------------------
  std::vector<Point> combos(const std::vector<size_t>& scenes) {
    std::vector<Point> out;
    std::set<std::string> names;
    Point p(plan_.keys.size(), 0);
    for (size_t k : biasKeys_) p[k] = warm_[k];
    while (true) {
      const Point q = normalize(p);
      if (names.insert(result_.evaluations[evaluation(q)].config).second) out.push_back(q);
      bool doneAll = true;
      for (size_t a = catKeys_.size(); a-- > 0;) {
        const size_t k = catKeys_[a];
        if (++p[k] < plan_.keys[k].values.size()) {
          doneAll = false;
          break;
        }
        p[k] = 0;
      }
      if (doneAll) break;
    }
    // Cheapest first (at the smallest map size), so the pruning below bites early.
    std::stable_sort(out.begin(), out.end(),
                     [&](const Point& a, const Point& b) { return costOf(a, scenes) < costOf(b, scenes); });
    return out;
  }

  size_t sizeCount() const { return sizeKey_ < 0 ? 1 : plan_.keys[size_t(sizeKey_)].values.size(); }
  Point withSize(Point p, size_t i) const {
    if (sizeKey_ >= 0) p[size_t(sizeKey_)] = i;
    return p;
  }
  Point withWarmBias(Point p) const {
    for (size_t k : biasKeys_) p[k] = warm_[k];
    return p;
  }

  std::optional<Point> feasibleAt(const Point& combo, size_t sizeIndex, const std::vector<size_t>& scenes) {
    bool feasible = false;
    Point q = optimizeBias(withWarmBias(withSize(combo, sizeIndex)), scenes, true, feasible);
    if (!feasible) return std::nullopt;
    for (size_t k : biasKeys_) warm_[k] = q[k];
    return q;
  }

  // --max-error: per combination (cheapest first), the smallest map size that meets the target
  // (bisection; accuracy grows with the size), only among sizes cheaper than the best so far.
  std::optional<Point> searchMaxError(const std::vector<size_t>& scenes) {
    std::optional<Point> best;
    CostKey bestCost;
    for (const Point& combo : combos(scenes)) {
      if (best && !(costOf(withSize(combo, 0), scenes) < bestCost)) continue;
      size_t hi = sizeCount() - 1;
      while (best && hi > 0 && !(costOf(withSize(combo, hi), scenes) < bestCost)) --hi;
      std::optional<Point> found = feasibleAt(combo, hi, scenes);
      if (!found) continue;
      size_t lo = 0;
      while (lo < hi) {
        const size_t mid = (lo + hi) / 2;
        if (auto q = feasibleAt(combo, mid, scenes)) {
          hi = mid;
          found = q;
        } else {
          lo = mid + 1;
        }
      }
      best = *found;
      bestCost = costOf(*best, scenes);
    }
    if (!best) return std::nullopt;
    // The chosen structure's bias: the minimax point (the crossover of acne and leaks), not merely
    // the first that met the target.
    bool feasible = false;
    Point refined = optimizeBias(*best, scenes, false, feasible);
    if (feasible && score(evaluation(refined), scenes).objective <= score(evaluation(*best), scenes).objective)
      best = refined;
    for (size_t k : biasKeys_) warm_[k] = (*best)[k];
    return best;
  }

  // --budget-ms: per combination, the largest map size within the budget (accuracy grows with the
  // size), its minimax bias; the lowest worst-case error wins (then the lower cost).
  std::optional<Point> searchBudget(const std::vector<size_t>& scenes) {
    std::optional<Point> best;
    double bestObj = std::numeric_limits<double>::infinity();
    CostKey bestCost;
    for (const Point& combo : combos(scenes)) {
      long hi = long(sizeCount()) - 1;
      while (hi >= 0 && costOf(withSize(combo, size_t(hi)), scenes).first > plan_.spec.budgetMs) --hi;
      if (hi < 0) continue;
      bool feasible = false;
      Point q = optimizeBias(withWarmBias(withSize(combo, size_t(hi))), scenes, false, feasible);
      const double obj = score(evaluation(q), scenes).objective;
      const CostKey cost = costOf(q, scenes);
      if (!best || obj < bestObj || (obj == bestObj && cost < bestCost)) {
        best = q;
        bestObj = obj;
        bestCost = cost;
        for (size_t k : biasKeys_) warm_[k] = q[k];
      }
    }
    return best;
  }

  TunePlan& plan_;
  SweepRunner& runner_;
  const TuneOptions& options_;
  TuneResult& result_;
  std::vector<SweepJob> sceneJobs_;
  SweepConfig baseConfig_;
  long sizeKey_ = -1;
  std::vector<size_t> biasKeys_, catKeys_;
  Point warm_;
  std::map<std::string, size_t> byConfig_;
  std::vector<Point> points_;
  std::set<std::pair<size_t, size_t>> asked_;
  size_t runNow_ = 0;
  std::map<std::string, SweepJournalRow> journal_;
  std::string device_;
  bool deviceKnown_ = false;
  bool targetsChecked_ = false;

 public:
  std::vector<std::string> notes_;  // said once the search is done (checkTargetsConstrain)
};

// The dense grid of the plan's keys and values through the sweep loop (same journal: the rows the
// search ran are resumed), and its best configuration by the same target and cost model. False
// when interrupted.
bool checkDenseGrid(const TunePlan& plan, SweepRunner& runner, const TuneOptions& options, TuneResult& result) {
  SweepSpec spec;
  spec.scenes = plan.sweep.scenePaths;
  spec.fixed = plan.spec.fixed;
  spec.methodFile = plan.spec.methodFile;
  spec.light = plan.spec.light;
  spec.spp = plan.spec.spp;
  spec.lightSamples = plan.spec.lightSamples;
  for (const auto& k : plan.keys) {
    SweepAxis axis;
    axis.key = k.key;
    axis.origin = k.origin;
    for (const auto& v : k.values) axis.values.push_back(v);
    spec.grid.push_back(axis);
  }
  const SweepPlan grid = planSweep(spec);
  if (options.progress) {
    std::fprintf(options.progress, "tune: --check-grid: running the dense grid, %zu rows (the search's are resumed)\n",
                 grid.jobs.size());
    std::fflush(options.progress);
  }
  SweepOptions o;
  o.outDir = options.outDir;
  o.progress = options.progress;
  o.stop = options.stop;
  o.writeResults = false;
  o.writeReport = false;
  const SweepSummary summary = runSweep(grid, runner, o);
  if (summary.interrupted) return false;
  result.grid.checked = true;
  result.grid.rows = grid.jobs.size();
  result.grid.rowsRun = summary.ran;
  // Gather each configuration's rows into a TuneEvaluation (scene index = the plan's).
  std::vector<TuneEvaluation> evals(grid.configs.size());
  for (size_t c = 0; c < grid.configs.size(); ++c) {
    evals[c].config = grid.configs[c].config;
    evals[c].method = grid.configs[c].method;
    for (const auto& job : plan.sweep.jobs)
      evals[c].cost.push_back(
          estimateMethodCost(plan.sweep.variants[job.variantIndex], grid.configs[c].method, job.light));
  }
  for (size_t i = 0; i < grid.jobs.size(); ++i)
    evals[grid.jobs[i].configIndex].rows[grid.jobs[i].sceneIndex] = summary.rows[i];
  std::vector<size_t> all;
  for (size_t s = 0; s < plan.sweep.sceneNames.size(); ++s) all.push_back(s);
  const bool target = !std::isnan(plan.spec.maxError);
  const TuneEvaluation* best = nullptr;
  double bestWorst = 0;
  std::pair<double, double> bestCost;
  for (const auto& e : evals) {
    if (!tuneMeetsTarget(plan, e, all)) continue;
    double worst = 0;
    for (size_t s : all) worst = std::max(worst, numberAt(e.rows.at(s).metrics, "error_rate"));
    const auto cost = tuneCost(e, all);
    const bool better =
        !best || (target ? cost < bestCost : (worst < bestWorst || (worst == bestWorst && cost < bestCost)));
    if (better) {
      best = &e;
      bestWorst = worst;
      bestCost = cost;
    }
  }
  result.grid.met = best != nullptr;
  if (best) {
    result.grid.config = best->config;
    result.grid.costMs = bestCost.first;
    result.grid.mapBytes = bestCost.second;
    result.grid.worstError = bestWorst;
  }
  return true;
}

}  // namespace

std::pair<double, double> tuneCost(const TuneEvaluation& e, const std::vector<size_t>& scenes) {
  double ms = 0, bytes = 0;
  for (size_t s : scenes) {
    ms = std::max(ms, e.cost.at(s).estimatedMs);
    bytes = std::max(bytes, e.cost.at(s).mapBytes);
  }
  return {ms, bytes};
}

bool tuneMeetsTarget(const TunePlan& plan, const TuneEvaluation& e, const std::vector<size_t>& scenes) {
  for (size_t s : scenes) {
    auto it = e.rows.find(s);
    if (it == e.rows.end()) return false;
    if (!std::isnan(plan.spec.maxError)) {
      if (!(numberAt(it->second.metrics, "error_rate") <= plan.spec.maxError)) return false;
      for (const auto& [key, limit] : plan.spec.maxRates)
        if (!tuneTargetVacuous(it->second.metrics, key) && !(numberAt(it->second.metrics, key.c_str()) <= limit))
          return false;
    } else if (!(tuneCost(e, scenes).first <= plan.spec.budgetMs)) {
      return false;
    }
  }
  return true;
}

TuneResult runTune(TunePlan& plan, SweepRunner& runner, const TuneOptions& options) {
  TuneResult result;
  const SweepPlan original = plan.sweep;
  makeDirs(options.outDir);
  Engine engine(plan, runner, options, result);
  std::vector<size_t> all;
  for (size_t s = 0; s < original.sceneNames.size(); ++s) all.push_back(s);
  try {
    result.robust = engine.search("all", all);
    if (all.size() > 1)
      for (size_t s : all) result.perScene.push_back(engine.search(original.sceneNames[s], {s}));
  } catch (const Interrupted&) {
    result.interrupted = true;
    plan.sweep = original;
    return result;
  }
  for (const auto& e : result.evaluations) result.rowsTotal += e.rows.size();
  result.gridRows = plan.gridConfigurations * all.size();
  plan.sweep = original;
  if (options.checkGrid && !checkDenseGrid(plan, runner, options, result)) {
    result.interrupted = true;
    return result;
  }
  result.notes = engine.notes_;
  writeTuneOutputs(plan, runner, options, result);
  return result;
}

}  // namespace shadowlab
