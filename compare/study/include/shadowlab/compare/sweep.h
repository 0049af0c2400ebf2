#pragma once
// Sweeps: every scene x configuration of a grid of method (and scene) values, one ResultRow each,
// resumable after an interruption, ending in results.csv / results.json / figures/ / report.html.
// The command line and the sweep file format are documented in compare/SWEEPS.md.
//
// The work is split so that every input error surfaces before anything is written:
//   SweepSpec  (what the user asked: scenes, grid axes, fixed settings)
//     -> planSweep()  validates every key and value, loads every scene, expands the grid (no I/O
//                     besides reading inputs)
//     -> runSweep()   creates the output folder, runs the missing rows through a SweepRunner and
//                     regenerates the outputs.
// The runner is injectable: production uses makePipelineRunner() (reference cache + one Rasterizer
// + compareFrames, exactly what runPipeline does); tests inject a fake to exercise resume,
// interruption and grid logic without renderers.
#include <algorithm>
#include <atomic>
#include <cstdio>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "shadowlab/compare/config_name.h"
#include "shadowlab/compare/results.h"
#include "shadowlab/scenes/loader.h"
#include "shadowlab/scenes/method.h"
#include "shadowlab/scenes/scene.h"

namespace shadowlab {

// Swept keys are method keys (methodKeys(), e.g. "map.size") or scene values written
// "scene:" + a JSON pointer into the scene file (e.g. "scene:/lights/0/elevation_deg").
inline constexpr const char* kSceneKeyPrefix = "scene:";
// "scene:failure": the value each scene's declared failure pointer names (scenes/FORMAT.md,
// "failure"), resolved per scene by planSweep (a scene without "failure" is an InputError).
inline constexpr const char* kSceneFailureKey = "scene:failure";

struct SweepAxis {
  std::string key;
  std::vector<nlohmann::json> values;     // text from the command line, typed values from a sweep file
  std::string origin;                     // where it came from, for messages: "--grid map.size=..."
  std::vector<std::string> valueOrigins;  // one per value ("sweep.json: /grid/map.size/2")
  // Which block of a union of grids the axis belongs to: a sweep file's "grid" may be an array of
  // grid objects, each expanded as a product on its own and the configurations joined (a key
  // swept in another block takes the base method's value here). -1: every block (--grid axes,
  // and the axes of a single grid object).
  int block = -1;
};

struct SweepSetting {
  std::string key;
  nlohmann::json value;
  std::string origin;
};

struct SweepSpec {
  std::vector<std::string> scenes;  // bundled names or paths; empty = every bundled scene
  // A scene a sweep file names -> "sweep.json: /scenes/1", so that a missing one names its place.
  std::map<std::string, std::string> sceneOrigins;
  std::vector<SweepAxis> grid;      // in the order given; the last axis varies fastest (per block)
  // A union of grids' block -> the scenes its configurations run on (names or paths, as `scenes`;
  // a block not listed runs on every scene). A scene: key swept only in such blocks need not be
  // swept in the others: each scene runs the configurations whose values it can take.
  std::map<int, std::vector<std::string>> blockScenes;
  std::map<int, std::string> blockScenesOrigin;  // "sweep.json: /grid/3/scenes", for messages
  std::vector<SweepSetting> fixed;  // --set / "set": applied to every configuration, before the grid
  std::string methodFile;           // optional base method file (--method / "method")
  std::string light;                // empty: each scene's first light
  int spp = 1;                      // reference samples per pixel
  int lightSamples = 64;            // reference samples of a sized light per pixel sample (kDefaultLightSamples)
  bool keepImages = false;          // write raster.exr + errors.png per configuration
  double gpuTimeoutS = 0;           // seconds a GPU pass may take (0: $SHADOWLAB_GPU_TIMEOUT_S, else 120)
  // Failure frontiers (sweep_frontier.h): the metric walked along swept scene: parameters and the
  // rate above which a configuration counts as broken. Checked by planSweep.
  std::string frontierMetric = "error_rate";
  double frontierThreshold = 0.01;
};

// "map.size=256,512" (from --grid; a comma inside [...], {...} or "..." does not split, so
// scene:/camera/look_at=[4,10,6],[0,0,0] has two values). InputError when there is no '=', no key
// or an empty list; the key and the values are validated by planSweep.
SweepAxis parseGridArgument(const std::string& text);
// "filter=pcf" (from --set).
SweepSetting parseSetArgument(const std::string& text);
// Reads a sweep file (JSON, comments allowed) into `spec`; what the command line gives is added
// afterwards by the caller (grid axes given again on the command line replace the file's).
// InputError naming the file and line:col (syntax) or JSON pointer (shape, keys, values).
void loadSweepFile(const std::string& path, SweepSpec& spec);

// A scene value from the command line (--set scene:/pointer=TEXT): the JSON value when TEXT parses
// as one (30 -> number, true -> bool, [4,10,6] -> array), else TEXT as a string. Typed values
// pass unchanged. (canonicalValueText, a value's text in a configuration's name: config_name.h.)
nlohmann::json sceneValueFromText(const nlohmann::json& value);

struct SweepConfig {
  // configName(method, sceneOverrides) (config_name.h): the row's `config`, also the resume key.
  std::string config;
  std::vector<std::pair<std::string, std::string>> values;  // swept key -> canonical value, sorted
  Method method;                                            // base + fixed + this point of the grid
  // The scene: keys of this point; scene:failure has the pointer "failure" here, replaced by each
  // scene's own failure pointer when the scene is loaded.
  std::vector<SceneOverride> sceneOverrides;
  // The scenes it runs on (resolved paths) when every block that produced it names its scenes
  // (SweepSpec::blockScenes); empty: every scene of the sweep.
  std::vector<std::string> onlyScenes;
  bool runsOn(const std::string& scenePath) const {
    return onlyScenes.empty() || std::find(onlyScenes.begin(), onlyScenes.end(), scenePath) != onlyScenes.end();
  }
};

struct SweepJob {
  size_t sceneIndex = 0;    // into SweepPlan::scenePaths
  size_t configIndex = 0;   // into SweepPlan::configs
  size_t variantIndex = 0;  // into SweepPlan::variants: the scene as loaded for this point
  std::string light;        // resolved light name
  std::string key() const;  // ResultRow::key() of its row
  std::string sceneName;
  std::string config;
};

struct SweepPlan {
  SweepSpec spec;
  std::vector<std::string> scenePaths;  // resolved, one per requested scene
  std::vector<std::string> sceneNames;
  std::vector<SweepConfig> configs;  // the expanded grid (every scene runs those whose runsOn() holds)
  std::vector<Scene> variants;       // each scene under each distinct set of scene: values
  std::vector<SweepJob> jobs;        // scene-major, then configuration in grid order
};

// Validates everything (keys, every value of every axis, cross-field rules of every configuration,
// scenes, lights) and expands the grid. Reads the inputs; writes nothing.
SweepPlan planSweep(const SweepSpec& spec);

// The swept keys of a plan, one axis each, in the order they were first given, with the distinct
// canonical value texts of its configurations in first-seen order (strings). For a single grid
// the axes as given; for a union of grids a key swept in one block only also lists the base
// value the other blocks' configurations carry.
std::vector<SweepAxis> sweptAxes(const SweepPlan& plan);

// What one configuration produced (the renderer-independent part of a ResultRow).
// One timed run of a configuration's method passes, GPU milliseconds (compare/TIMINGS.md).
struct MethodSample {
  double shadowGpuMs = 0, lookupGpuMs = 0, momentsGpuMs = 0;
  double sdsmGpuMs = 0;  // fit=sdsm: the kept samples' pass, the same in every run
  double methodGpuMs() const { return shadowGpuMs + lookupGpuMs + sdsmGpuMs; }
};

struct SweepRunOutput {
  nlohmann::json metrics = nlohmann::json::object();  // Metrics::toJson()
  nlohmann::json timings =
      nlohmann::json::object();  // shadow_gpu_ms, camera_gpu_ms, readback_ms, render_wall_ms, compare_ms
};

class SweepRunner {
 public:
  virtual ~SweepRunner() = default;
  // Runs one configuration. `imagesDir` non-empty: also write raster.exr and errors.png there.
  virtual SweepRunOutput run(const Scene& scene, const Method& method, const std::string& light,
                             const std::string& imagesDir) = 0;
  // Renders one configuration again and writes reference | raster | errors to `pngPath`.
  // Returns false when this runner cannot make pictures.
  virtual bool writeTriptych(const Scene& scene, const Method& method, const std::string& light,
                             const std::string& pngPath) = 0;
  // Device-dependent checks of one configuration before anything is written (e.g. a map larger
  // than the device allows); throws InputError prefixed by `origin`.
  virtual void checkMethod(const Method& method, const std::string& origin) {
    (void)method;
    (void)origin;
  }
  // Times one configuration's method again (compare/TIMINGS.md, "Timed repetitions"): `runs`
  // more runs of its method's passes, each submitted and timed on its own, after the row's own
  // render (the loop's). Empty where this runner cannot time a method (a fake runner).
  virtual std::vector<MethodSample> timeAgain(const Scene& scene, const Method& method, const std::string& light,
                                              int runs) {
    (void)scene, (void)method, (void)light, (void)runs;
    return {};
  }
  // An outside renderer's configurations of one scene and light (each with a renderer=;
  // adapters/README.md), before the first of them runs: one batch per adapter, each with its
  // request, frames and log under `workDir`; run() then scores each from the batch. Without it
  // run() renders an adapter's configuration as a batch of one. Default: nothing.
  virtual void prefetch(const Scene& scene, const std::vector<std::pair<std::string, Method>>& configs,
                        const std::string& light, const std::string& workDir) {
    (void)scene, (void)configs, (void)light, (void)workDir;
  }
  // Device and cache facts for results.json ("device", "reference_cache", ...).
  virtual nlohmann::json info() const { return nlohmann::json::object(); }
  // The device whose clock the timings come from ("" when there is none, e.g. a fake runner).
  // Every row records it (rows.jsonl and results.json "device"), and runSweep refuses to resume
  // rows measured on another device: one time axis never holds two devices.
  virtual std::string deviceName() { return ""; }
};

// Production runner: references from a ReferenceCache in `cacheDir` (traced once per scene and
// camera, kept in memory for the sweep), one Rasterizer (created on first use, on the Vulkan device
// whose name contains `device`; empty = lavapipe), compareFrames. `keepReferences`: how many scenes'
// reference frames stay in memory (a sweep visits scenes one after another and needs 1; shadowlab
// tune evaluates each configuration on every scene in turn and keeps one per scene).
// Rows that keep no pictures render with evidence on demand (raster.h, `disagreementSelector`):
// the same metrics, the evidence resolved only where the decisions disagree; `fullEvidence`
// (--full-evidence) renders every row's full frame instead. `keepTriptychs`: keep each scene's best
// and worst row so far (a few planes and the classification) for writeTriptych, which then draws
// them without rendering again; off where no report will ask (--no-report).
// `lightSamples`: the reference's ReferenceOptions::lightSamples (sized lights only).
std::unique_ptr<SweepRunner> makePipelineRunner(const std::string& cacheDir, int spp, const std::string& device = "",
                                                size_t keepReferences = 1, bool fullEvidence = false,
                                                bool keepTriptychs = true, int lightSamples = 64,
                                                double gpuTimeoutS = 0);

// The cache folder a sweep into `outDir` uses when none is given: $SHADOWLAB_CACHE, else
// <parent of outDir>/.shadowlab-cache, so sweeps side by side share their references.
std::string defaultSweepCacheDir(const std::string& outDir);

// One of N machines' share of a plan (--shard I/N): the jobs whose index in SweepPlan::jobs is
// congruent to I mod N. Round-robin rather than contiguous blocks because jobs are scene-major
// and the grid's last axis varies fastest: a block would give one shard all of a slow scene or
// all of the largest map sizes, whereas every N-th job spreads scenes and expensive values evenly.
struct SweepShard {
  size_t index = 0;  // I, 0-based
  size_t count = 0;  // N; 0 = not sharded
  bool active() const { return count > 0; }
  bool owns(size_t jobIndex) const { return !active() || jobIndex % count == index; }
};

// "2/3" (from --shard). InputError "--shard TEXT: error: ..." unless it is I/N with 0 <= I < N.
SweepShard parseShardArgument(const std::string& text);
// OUT/shards/I-of-N: a shard's own folder (journal, log, lock, shard.json).
std::string shardDir(const std::string& outDir, const SweepShard& shard);
// A 16-hex-digit hash of what decides the plan's rows: every job's key, its scene content hash and
// resolved method (so the --set values, the grid and the method file content are all in it), the
// method file's bytes, spp, light and the frontier settings. Shards of one sweep share it; the
// merge refuses shards whose fingerprints differ.
std::string planFingerprint(const SweepPlan& plan);
// The spec as JSON (scene paths absolute, so another machine or folder can plan it again) and
// back; shard.json holds it so that `shadowlab merge OUT` needs no sweep arguments.
nlohmann::json sweepSpecToJson(const SweepPlan& plan);
SweepSpec sweepSpecFromJson(const nlohmann::json& j, const std::string& origin);
// The spec recorded by the shards under outDir (the first shard folder's shard.json).
// InputError when outDir/shards holds no shard.
SweepSpec loadShardedSpec(const std::string& outDir);

// Timing where it decides something (compare/TIMINGS.md, "Timed repetitions"). Every row is timed
// once, by its render after the warm-up; the rows whose time can change a conclusion are timed
// again, `repetitions` runs of the method's passes, and carry their median and range:
//   - rows within the noise band of their scene's Pareto front of error_rate against
//     method_gpu_ms: every row that no other row of the scene beats at an equal or lower error,
//     where beating means being faster by more than kTimingNoiseFactor, or having the same cost by
//     the model (method_cost.h) and not being slower by more than the factor (configurations of one
//     cost, such as a bias axis, differ in time by noise alone, which a median would not settle).
//     The report's front, its findings' best, cheapest and best-within-a-budget rows all are such
//     rows, and runSweep times again any row that is on a front once the others are timed;
//   - rows a caller names (shadowlab tune: the configurations its verdict quotes).
// A single sample on lavapipe moves by up to about 20 % on a shared machine: two rows whose
// single samples differ by less than this factor may swap places when timed again.
inline constexpr double kTimingNoiseFactor = 1.5;
inline constexpr int kDefaultTimingRepetitions = 3;  // odd, so the median is a run
// `timings` (a row's) with its method's time the median of its own sample and `more` runs:
// shadow_gpu_ms, lookup_gpu_ms, moments_gpu_ms and method_gpu_ms of the median run (the parts sum
// up), method_gpu_ms_min and _max the range. With no more runs, `timings` unchanged.
nlohmann::json withMedianTiming(const nlohmann::json& timings, const std::vector<MethodSample>& more);
// The jobs of `plan` whose row's time decides something (rowsWhoseTimeDecides below, with each
// job's modelled cost); `rows` holds one row per job, null for a job without one.
std::vector<size_t> jobsWhoseTimeDecides(const SweepPlan& plan, const std::vector<const ResultRow*>& rows);
// The indices of `rows` (one sweep's rows, any order) whose time decides a Pareto front, as above,
// ascending. `modelMs`: each row's estimated cost (MethodCost::estimatedMs), NaN or absent where
// unknown (then only the measured times decide). Rows that compared nothing or have no finite
// error_rate are never among them.
std::vector<size_t> rowsWhoseTimeDecides(const std::vector<const ResultRow*>& rows,
                                         const std::vector<double>& modelMs = {},
                                         double noiseFactor = kTimingNoiseFactor);

struct SweepOptions {
  std::string outDir;
  // Timed runs of the rows whose time decides something (above), the row's own render one of
  // them (so 3 is 2 more); 0 or 1: every row keeps its render's own single sample. Shards time
  // none again (their rows keep single samples).
  int timingRepetitions = kDefaultTimingRepetitions;
  // With writeResults: time again the rows on or near each scene's Pareto front. Off: only the
  // rows of retimeKeys (shadowlab tune, which calls runSweep a few rows at a time).
  bool retimeFront = true;
  std::vector<std::string> retimeKeys;  // ResultRow::key() of rows to time again as well
  // Active: run only this shard's jobs into shardDir(outDir, shard) and write no results or
  // report (mergeSweepShards does).
  SweepShard shard;
  // Progress: a bar with rate and ETA when `progressBar`, plain lines otherwise; null: silent.
  std::FILE* progress = stderr;
  bool progressBar = false;
  // Set (e.g. by a SIGINT handler) to stop after the configuration in progress.
  const std::atomic<bool>* stop = nullptr;
  // false: only run and journal the rows (shadowlab tune evaluates a few rows at a time and writes
  // results.json, results.csv and the report once, at its end): no results files, no report.
  bool writeResults = true;
  bool writeReport = true;   // charts + report.html (results.csv/json are always written when writeResults)
  bool triptychs = true;     // render the best and worst configuration of each scene again
  std::string reportScript;  // chart script; empty: no charts (a note in the report). See defaultReportScript.
  std::string python;        // empty: $SHADOWLAB_PYTHON, else /usr/bin/python3
};

struct SweepSummary {
  size_t configurations = 0;                        // rows planned
  size_t resumed = 0;                               // rows found in rows.jsonl and not run again
  size_t ran = 0;                                   // rows run by this call
  bool interrupted = false;                         // stopped by options.stop; outputs not regenerated
  double commandWallSeconds = 0;                    // command_wall_seconds: this runSweep call, report included
  std::string resultsJson, resultsCsv, reportHtml;  // empty when not written
  std::vector<std::string> notes;                   // e.g. charts skipped or failed
  size_t retimed = 0;                               // rows timed again by this call (SweepOptions::timingRepetitions)
  std::map<std::string, nlohmann::json> retimedTimings;  // their key -> the row's timings after it
  // With SweepOptions::writeResults off (and no shard): each job's row, run or resumed, in plan
  // order; a job left unrun by an interruption has an empty `scene`.
  std::vector<ResultRow> rows;
};

// Checks every configuration with runner.checkMethod, then runs the plan into options.outDir
// (created), appending each finished row to outDir/rows.jsonl (one write per row before the next
// starts; fdatasync'd by a thread of its own, every row synced before the results are written);
// rows already there for the same scene content and method are not run again; a torn last line
// is dropped. A row to resume that was measured on another device
// than runner.deviceName() is an InputError naming both devices (nothing is run or rewritten). At the end writes
// results.json, results.csv, figures/ and report.html. Log of starts/finishes: outDir/sweep.log.
SweepSummary runSweep(const SweepPlan& plan, SweepRunner& runner, const SweepOptions& options);

// One line of a sweep journal (DIR/rows.jsonl), as runSweep stores it.
struct SweepJournalRow {
  ResultRow row;
  std::string sceneHash;  // the scene's content hash when the row was run
  double configWallSeconds = 0;
  std::string device;  // SweepRunner::deviceName() that measured its timings
};
// The rows of a journal by ResultRow::key() (a later line for the same key wins); none when the
// file does not exist. A torn last line is ignored (not truncated); a damaged earlier line is an
// InputError naming the file and line. runSweep resumes a row only for the same scene hash,
// resolved method and device; a caller that reuses rows must check the same.
std::map<std::string, SweepJournalRow> readSweepJournal(const std::string& path);

// Gathers every shard journal under options.outDir/shards into options.outDir/results.json,
// results.csv and the report, exactly as an unsharded runSweep of `plan` would. InputError (nothing
// written) naming the files when shards come from different plans (fingerprint or N differ), a
// shard is missing (the missing I listed), a shard holds fewer rows than its share, a row does not
// belong to the plan, a configuration appears twice with different metrics, or the rows were
// measured on different devices.
SweepSummary mergeSweepShards(const SweepPlan& plan, SweepRunner& runner, const SweepOptions& options);

// The chart script's Python, started before the configuration loop (prestartCharts): the
// interpreter starts, imports matplotlib and draws one throw-away figure (fonts, mathtext parser:
// ~0.6 s of CPU) while the sweep starts its device and runs rows, then waits on its stdin. The
// report hands it the chart script's command line, and it runs the script exactly as
// `python SCRIPT RESULTS_JSON FIGURES_DIR` would (same files, same exit status, output into
// figures/charts.log). Destroyed unused (an error, an interruption, no report), it is ended
// (SIGTERM) and reaped, having written nothing.
class PrestartedCharts {
 public:
  PrestartedCharts(int pid, int goFd) : pid_(pid), goFd_(goFd) {}
  ~PrestartedCharts();
  PrestartedCharts(const PrestartedCharts&) = delete;
  PrestartedCharts& operator=(const PrestartedCharts&) = delete;
  // Hands over `argv` (the interpreter's arguments: script, results.json, figures folder) with its
  // output into `logPath`; the pid to wait for, or -1 when the Python is gone (the caller then
  // starts the script afresh). Once only.
  int run(const std::vector<std::string>& argv, const std::string& logPath);

