// `shadowlab sweep [SCENES...] [--grid key=v1,v2]... [--sweep FILE] [--set key=value]... -o DIR`:
// every scene x configuration of the grid, one row each, resumable; ends with results.json,
// results.csv, figures/ and report.html (compare/SWEEPS.md).
#include <algorithm>
#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>

#include "command.h"
#include "shadowlab/compare/sweep.h"
#include "shadowlab/reference/reference.h"
#include "shadowlab/raster/raster.h"
#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/io.h"

namespace cmd_sweep {
namespace {

namespace fs = std::filesystem;
using namespace shadowlab;

struct Options : app::StudyOptions {
  std::vector<std::string> scenes;
  std::vector<std::string> grid;
  std::string sweepFile;
  std::vector<std::string> sets;
  bool keepImages = false;
  bool fullEvidence = false;  // every row renders the full frame (no evidence on demand)
  bool noReport = false;
  std::string shard;  // "I/N": only this shard's rows, into DIR/shards/I-of-N (no report)
  std::string slurm;  // N (text, checked here): write DIR/sweep.sbatch (an N-task array of shards) and DIR/merge.sbatch
  std::vector<std::string> slurmOpts;  // extra #SBATCH options, whitespace-separated, repeatable
  bool submit = false;                 // with --slurm: run sbatch on both scripts
  std::string frontierMetric;          // empty: not given (error_rate)
  std::string frontierThreshold;       // text, checked here so "abc" is a GCC-style InputError, not CLI11's
};

std::atomic<bool> gStop{false};
static_assert(std::atomic<bool>::is_always_lock_free, "the signal handler needs a lock-free flag");

extern "C" void onInterrupt(int) { gStop.store(true); }

// Single-quoted for a POSIX shell.
std::string shellQuote(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

std::string absolutePath(const std::string& p) { return fs::absolute(fs::path(p)).lexically_normal().string(); }

// The sweep's arguments again, for the Slurm script: paths stay as given (the script cd's to this
// folder first); -o and the cache are absolute, so every task and the merge share them.
std::string sweepArguments(const Options& o, const std::string& cacheDir) {
  std::string a;
  auto add = [&](const std::string& flag, const std::string& value) { a += " " + flag + " " + shellQuote(value); };
  for (const auto& s : o.scenes) a += " " + shellQuote(s);
  for (const auto& g : o.grid) add("--grid", g);
  if (!o.sweepFile.empty()) add("--sweep", o.sweepFile);
  for (const auto& s : o.sets) add("--set", s);
  if (!o.methodFile.empty()) add("--method", o.methodFile);
  if (!o.light.empty()) add("--light", o.light);
  if (o.spp) add("--spp", std::to_string(*o.spp));
  if (o.lightSamples) add("--light-samples", std::to_string(*o.lightSamples));
  if (!o.device.empty()) add("--device", o.device);
  if (o.gpuTimeoutS) add("--gpu-timeout-s", std::to_string(*o.gpuTimeoutS));
  if (o.keepImages) a += " --keep-images";
  if (o.fullEvidence) a += " --full-evidence";
  if (!o.frontierMetric.empty()) add("--frontier-metric", o.frontierMetric);
  if (!o.frontierThreshold.empty()) add("--frontier-threshold", o.frontierThreshold);
  add("--cache", absolutePath(cacheDir));
  add("-o", absolutePath(o.outDir));
  return a;
}

// The running binary, so the cluster runs the same build (it must sit on the shared filesystem).
std::string selfPath() {
  std::error_code ec;
  fs::path p = fs::read_symlink("/proc/self/exe", ec);
  return ec ? std::string("shadowlab") : p.string();
}

// Runs `command` through the shell; its stdout (trimmed), or an InputError naming it.
std::string runCapture(const std::string& command) {
  std::FILE* pipe = ::popen(command.c_str(), "r");
  if (!pipe) throw InputError("--submit: error: cannot run " + command);
  std::string out;
  char buf[256];
  while (std::fgets(buf, sizeof buf, pipe)) out += buf;
  const int status = ::pclose(pipe);
  while (!out.empty() && (out.back() == '\n' || out.back() == '\r' || out.back() == ' ')) out.pop_back();
  if (status != 0)
    throw InputError("--submit: error: `" + command + "` failed (status " + std::to_string(status) + ")" +
                     (out.empty() ? "" : ": " + out));
  return out;
}

bool onPath(const std::string& name) {
  const char* path = std::getenv("PATH");
  std::string dirs = path ? path : "";
  size_t pos = 0;
  while (pos <= dirs.size()) {
    size_t colon = dirs.find(':', pos);
    std::string d = dirs.substr(pos, colon == std::string::npos ? std::string::npos : colon - pos);
    if (d.empty()) d = ".";
    if (::access((fs::path(d) / name).c_str(), X_OK) == 0) return true;
    if (colon == std::string::npos) break;
    pos = colon + 1;
  }
  return false;
}

// --slurm N: writes DIR/sweep.sbatch (an array of N tasks, task I running --shard I/N) and
// DIR/merge.sbatch, prints the two sbatch commands (the merge after the whole array succeeded)
// and, with --submit, runs them. The plan was checked already, so the scripts only run valid work.
int writeSlurmJobs(const Options& o, const SweepPlan& plan, size_t n) {
  if (o.submit && !onPath("sbatch"))
    throw InputError(
        "--submit: error: no Slurm installed (sbatch not found on PATH); expected a Slurm client, or "
        "leave out --submit and run the printed commands where Slurm is");
  OutputFolder out(o.outDir);
  const std::string cacheDir = o.cacheDir.empty() ? defaultSweepCacheDir(o.outDir) : o.cacheDir;
  const std::string outAbs = absolutePath(o.outDir);
  const std::string self = selfPath();
  std::vector<std::string> extra;
  for (const auto& opt : o.slurmOpts) {
    std::string word;
    for (char c : opt + " ") {
      if (c == ' ' || c == '\t' || c == '\n') {
        if (!word.empty()) extra.push_back(word);
        word.clear();
      } else {
        word += c;
      }
    }
  }
  std::string sbatchExtra;
  for (const auto& e : extra) sbatchExtra += "#SBATCH " + e + "\n";
  const std::string cd = "cd " + shellQuote(fs::current_path().string()) + "\n";
  std::string sweep =
      "#!/bin/bash\n"
      "# Written by `shadowlab sweep --slurm " +
      std::to_string(n) + "`: task I of the array runs shard I/" + std::to_string(n) + " of a " +
      std::to_string(plan.jobs.size()) + "-row sweep into " + outAbs + "/shards/I-of-" + std::to_string(n) +
      "/.\n"
      "# The output folder, the reference cache and the binary must be on a filesystem every node sees.\n"
      "#SBATCH --job-name=shadowlab-sweep\n"
      "#SBATCH --array=0-" +
      std::to_string(n - 1) +
      "\n"
      "#SBATCH --output=" +
      outAbs + "/shards/slurm-%A_%a.out\n" + sbatchExtra + "set -euo pipefail\n" + cd + "exec " + shellQuote(self) +
      " sweep" + sweepArguments(o, cacheDir) + " --shard \"$SLURM_ARRAY_TASK_ID/" + std::to_string(n) + "\"\n";
  std::string merge =
      "#!/bin/bash\n"
      "# Written by `shadowlab sweep --slurm " +
      std::to_string(n) + "`: gathers the " + std::to_string(n) +
      " shards into results.json, results.csv and the report; submit it with\n"
      "# --dependency=afterok:<the array's job id>.\n"
      "#SBATCH --job-name=shadowlab-merge\n"
      "#SBATCH --output=" +
      outAbs + "/merge-slurm-%j.out\n" + sbatchExtra + "set -euo pipefail\n" + cd + "exec " + shellQuote(self) +
      " merge " + shellQuote(outAbs) + " --cache " + shellQuote(absolutePath(cacheDir)) +
      (o.device.empty() ? "" : " --device " + shellQuote(o.device)) + (o.noReport ? " --no-report" : "") + "\n";
  makeDirs(outAbs + "/shards");  // sbatch opens the --output files there before the task starts
  const std::string sweepPath = outAbs + "/sweep.sbatch", mergePath = outAbs + "/merge.sbatch";
  writeFileAtomic(sweepPath, sweep);
  writeFileAtomic(mergePath, merge);
  fs::permissions(sweepPath, fs::perms::owner_exec | fs::perms::group_exec | fs::perms::others_exec,
                  fs::perm_options::add);
  fs::permissions(mergePath, fs::perms::owner_exec | fs::perms::group_exec | fs::perms::others_exec,
                  fs::perm_options::add);
  out.keep();
  std::printf("slurm: wrote %s (%zu tasks, %zu rows) and %s\n", sweepPath.c_str(), n, plan.jobs.size(),
              mergePath.c_str());
  const std::string first = "sbatch --parsable " + shellQuote(sweepPath);
  if (!o.submit) {
    std::printf("slurm: submit with:\n  jobid=$(%s)\n  sbatch --dependency=afterok:$jobid %s\n", first.c_str(),
                shellQuote(mergePath).c_str());
    return 0;
  }
  std::string jobid = runCapture(first);
  jobid = jobid.substr(0, jobid.find(';'));  // --parsable prints "jobid[;cluster]"
  if (jobid.empty() || jobid.find_first_not_of("0123456789") != std::string::npos)
    throw InputError("--submit: error: `" + first + "` printed \"" + jobid + "\"; expected a job id");
  const std::string second = "sbatch --parsable --dependency=afterok:" + jobid + " " + shellQuote(mergePath);
  const std::string mergeId = runCapture(second);
  std::printf("slurm: submitted the sweep array as job %s and the merge as job %s (after it succeeds)\n", jobid.c_str(),
              mergeId.c_str());
  return 0;
}

int run(const Options& o) {
  // ---- inputs: every error surfaces here, before the output folder exists --------------------
  SweepShard shard;
  if (!o.shard.empty()) shard = parseShardArgument(o.shard);
  size_t slurm = 0;
  if (!o.slurm.empty() || !o.slurmOpts.empty() || o.submit) {
    if (o.slurm.empty()) throw InputError("--slurm: error: missing; --slurm-opt and --submit need --slurm N");
    const bool digits = o.slurm.size() <= 6 && o.slurm.find_first_not_of("0123456789") == std::string::npos;
    slurm = digits ? size_t(std::stoul(o.slurm)) : 0;
    if (slurm < 1)
      throw InputError("--slurm " + o.slurm + ": error: got \"" + o.slurm +
                       "\"; expected a number of shards 1..999999");
    if (shard.active())
      throw InputError("--slurm: error: given with --shard; expected one of them (the script adds --shard)");
  }
  SweepSpec spec;
  if (!o.sweepFile.empty()) loadSweepFile(o.sweepFile, spec);
  if (!o.scenes.empty()) spec.scenes = o.scenes;  // the command line names replace the file's
  std::map<std::string, std::string> given;       // key -> the --grid or --set that gave it
  auto once = [&](const std::string& key, const std::string& origin, const char* verb) {
    const auto [first, fresh] = given.emplace(key, origin);
    if (!fresh)
      throw InputError(formatError(
          origin, "",
          "\"" + key + "\" is " + verb + " again (first by " + first->second + "); expected each key once"));
  };
  for (const auto& g : o.grid) {
    // A --grid axis replaces the file's axes of that key, in every grid of a union, and is swept
    // in every one of them; the same key in two --grid is refused (one would be lost).
    SweepAxis axis = parseGridArgument(g);
    once(axis.key, axis.origin, "swept");
    auto first =
        std::find_if(spec.grid.begin(), spec.grid.end(), [&](const SweepAxis& a) { return a.key == axis.key; });
    if (first == spec.grid.end()) {
      spec.grid.push_back(std::move(axis));
    } else {
      *first = std::move(axis);
      const std::string key = first->key;
      spec.grid.erase(std::remove_if(first + 1, spec.grid.end(), [&](const SweepAxis& a) { return a.key == key; }),
                      spec.grid.end());
    }
  }
  given.clear();
  for (const auto& s : o.sets) {
    SweepSetting setting = parseSetArgument(s);
    once(setting.key, setting.origin, "set");
    bool replaced = false;
    for (auto& existing : spec.fixed)
      if (existing.key == setting.key) {
        existing = setting;
        replaced = true;
      }
    if (!replaced) spec.fixed.push_back(std::move(setting));
  }
  if (!o.methodFile.empty()) spec.methodFile = o.methodFile;
  if (!o.light.empty()) spec.light = o.light;
  if (o.spp) {
    checkSpp(*o.spp, "--spp");
    spec.spp = *o.spp;
  }
  if (o.lightSamples) {
    checkLightSamples(*o.lightSamples, "--light-samples");
    spec.lightSamples = *o.lightSamples;
  }
  if (o.gpuTimeoutS) {
    checkGpuTimeout(*o.gpuTimeoutS, "--gpu-timeout-s");
    spec.gpuTimeoutS = *o.gpuTimeoutS;
  }
  if (o.keepImages) spec.keepImages = true;
  if (!o.frontierMetric.empty()) spec.frontierMetric = o.frontierMetric;
  if (!o.frontierThreshold.empty()) {
    char* end = nullptr;
    double t = std::strtod(o.frontierThreshold.c_str(), &end);
    if (!end || *end != '\0' || !std::isfinite(t) || t < 0)
      throw InputError("--frontier-threshold: error: got \"" + o.frontierThreshold +
                       "\"; expected a number >= 0 (a rate, e.g. 0.01)");
    spec.frontierThreshold = t;
  }
  const SweepPlan plan = planSweep(spec);
  if (slurm > 0) return writeSlurmJobs(o, plan, slurm);
  // Every output location, before any work.
  OutputFolder out(o.outDir);
  const std::string cacheDir = o.cacheDir.empty() ? defaultSweepCacheDir(o.outDir) : o.cacheDir;
  OutputFolder cacheFolder(cacheDir, o.cacheDir.empty() ? "-o (its reference cache)" : "--cache");
  cacheFolder.keep();  // a cache outlives the command

  // ---- work ------------------------------------------------------------------------------------
  // A shard writes no report, and neither does --no-report: nothing would draw the kept rows.
  auto runner = makePipelineRunner(cacheDir, spec.spp, o.device, 1, o.fullEvidence, !o.noReport && !shard.active(),
                                   spec.lightSamples, spec.gpuTimeoutS);
  SweepOptions options;
  options.outDir = o.outDir;
  options.progress = stderr;
  options.progressBar = ::isatty(STDERR_FILENO) == 1 && !app::verbose();  // -v: a line per row
  options.stop = &gStop;
  options.writeReport = !o.noReport;
  if (o.timingRepetitions) options.timingRepetitions = *o.timingRepetitions;
  options.shard = shard;
  // $SHADOWLAB_HOME (an unpacked bundle, like scenes/data) holds compare/report/charts.py too.
  const char* home = std::getenv("SHADOWLAB_HOME");
  options.reportScript = defaultReportScript(home && *home ? home : SHADOWLAB_SOURCE_DIR);
  std::fprintf(stderr, "sweep: %zu scene(s) x %zu configuration(s) = %zu rows into %s (reference cache %s)\n",
               plan.sceneNames.size(), plan.configs.size(), plan.jobs.size(), o.outDir.c_str(), cacheDir.c_str());
  if (shard.active())
    std::fprintf(stderr, "sweep: shard %zu/%zu: every %zu-th row from row %zu, into %s\n", shard.index, shard.count,
                 shard.count, shard.index, shardDir(o.outDir, shard).c_str());
  app::installStopHandlers(onInterrupt);
  const SweepSummary summary = runSweep(plan, *runner, options);
  out.keep();  // rows, log and lock live there: a later run continues from them
  if (summary.interrupted) {
    std::fprintf(stderr,
                 "sweep: interrupted: %zu of %zu rows are saved in %s/rows.jsonl; run the same command again to "
                 "continue\n",
                 summary.resumed + summary.ran, summary.configurations,
                 (shard.active() ? shardDir(o.outDir, shard) : o.outDir).c_str());
    return 130;
  }
  for (const auto& n : summary.notes) std::fprintf(stderr, "sweep: note: %s\n", n.c_str());
  if (gStop.load()) {
    // Every row is saved; only the report may be incomplete (its chart script saw the Ctrl-C too).
    std::fprintf(stderr,
                 "sweep: interrupted while writing the report; every row is saved, run the same command "
                 "again to regenerate it\n");
    return 130;
  }
  std::printf("sweep: %zu rows (%zu run, %zu resumed) in %.2f s\n", summary.configurations, summary.ran,
              summary.resumed, summary.commandWallSeconds);
  if (shard.active()) {
    std::printf("sweep: shard %zu/%zu done in %s; when every shard is done: shadowlab merge %s\n", shard.index,
                shard.count, shardDir(o.outDir, shard).c_str(), o.outDir.c_str());
    return 0;
  }
  std::printf("sweep: wrote %s and %s\n", summary.resultsJson.c_str(), summary.resultsCsv.c_str());
  if (!summary.reportHtml.empty()) std::printf("report: %s\n", fs::absolute(summary.reportHtml).c_str());
  return 0;
}

app::Registrar reg{
    "sweep", [](CLI::App& app) {
      auto opts = std::make_shared<Options>();
      auto* sub =
          app.add_subcommand("sweep", "Sweep scenes x a grid of method settings into a report (compare/SWEEPS.md)");
      sub->add_option("SCENES", opts->scenes, "Bundled scene names or scene files (default: every bundled scene)");
      sub->add_option("--grid", opts->grid,
                      "Swept key and its values, repeatable: key=v1,v2,... (method keys, or scene:/json/pointer)")
          ->allow_extra_args(false);
      sub->add_option("--sweep", opts->sweepFile,
                      "Sweep file (JSON: scenes, grid, set, ...); the command line adds to it");
      sub->add_option("--set", opts->sets, "Method setting for every configuration key=value, repeatable")
          ->allow_extra_args(false);
      app::addStudyOptions(sub, *opts, "sweep");
      sub->add_flag("--keep-images", opts->keepImages,
                    "Write raster.exr and errors.png per configuration under DIR/images/");
      sub->add_flag("--full-evidence", opts->fullEvidence,
                    "Render every configuration's full frame (every evidence channel at every pixel) instead of "
                    "resolving the evidence only where the decisions disagree; the metrics are the same");
      sub->add_option("--frontier-metric", opts->frontierMetric,
                      "Metric walked along swept scene: parameters for failure frontiers (default error_rate)");
      sub->add_option("--frontier-threshold", opts->frontierThreshold,
                      "Rate above which a configuration counts as broken (default 0.01)");
      sub->add_flag("--no-report", opts->noReport, "Write results.json/csv only: no charts, triptychs or report.html");
      sub->add_option("--shard", opts->shard,
                      "I/N: run only the rows whose plan index is I mod N, into DIR/shards/I-of-N (no report; "
                      "`shadowlab merge DIR` gathers the shards)");
      sub->add_option("--slurm", opts->slurm,
                      "N: write DIR/sweep.sbatch (a Slurm array of N shards) and DIR/merge.sbatch, print the sbatch "
                      "commands; runs nothing");
      sub->add_option("--slurm-opt", opts->slurmOpts,
                      "Extra #SBATCH options for both scripts, e.g. \"--partition=gpu --time=2:00:00\"")
          ->allow_extra_args(false);
      sub->add_flag("--submit", opts->submit,
                    "With --slurm: submit both scripts with sbatch (the merge after the array)");
      return std::function<int()>([opts] { return run(*opts); });
    }};

}  // namespace
}  // namespace cmd_sweep
