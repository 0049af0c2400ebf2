#pragma once
// `shadowlab tune`: the least expensive method that meets an accuracy target on every listed scene
// (or the most accurate within a time budget), found by a search that uses the problem's shape
// instead of a full grid. The command, the search, the cost model and the outputs: compare/TUNE.md.
//
// The split mirrors sweeps (sweep.h): planTune validates everything and writes nothing; runTune
// creates the output folder, evaluates configurations through the sweep loop (runSweep with
// writeResults off: every row goes to DIR/rows.jsonl, so a tune resumes like a sweep and its rows
// feed results.json / results.csv / report.html), then writes tuned.json, tune.json and tune.html.
// The SweepRunner is injectable: tests run the search against a fake landscape without renderers.
#include <atomic>
#include <cstdio>
#include <limits>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "shadowlab/compare/method_cost.h"
#include "shadowlab/compare/results.h"
#include "shadowlab/compare/sweep.h"

namespace shadowlab {

// How a tuned key is searched.
enum class TuneRole {
  Bias,         // a U-curve (acne at low values, leaks at high): bracketing + golden-section search
  Monotone,     // accuracy grows with the value (map.size): bisection for the smallest that suffices
  Categorical,  // a few values, each tried (filter, fit, map.format, filter.size, filter.taps)
};

// The keys tune can search, with their role and default range (compare/TUNE.md, "Keys").
struct TunableKey {
  const char* key;
  TuneRole role;
  const char* defaultRange;  // "--range" syntax: "lo:hi:intervals", "lo:hi" (powers of two / odd), or "v1,v2,..."
  const char* onlyWith;      // "filter=pcf": the key matters only then (else held at its first value); "" always
};
const std::vector<TunableKey>& tunableKeys();
// "bias.slope,filter,map.size": what --keys searches when not given.
const char* defaultTuneKeys();

struct TuneSpec {
  std::vector<std::string> scenes;  // bundled names or scene files; empty = every bundled scene
  std::vector<std::string> keys;    // tuned keys (--keys, split); empty: defaultTuneKeys()
  std::vector<std::string> ranges;  // --range key=lo:hi[:n] or key=v1,v2,... (repeatable)
  std::vector<SweepSetting> fixed;  // --fixed key=value: method keys or scene:/pointer values
  std::string methodFile;           // base method file (--method)
  std::string light;                // empty: each scene's first light
  int spp = 1;
  int lightSamples = 64;  // reference samples of a sized light per pixel sample (kDefaultLightSamples)
  // The target: exactly one of maxError (error_rate on every scene <= it, with maxRates: each
  // named metric <= its value too) and budgetMs (the lowest worst-case error_rate whose estimated
  // cost is within it). NaN: not given.
  double maxError = std::numeric_limits<double>::quiet_NaN();
  std::vector<std::pair<std::string, double>> maxRates;  // --max metric=value
  double budgetMs = std::numeric_limits<double>::quiet_NaN();
};

// "0.002" for --max-error / --budget-ms: InputError "FLAG: error: got ...; expected ..." unless a
// finite number >= 0 (--budget-ms: > 0). --max-error is a rate, so also <= 1.
double parseTuneNumber(const std::string& flag, const std::string& text);
// "acne_rate=0.001" (--max): the metric must be one of tuneMaxMetrics(), its value in 0..1.
std::pair<std::string, double> parseTuneMax(const std::string& text);
// What --max accepts, in this order: the error classes' rates (classes.h), mae, rmse, each region's
// mae and rmse (lit_mae, ...), over_shadowing, under_shadowing (compare/METRICS.md).
std::vector<std::string> tuneMaxMetrics();
// A --max target on a region's mae or rmse constrains no scene whose truth has no pixel of that
// region (`<region>_pixels` 0, the metric null): nothing there can be wrong.
bool tuneTargetVacuous(const nlohmann::json& metrics, const std::string& key);

struct TuneKey {
  std::string key;
  TuneRole role = TuneRole::Categorical;
  std::vector<std::string> values;         // canonical texts (as in a row's config), ascending for Bias and Monotone
  std::string origin;                      // "--range bias.slope=0:4" or "default range 0:4:16"
  std::string onlyWithKey, onlyWithValue;  // from TunableKey::onlyWith
};

struct TunePlan {
  TuneSpec spec;
  Method base;                // method file + fixed method keys
  std::vector<TuneKey> keys;  // sorted by key (the order of a row's config)
  // The scenes as loaded with the fixed scene: values, their lights and names (planSweep of the
  // fixed settings alone); runTune reuses it to run each evaluation's rows.
  SweepPlan sweep;
  size_t gridConfigurations = 0;  // the dense grid of the same keys and values (onlyWith keys collapsed)
};

// Validates every argument, key, value and scene; writes nothing. InputError naming the argument.
TunePlan planTune(const TuneSpec& spec);

struct TuneOptions {
  std::string outDir;
  std::FILE* progress = stderr;  // one line per evaluated configuration; null: silent
  const std::atomic<bool>* stop = nullptr;
  bool writeReport = true;  // report.html with charts and best/worst triptychs (as a sweep's)
  bool triptychs = true;    // tune.html's triptych per scene (rendered again through the runner)
  // Also run the dense grid of the same keys and values (into the same journal) and compare its
  // best configuration with the search's choice (TuneResult::grid): the measurement of
  // compare/TUNE.md, "How good is the search".
  bool checkGrid = false;
  std::string reportScript, python;
  // Timed runs of the rows the verdict quotes and of those near each scene's front (SweepOptions).
  int timingRepetitions = kDefaultTimingRepetitions;
};

// One configuration (a point of the tuned keys) and its rows on the scenes it was run on.
struct TuneEvaluation {
  std::string config;                                       // canonical "key=value,..." of the tuned keys
  std::vector<std::pair<std::string, std::string>> values;  // tuned key -> canonical value, sorted by key
  Method method;
  std::map<size_t, ResultRow> rows;  // scene index -> its row
  std::vector<MethodCost> cost;      // per scene (estimateMethodCost)
};

// The answer of one search: over every scene (scope "all", the minimax choice) or one scene.
struct TuneChoice {
  std::string scope;
  std::vector<size_t> scenes;  // indices into TunePlan::sweep.sceneNames
  bool met = false;            // target met / a configuration within the budget was found
  long evaluation = -1;        // the chosen evaluation (the best found when not met); -1: none
  double worstError = 0;       // largest error_rate over the scope's scenes
  std::string worstScene;
  double costMs = 0, mapBytes = 0;  // the model's estimate, largest over the scope's scenes
  double measuredMs = 0;            // measured method_gpu_ms (methodMs), largest over the scenes
  size_t rowsAsked = 0;             // rows this search looked at (new or already evaluated)
  size_t rowsRun = 0;               // of which run for the first time by this search
  std::string sentence;             // the verdict
};

struct TuneResult {
  std::vector<TuneEvaluation> evaluations;
  TuneChoice robust;                                   // every scene: one setting to ship
  std::vector<TuneChoice> perScene;                    // each scene alone
  size_t rowsRun = 0, rowsResumed = 0, rowsTotal = 0;  // rows rendered now / found in rows.jsonl / distinct
  size_t gridRows = 0;                                 // the dense grid's rows (configurations x scenes)
  bool interrupted = false;
  // TuneOptions::checkGrid: the dense grid's best over every scene (--max-error: the cheapest
  // configuration meeting the target; --budget-ms: the lowest worst-case error within the budget).
  struct Grid {
    bool checked = false;
    bool met = false;
    std::string config;  // "" when nothing in the grid meets the target / fits the budget
    double costMs = 0, mapBytes = 0, worstError = 0;
    size_t rows = 0, rowsRun = 0;  // the grid's rows, of which rendered by this run
  } grid;
  std::string verdict;                                                 // the paragraph printed on the terminal
  std::string tunedJson, tuneJson, tuneHtml, resultsJson, reportHtml;  // written files ("" when not)
  std::vector<std::string> notes;
};

// Runs the searches (every scene, then each scene alone), then writes into options.outDir:
// tuned.json (the robust choice as a method file), tune.json, tune.html, results.json,
// results.csv and (writeReport) report.html. Rows already in outDir/rows.jsonl are not run again.
TuneResult runTune(TunePlan& plan, SweepRunner& runner, const TuneOptions& options);

// The scope's worst error_rate, and whether `e` meets the plan's target on every scene of `scenes`
// (false when a scene has no row). Exposed for tests.
bool tuneMeetsTarget(const TunePlan& plan, const TuneEvaluation& e, const std::vector<size_t>& scenes);
// The model's cost of `e` over `scenes` (largest per scene) as (estimated ms, map bytes).
std::pair<double, double> tuneCost(const TuneEvaluation& e, const std::vector<size_t>& scenes);

}  // namespace shadowlab
