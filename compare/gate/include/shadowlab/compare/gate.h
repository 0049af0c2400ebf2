#pragma once
// The regression gate: compares a current metrics.json / results.json against a baseline, row by
// row (matched by scene, config, light) and metric by metric, under tolerances that are data
// (compare/GATE.md documents the tolerance file with examples).
//
// Exit codes of `shadowlab gate`: 0 every check passed, 1 at least one regression, 2 bad input
// (missing file, malformed tolerance file, a baseline row or metric absent from the current file,
// duplicate rows, NaN). A baseline row absent from the current results is an error, never a pass;
// a row new in the current results is reported and does not fail.
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "shadowlab/compare/results.h"

namespace shadowlab {

// Several current files gated as one (e.g. one sweep per method): rows concatenated, each still
// named by its own file in messages. A row found in several files is a repeated run of one
// configuration: its metrics must be identical in every file (the pipeline is deterministic;
// InputError naming both files otherwise) and its timings become the median over the runs, the
// noise-aware input the timing rule wants. A row twice in one file is an InputError. One file is
// returned unchanged.
ResultFile mergeResultFiles(const std::vector<ResultFile>& files);
// What --update-baseline writes: the rows only (no sweep bookkeeping such as machine or seconds),
// as a metrics.json when `f` is one metrics.json, else as a results.json.
nlohmann::json baselineDocument(const ResultFile& f);

enum class Direction {
  LowerIsBetter,   // error metrics: a rise beyond tolerance fails, a fall is an improvement
  HigherIsBetter,  // shadow_iou and the like: a fall beyond tolerance fails
  Equal,           // any move beyond tolerance fails (e.g. pixels_compared: the scene changed)
  Ignore,          // reported, never fails
};
std::string toString(Direction d);

struct MetricTolerance {
  Direction direction = Direction::Equal;
  double absTolerance = 0;  // in the metric's own unit
  double relTolerance = 0;  // fraction of |baseline|; the allowed move is max(abs, rel * |baseline|)
  double allowed(double baseline) const;
};

enum class TimingMode { Report, Fail };

// Timings are noisy on shared machines: compared as the ratio current / baseline, reported
// by default; with Fail, a ratio above maxRatio fails. Baselines under minMs are only reported
// (a 0.2 ms pass doubling is noise, not a regression).
struct TimingTolerance {
  TimingMode mode = TimingMode::Report;
  double maxRatio = 1.5;
  double minMs = 1.0;
};

// One entry of a tolerance file; what it leaves out is filled in by Tolerances::forMetric.
struct ToleranceSpec {
  std::optional<Direction> direction;
  std::optional<double> absTolerance;
  std::optional<double> relTolerance;
};

struct Tolerances {
  std::string origin = "built-in defaults";      // the file they came from
  std::map<std::string, ToleranceSpec> metrics;  // "metrics": per metric name
  ToleranceSpec fallback;                        // "default"
  TimingTolerance timing;                        // "timing"
  // A row whose technique file (method key technique) changed since the baseline (another
  // technique.hash) is refused unless this is set (gate --technique-changed): then it is gated.
  bool techniqueChanged = false;

  // A listed metric: its entry's fields, direction else builtinDirection(metric), abs/rel else 0.
  // An unlisted metric: the default's fields, direction else builtinDirection(metric).
  MetricTolerance forMetric(const std::string& metric) const;
};

// Built-in direction of the metrics Metrics::toJson writes (error counts and rates, mae, rmse,
// m_*: lower is better; *_iou: higher; pixels_compared: equal). Unknown names: Equal.
Direction builtinDirection(const std::string& metric, bool* known = nullptr);

// Built-in tolerances used without --tolerances: built-in directions, exact up to 1e-9 relative
// (the pipeline is deterministic), timings reported.
Tolerances defaultTolerances();
Tolerances parseTolerances(const nlohmann::json& j, const std::string& file);
Tolerances loadTolerances(const std::string& path);

// Missing rows and metrics are not verdicts: they are bad input (exit 2).
enum class Verdict { Regressed, New, Improved, Pass, Reported };
std::string toString(Verdict v);

struct GateCheck {
  std::string rowKey;  // "scene | config | light"
  std::string scene, config, light;
  std::string metric;       // metric name, or timing name for kind "timing"
  std::string kind;         // "metric" | "timing" | "row"
  nlohmann::json baseline;  // the values as found (number, string, bool)
  nlohmann::json current;
  std::string tolerance;  // printable: "+0.005", "-0.01", "+/-50", "<= 1.50x", "report"
  int samples = 1;        // timings: how many current runs the value is the median of
  Verdict verdict = Verdict::Pass;
  std::string message;  // for regressions: the one-line error (without "shadowlab gate: error: ")
};

struct GateResult {
  std::vector<GateCheck> checks;  // regressions first, then the rest in row/metric order
  int rowsCompared = 0, rowsNew = 0;
  int rowsNotRun = 0;  // one run gated against a sweep: the baseline's rows of other configurations
  int regressions = 0, improvements = 0, passes = 0, reported = 0;
  int newMetrics = 0;  // metrics of matched rows that the baseline lacks (verdict New)
  bool passed() const { return regressions == 0; }
  std::string summary() const;  // one line
};

// Compares every baseline row with its current row. One run (a metrics.json) against a sweep's
// results.json compares its row with the sweep's row of the same name and leaves the sweep's other
// rows out (rowsNotRun); a run that matches no row there is an InputError. InputError (exit 2) for a
// baseline row or metric missing from current (a results file), duplicate rows, NaN (null) values, or a tolerance naming a metric
// no row has (a typo would otherwise never apply).
GateResult runGate(const ResultFile& current, const ResultFile& baseline, const Tolerances& tolerances);

// Outputs; the writers are atomic.
std::string formatGateTable(const GateResult& result, bool brief);
nlohmann::json gateToJson(const GateResult& result, const ResultFile& current, const ResultFile& baseline,
                          const Tolerances& tolerances);
std::string gateToJunitXml(const GateResult& result);

// `--update-baseline`: what would change from `baseline` (may have no rows: a new file) to `current`,
// one line per changed row/metric. Used to print the change before rewriting the baseline.
std::vector<std::string> describeBaselineUpdate(const ResultFile& current, const ResultFile& baseline);

}  // namespace shadowlab