 private:
  int pid_ = -1;
  int goFd_ = -1;
};
// The Python of options.python ($SHADOWLAB_PYTHON, /usr/bin/python3) waiting as above; null when
// no report would be written (options.writeReport or options.writeResults off, a shard), no chart
// script is configured or found, or it cannot be started (the report then starts the script as before).
std::unique_ptr<PrestartedCharts> prestartCharts(const SweepOptions& options);

// Where a report's wall time went: results.json's report_charts_wall_seconds and
// report_triptychs_wall_seconds (compare/TIMINGS.md). The two overlap.
struct SweepReportTimings {
  std::optional<double>
      chartsWallSeconds;  // the chart script, handed its arguments to exited; none when it did not start
  std::optional<double> triptychsWallSeconds;  // rendering and writing the triptychs; none without triptychs
};

// The report of a finished sweep whose results.json is written: runs the chart script into
// outDir/figures (PNG, PDF, SVG and figures/charts.json), renders the best and worst configuration
// of each scene again for triptychs (figures/triptych_*.png) while the script runs, and writes
// outDir/report.html. Returns notes (charts skipped, script failures, triptychs that failed) that
// the report also shows. `charts`: a Python started earlier by prestartCharts to run the chart
// script in (null: started here). `timings` (optional) receives the two parts' wall times.
std::vector<std::string> writeSweepReport(const SweepPlan& plan, const std::vector<ResultRow>& rows,
                                          const nlohmann::json& results, SweepRunner& runner,
                                          const SweepOptions& options, PrestartedCharts* charts = nullptr,
                                          SweepReportTimings* timings = nullptr);

// Pieces of the report, usable on their own.
void writeResultsCsv(const std::string& path, const std::vector<ResultRow>& rows);
// Per scene: configurations on the Pareto front of (the method's time = method_gpu_ms, i.e.
// shadow_gpu_ms + lookup_gpu_ms, compare/TIMINGS.md; error_rate), by increasing time: each is the
// lowest error reachable within its time budget. The harness's stages (camera_gpu_ms, readback,
// compare) do not count. A row without method_gpu_ms: shadow_gpu_ms + lookup_gpu_ms (absent: 0).
std::vector<size_t> paretoFront(const std::vector<ResultRow>& rows, const std::string& scene);
// A row's method time, the report's and tune's time axis: method_gpu_ms, else (a row journaled
// before the lookup pass existed) shadow_gpu_ms + lookup_gpu_ms, an absent term counting 0.
double methodMs(const ResultRow& r);
// A row's method family, the unit every chart of the report draws in one colour and marker: the
// technique when the method names one ("technique <name>"), else "<filter> / <fit>" (filter x fit;
// a filter with a sized light is a filter of its own). From the row's method JSON (ResultRow::method).
std::string methodFamily(const nlohmann::json& method);
// The families of `rows`, the table results.json carries as "families" (and each row as "family"):
// [{key, label, color, marker}] in the kinds tables' order (filters, then fits; techniques last),
// each with its own colour ("#rrggbb") and marker (circle, square, triangle, diamond,
// triangle_down, pentagon, hexagon, star).
nlohmann::json methodFamilies(const std::vector<ResultRow>& rows);
// False for a row whose frame compared no pixel (metrics pixels_compared 0, or a row marked
// "nothing_compared"): its rates are 0 of 0, so the report and the charts never rank it.
bool comparedSomething(const ResultRow& r);
// The chart script: $SHADOWLAB_REPORT_SCRIPT when set, else <sourceDir>/compare/report/charts.py
// (the executables know their source folder through the SHADOWLAB_SOURCE_DIR definition).
std::string defaultReportScript(const std::string& sourceDir);

}  // namespace shadowlab
