// `shadowlab gate`: fails a CI run when shadows got measurably worse than a baseline.
// Exit 0 pass, 1 regression, 2 bad input (InputError, mapped by main). compare/GATE.md documents
// the tolerance file.
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>

#include "command.h"
#include "shadowlab/compare/gate.h"
#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/io.h"

namespace cmd_gate {
namespace {

struct Options {
  std::vector<std::string> currents;
  std::string baseline;
  std::string tolerances;
  std::string jsonOut;
  std::string junitOut;
  bool updateBaseline = false;
  bool brief = false;
  bool techniqueChanged = false;
};

int updateBaseline(const Options& o, const shadowlab::ResultFile& current) {
  using namespace shadowlab;
  ResultFile baseline;
  baseline.path = o.baseline;
  bool existed = std::filesystem::exists(o.baseline);
  // An existing baseline that does not load is an error: overwriting it blindly would hide
  // whatever wrote it wrong.
  if (existed) baseline = loadResultFile(o.baseline);
  if (current.rows.empty())
    throw InputError(formatError(current.path, "/rows", "no rows; expected at least one to make a baseline of"));
  // The rows are about to become the reference: refuse duplicates and NaN as the gate would.
  (void)runGate(current, current, defaultTolerances());
  std::vector<std::string> changes = describeBaselineUpdate(current, baseline);
  // A first baseline may live in a folder that does not exist yet (out/base/metrics.json): made
  // now, after every check, and removed again if the write fails.
  const std::string folder = std::filesystem::path(o.baseline).parent_path().string();
  std::optional<OutputFolder> created;
  if (!folder.empty()) created.emplace(folder, "--baseline");
  writeJsonAtomic(o.baseline, baselineDocument(current));
  if (created) created->keep();
  std::printf("shadowlab gate: %s baseline %s from %s (%zu rows)\n", existed ? "updated" : "created",
              o.baseline.c_str(), current.path.c_str(), current.rows.size());
  for (const std::string& line : changes) std::printf("  %s\n", line.c_str());
  if (changes.empty()) std::printf("  no metric changed (timings may have)\n");
  return 0;
}

int run(const Options& o) {
  using namespace shadowlab;
  // Everything is read and checked before anything is written: a bad input never leaves a
  // half-updated baseline or a report of a gate that did not run.
  Tolerances tolerances = o.tolerances.empty() ? defaultTolerances() : loadTolerances(o.tolerances);
  tolerances.techniqueChanged = o.techniqueChanged;
  std::vector<ResultFile> files;
  for (const std::string& path : o.currents) files.push_back(loadResultFile(path));
  ResultFile current = mergeResultFiles(files);
  if (o.updateBaseline) return updateBaseline(o, current);
  if (!std::filesystem::exists(o.baseline))
    throw InputError(formatError(o.baseline, "",
                                 "baseline file not found; expected a metrics.json, results.json or stability.json "
                                 "(create it on purpose with --update-baseline)"));
  ResultFile baseline = loadResultFile(o.baseline);
  GateResult result = runGate(current, baseline, tolerances);

  if (!o.jsonOut.empty()) writeJsonAtomic(o.jsonOut, gateToJson(result, current, baseline, tolerances));
  if (!o.junitOut.empty()) writeFileAtomic(o.junitOut, gateToJunitXml(result));

  std::fputs(formatGateTable(result, o.brief).c_str(), stdout);
  std::printf("shadowlab gate: %s (baseline %s, current %s, tolerances %s)\n", result.summary().c_str(),
              o.baseline.c_str(), current.path.c_str(), tolerances.origin.c_str());
  std::fflush(stdout);
  for (const GateCheck& c : result.checks)
    if (c.verdict == Verdict::Regressed) std::fprintf(stderr, "shadowlab gate: error: %s\n", c.message.c_str());
  return result.passed() ? 0 : 1;
}

shadowlab::app::Registrar reg{
    "gate", [](CLI::App& app) {
      auto* sub =
          app.add_subcommand("gate", "Compare results against a baseline under tolerances; exit 1 on a regression");
      auto o = std::make_shared<Options>();
      sub->add_option(
             "current", o->currents,
             "Current metrics.json, results.json or stability.json files (several are gated as one set of rows)")
          ->required();
      sub->add_option("--baseline", o->baseline, "Baseline metrics.json, results.json or stability.json")->required();
      sub->add_option("--tolerances", o->tolerances,
                      "Tolerance file (JSON, see compare/GATE.md); default: exact metrics, timings reported");
      sub->add_option("--json", o->jsonOut, "Write the verdicts as JSON here");
      sub->add_option("--junit", o->junitOut, "Write JUnit XML here (one testcase per row x metric)");
      sub->add_flag("--update-baseline", o->updateBaseline,
                    "Rewrite the baseline from the current results (prints what changed) instead of gating");
      sub->add_flag("--brief", o->brief, "Table shows only regressions, improvements and new entries");
      sub->add_flag("--technique-changed", o->techniqueChanged,
                    "Gate rows whose technique file changed since the baseline (another technique.hash) against "
                    "it, instead of refusing them");
      return std::function<int()>([o] { return run(*o); });
    }};

}  // namespace
}  // namespace cmd_gate
