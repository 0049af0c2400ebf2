// The sweep loop: runs what rows.jsonl does not hold yet, one durable line per finished row, then
// regenerates results.json / results.csv / the report from the whole set.
//
// Why rows.jsonl and not results.json as the journal: appending one line and fsync-ing it costs
// microseconds and cannot corrupt earlier rows, whereas rewriting a growing JSON file per row
// would cost O(rows^2) bytes. A kill during the append leaves at most one torn last line, which
// the next run drops (and truncates away, so the next append starts on a clean line).
#include <fcntl.h>
#include <sys/file.h>
#include <sys/ioctl.h>
#include <sys/utsname.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <thread>

#include "shadowlab/compare/sweep.h"
#include "shadowlab/compare/sweep_frontier.h"
#include "shadowlab/compare/timings.h"
#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/io.h"

namespace shadowlab {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// Folder name for one configuration's images: the config text with anything a file system or a
// shell might trip on replaced.
std::string slug(const std::string& text) {
  std::string out;
  for (char c : text) {
    bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' || c == '-' ||
              c == '_' || c == '=' || c == ',';
    out += ok ? c : '_';
  }
  return out.empty() ? "default" : out;
}

struct StoredRow {
  ResultRow row;
  std::string sceneHash;
  double configWallSeconds = 0;  // config_wall_ms / 1000, kept beside the row in the journal
  std::string device;            // SweepRunner::deviceName() that measured the timings; "" in journals of older builds
};

// Reads rows.jsonl; drops (and truncates away) a torn last line. A damaged line before the last
// is not a torn write: refuse it rather than silently run its configuration again.
// `repair` false (the merge reads other processes' journals): a torn last line is ignored, not
// truncated away.
std::map<std::string, StoredRow> readJournal(const std::string& path, bool repair = true) {
  std::map<std::string, StoredRow> rows;
  std::error_code ec;
  if (!fs::exists(path, ec)) return rows;
  const std::string text = readFile(path);
  size_t pos = 0, goodEnd = 0;
  int lineNo = 0;
  while (pos < text.size()) {
    ++lineNo;
    size_t nl = text.find('\n', pos);
    bool complete = nl != std::string::npos;
    std::string line = text.substr(pos, complete ? nl - pos : std::string::npos);
    size_t next = complete ? nl + 1 : text.size();
    bool last = next >= text.size();
    if (line.empty()) {
      if (complete) goodEnd = next;
      pos = next;
      continue;
    }
    // The journal is this program's own output, so a damaged line is named, not dissected:
    // nlohmann's exception text never reaches the user.
    std::string problem;
    const nlohmann::json j =
        complete ? nlohmann::json::parse(line, nullptr, /*allow_exceptions=*/false) : nlohmann::json();
    if (!complete) {
      problem = "no newline";
    } else if (j.is_discarded()) {
      problem = "not valid JSON";
    } else if (!j.is_object() || !j.contains("row") || !j.value("scene_hash", nlohmann::json("")).is_string() ||
               !j.value("config_wall_seconds", nlohmann::json(0.0)).is_number() ||
               !j.value("device", nlohmann::json("")).is_string()) {
      problem = "expected {\"row\": {...}, \"scene_hash\": \"...\", \"config_wall_seconds\": N, \"device\": \"...\"}";
    } else {
      try {
        StoredRow s;
        s.row = ResultRow::fromJson(j.at("row"), path + ":" + std::to_string(lineNo));
        s.sceneHash = j.value("scene_hash", std::string());
        s.configWallSeconds = j.value("config_wall_seconds", 0.0);
        s.device = j.value("device", std::string());
        rows[s.row.key()] = std::move(s);  // a later line for the same key wins (a stale row re-run)
        goodEnd = next;
      } catch (const InputError& e) {
        problem = e.what();
      }
    }
    // A torn last line (the process died while appending it) is dropped below.
    if (!problem.empty() && !last)
      throw InputError(
          formatError(path + ":" + std::to_string(lineNo), "",
                      "damaged row (" + problem +
                          "); expected one JSON row per line. Delete the line or the file to run it again"));
    pos = next;
  }
  if (repair && goodEnd < text.size()) {
    if (::truncate(path.c_str(), static_cast<off_t>(goodEnd)) != 0)
      throw InputError(formatError(path, "", std::string("cannot drop the torn last line: ") + std::strerror(errno)));
  }
  return rows;
}

// Appends with one write() on an O_APPEND descriptor: once append returns, the row is in the
// file for any later reader, so a killed sweep (SIGKILL included) keeps it. Durability against a
// power cut comes from fdatasync, run by a thread of its own after each append so the next row
// need not wait for the disk (a few ms per row on a busy disk); close() waits for the last sync
// and the results are written only after it. A failed sync is an error at the next append or at close.
class Journal {
 public:
  explicit Journal(const std::string& path) : path_(path) {
    fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
    if (fd_ < 0)
      throw InputError(formatError(path, "", std::string("cannot open for appending: ") + std::strerror(errno)));
    syncer_ = std::thread([this] { syncLoop(); });
  }
  ~Journal() {
    stopSyncer();
    if (fd_ >= 0) ::close(fd_);
  }
  Journal(const Journal&) = delete;
  Journal& operator=(const Journal&) = delete;
  void append(const std::string& line) {
    throwSyncError();
    std::string bytes = line + "\n";
    const char* p = bytes.data();
    size_t left = bytes.size();
    while (left > 0) {
      ssize_t n = ::write(fd_, p, left);
      if (n < 0) {
        if (errno == EINTR) continue;
        throw InputError(formatError(path_, "", std::string("cannot append: ") + std::strerror(errno)));
      }
      p += n;
      left -= size_t(n);
    }
    {
      std::lock_guard<std::mutex> lock(mutex_);
      ++appended_;
    }
    wake_.notify_one();
  }
  // Waits until every appended row is synced; throws the sync's error if one failed.
  void close() {
    stopSyncer();
    throwSyncError();
  }

 private:
  void syncLoop() {
    std::unique_lock<std::mutex> lock(mutex_);
    for (;;) {
      wake_.wait(lock, [&] { return stop_ || synced_ < appended_; });
      if (synced_ == appended_) return;  // stop_ with nothing left to sync
      const size_t upTo = appended_;
      lock.unlock();
      const int err = ::fdatasync(fd_) == 0 ? 0 : errno;
      lock.lock();
      synced_ = upTo;
      if (err != 0 && syncError_.empty()) syncError_ = std::strerror(err);
    }
  }
  void stopSyncer() {
    if (!syncer_.joinable()) return;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    wake_.notify_one();
    syncer_.join();
  }
  void throwSyncError() {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!syncError_.empty()) throw InputError(formatError(path_, "", "cannot sync: " + syncError_));
  }

  std::string path_;
  int fd_ = -1;
  std::mutex mutex_;
  std::condition_variable wake_;
  size_t appended_ = 0, synced_ = 0;  // rows written, rows known synced
  bool stop_ = false;
  std::string syncError_;
  std::thread syncer_;
};

// One sweep per folder at a time: two writers would run the same rows twice.
class FolderLock {
 public:
  explicit FolderLock(const std::string& dir) {
    std::string path = joinPath(dir, ".sweep.lock");
    fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd_ < 0) throw InputError(formatError(path, "", std::string("cannot open: ") + std::strerror(errno)));
    if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
      ::close(fd_);
      fd_ = -1;
      throw InputError(
          formatError(dir, "", "another sweep is writing into this folder; expected one sweep per output folder"));
    }
  }
  ~FolderLock() {
    if (fd_ >= 0) ::close(fd_);
  }

 private:
  int fd_ = -1;
};

std::string fmtDuration(double s) {
  if (!std::isfinite(s) || s < 0) return "--:--";
  long t = long(s + 0.5);
  char buf[32];
  if (t >= 3600) std::snprintf(buf, sizeof buf, "%ld:%02ld:%02ld", t / 3600, (t / 60) % 60, t % 60);
  else std::snprintf(buf, sizeof buf, "%ld:%02ld", t / 60, t % 60);
  return buf;
}

class Progress {
 public:
  Progress(std::FILE* out, bool bar, size_t total, size_t already)
      : out_(out), bar_(bar), total_(total), done_(already), t0_(Clock::now()) {}

  void start(const std::string& what) {
    if (!out_ || !bar_) return;
    draw(what);
  }
  // errorRate NaN: the row compared nothing (its error_rate is null).
  void finish(const std::string& what, double errorRate, double seconds) {
    ++done_;
    ++ran_;
    if (!out_) return;
    if (bar_) {
      draw(what);
      return;
    }
    double elapsed = secondsSince(t0_);
    double rate = elapsed > 0 ? ran_ / elapsed : 0;
    double eta = rate > 0 ? (total_ - done_) / rate : NAN;
    char result[64];
    if (std::isnan(errorRate)) std::snprintf(result, sizeof result, "NOTHING COMPARED (pixels_compared 0)");
    else std::snprintf(result, sizeof result, "error_rate %.6g", errorRate);
    std::fprintf(out_, "sweep: %zu/%zu %s: %s in %.0f ms (%.2f cfg/s, ETA %s)\n", done_, total_, what.c_str(), result,
                 seconds * 1000.0, rate, fmtDuration(eta).c_str());
    std::fflush(out_);
  }
  void end() {
    if (out_ && bar_ && drawn_) {
      std::fputc('\n', out_);
      std::fflush(out_);
    }
  }

 private:
  void draw(const std::string& what) {
    int columns = 100;
    winsize ws{};
    if (::ioctl(::fileno(out_), TIOCGWINSZ, &ws) == 0 && ws.ws_col > 20) columns = ws.ws_col;
    double elapsed = secondsSince(t0_);
    double rate = elapsed > 0 && ran_ > 0 ? ran_ / elapsed : 0;
    double eta = rate > 0 ? (total_ - done_) / rate : NAN;
    const int width = 24;
    int filled = total_ ? int(double(done_) / double(total_) * width) : width;
    std::string bar(size_t(filled), '#');
    bar += std::string(size_t(width - filled), '-');
    char head[160];
    std::snprintf(head, sizeof head, "[%s] %zu/%zu %.2f cfg/s ETA %s ", bar.c_str(), done_, total_, rate,
                  fmtDuration(eta).c_str());
    std::string line = std::string(head) + what;
    if (int(line.size()) > columns - 1) line.resize(size_t(columns - 1));
    std::fprintf(out_, "\r\033[K%s", line.c_str());
    std::fflush(out_);
    drawn_ = true;
  }

  std::FILE* out_;
  bool bar_;
  size_t total_, done_, ran_ = 0;
  Clock::time_point t0_;
  bool drawn_ = false;
};

nlohmann::json machineInfo() {
  nlohmann::json m = nlohmann::json::object();
  char host[256] = {0};
  if (::gethostname(host, sizeof host - 1) == 0) m["hostname"] = host;
  utsname u{};
  if (::uname(&u) == 0) m["os"] = std::string(u.sysname) + " " + u.release + " " + u.machine;
  m["hardware_threads"] = std::thread::hardware_concurrency();
  std::ifstream cpu("/proc/cpuinfo");
  std::string line;
  while (std::getline(cpu, line)) {
    if (line.rfind("model name", 0) == 0) {
      size_t colon = line.find(':');
      if (colon != std::string::npos) m["cpu"] = line.substr(colon + 2);
      break;
    }
  }
  return m;
}

nlohmann::json sweepDescription(const SweepPlan& plan) {
  nlohmann::json d = nlohmann::json::object();
  d["scenes"] = plan.sceneNames;
  d["scene_paths"] = plan.scenePaths;
  nlohmann::json grid = nlohmann::json::array();
  // The canonical texts, in the order given, as they appear in `config` (one axis per key, also
  // for a union of grids).
  for (const auto& axis : sweptAxes(plan)) grid.push_back({{"key", axis.key}, {"values", axis.values}});
  d["grid"] = grid;
  nlohmann::json fixed = nlohmann::json::object();
  for (const auto& s : plan.spec.fixed) fixed[s.key] = s.value;
  d["set"] = fixed;
  if (!plan.spec.methodFile.empty()) d["method_file"] = plan.spec.methodFile;
  d["light"] = plan.spec.light;
  d["spp"] = plan.spec.spp;
  d["light_samples"] = plan.spec.lightSamples;
  d["keep_images"] = plan.spec.keepImages;
  d["frontier"] = {{"metric", plan.spec.frontierMetric}, {"threshold", plan.spec.frontierThreshold}};
  return d;
}

// results.json, results.csv and (options.writeReport) the report from one row per job: the end of
// runSweep and of mergeSweepShards. `extra` keys are added to results.json (e.g. "shards").
void writeSweepOutputs(const SweepPlan& plan, const std::vector<const StoredRow*>& have, SweepRunner& runner,
                       const SweepOptions& options, double loopSeconds, Clock::time_point t0,
                       const nlohmann::json& extra, SweepSummary& summary, PrestartedCharts* charts = nullptr) {
  std::vector<ResultRow> rows;
  nlohmann::json configSeconds = nlohmann::json::array();
  double secondsSum = 0;
  for (size_t i = 0; i < plan.jobs.size(); ++i) {
    rows.push_back(have[i]->row);
    configSeconds.push_back({{"scene", have[i]->row.scene},
                             {"config", have[i]->row.config},
                             {"light", have[i]->row.light},
                             {"config_wall_seconds", have[i]->configWallSeconds}});
    secondsSum += have[i]->configWallSeconds;
  }
  nlohmann::json results = nlohmann::json::object();
  results["schema"] = "shadowlab.results/1";
  results["rows"] = nlohmann::json::array();
  // Each row names the device of its timings (all the same: resuming rows of another device is refused).
  for (size_t i = 0; i < rows.size(); ++i) {
    nlohmann::json r = rows[i].toJson();
    r["device"] = have[i]->device;
    r["family"] = methodFamily(rows[i].method);  // the report's unit of colour and marker
    results["rows"].push_back(std::move(r));
  }
  results["families"] = methodFamilies(rows);
  results["configurations"] = rows.size();
  results["rows_run"] = summary.ran;
  // Which rows carry a median of timed repetitions (method_gpu_ms_min and _max beside it) and which
  // their render's single sample (compare/TIMINGS.md, "Timed repetitions").
  size_t medians = 0;
  for (const ResultRow& r : rows) medians += r.timings.contains(timing::kMethodGpuMsMin) ? 1 : 0;
  results["timing"] = {{"repetitions", options.timingRepetitions > 1 ? options.timingRepetitions : 1},
                       {"noise_factor", kTimingNoiseFactor},
                       {"rows_with_median", medians},
                       {"rows_single_sample", rows.size() - medians},
                       {"rows_timed_again", summary.retimed}};
  results["rows_resumed"] = summary.resumed;
  results["loop_wall_seconds"] = loopSeconds;  // the configuration loop of this invocation
  results["config_wall_seconds"] = configSeconds;
  results["config_wall_seconds_sum"] = secondsSum;  // includes rows finished by earlier invocations
  results["sweep"] = sweepDescription(plan);
  results["frontiers"] = computeFrontiers(plan, rows, plan.spec.frontierMetric, plan.spec.frontierThreshold);
  results["machine"] = machineInfo();
  results["runner"] = runner.info();
  results["report_wall_seconds"] = nullptr;
  results["report_charts_wall_seconds"] = nullptr;
  results["report_triptychs_wall_seconds"] = nullptr;
  results["command_wall_seconds"] = secondsSince(t0);
  for (auto it = extra.begin(); it != extra.end(); ++it) results[it.key()] = it.value();

  summary.resultsJson = joinPath(options.outDir, "results.json");
  summary.resultsCsv = joinPath(options.outDir, "results.csv");
  writeJsonAtomic(summary.resultsJson, results);
  writeResultsCsv(summary.resultsCsv, rows);

  if (options.writeReport) {
    if (options.progress) {
      std::fprintf(options.progress, "sweep: writing the report (charts, best/worst triptychs) into %s\n",
                   options.outDir.c_str());
      std::fflush(options.progress);
    }
    const auto r0 = Clock::now();
    SweepReportTimings reportTimings;
    summary.notes = writeSweepReport(plan, rows, results, runner, options, charts, &reportTimings);
    summary.reportHtml = joinPath(options.outDir, "report.html");
    // Written again so command_wall_seconds covers the report too (charts and triptychs included).
    results["report_wall_seconds"] = secondsSince(r0);
    if (reportTimings.chartsWallSeconds) results["report_charts_wall_seconds"] = *reportTimings.chartsWallSeconds;
    if (reportTimings.triptychsWallSeconds)
      results["report_triptychs_wall_seconds"] = *reportTimings.triptychsWallSeconds;
    results["runner"] = runner.info();  // with what the report's triptychs added
    results["command_wall_seconds"] = secondsSince(t0);
    writeJsonAtomic(summary.resultsJson, results);
  }
  // Rows that compared nothing carry "nothing_compared": true (a column of results.csv) and null
  // rates, so no best, worst, frontier or chart point is drawn from them; say which they are.
  std::vector<std::string> empty;
  for (const ResultRow& r : rows) {
    auto flag = r.metrics.find("nothing_compared");
    if (flag != r.metrics.end() && flag->is_boolean() && flag->get<bool>()) empty.push_back(r.key());
  }
  if (!empty.empty()) {
    std::string list;
    for (size_t i = 0; i < empty.size() && i < 5; ++i) list += (i ? "; " : "") + empty[i];
    if (empty.size() > 5) list += "; and " + std::to_string(empty.size() - 5) + " more";
    summary.notes.push_back(std::to_string(empty.size()) + (empty.size() == 1 ? " row" : " rows") +
                            " compared nothing (pixels_compared 0: the camera sees no surface both renderers agree "
                            "on), marked \"nothing_compared\": true in results.json and results.csv, rates null, "
                            "never ranked: " +
                            list);
  }
}

}  // namespace

std::map<std::string, SweepJournalRow> readSweepJournal(const std::string& path) {
  std::map<std::string, SweepJournalRow> out;
  for (auto& [key, s] : readJournal(path, /*repair=*/false))
    out[key] = SweepJournalRow{std::move(s.row), std::move(s.sceneHash), s.configWallSeconds, std::move(s.device)};
  return out;
}

std::string defaultSweepCacheDir(const std::string& outDir) {
  const char* env = std::getenv("SHADOWLAB_CACHE");
  if (env && *env) return env;
  fs::path out = fs::absolute(fs::path(outDir)).lexically_normal();
  if (!out.has_filename()) out = out.parent_path();  // trailing slash
  return (out.parent_path() / ".shadowlab-cache").string();
}

namespace {
SweepSummary runSweepIn(const SweepPlan& plan, SweepRunner& runner, const SweepOptions& options, size_t& finished);
}  // namespace

SweepSummary runSweep(const SweepPlan& plan, SweepRunner& runner, const SweepOptions& options) {
  // Bad input that only the work finds (a camera that sees no surface: the reference's check) is
  // exit 2 with no half-written output: what this call created in the folder (its journal, log,
  // lock, shard.json, images/) goes when no row was finished into a journal that did not exist
  // before. A folder with rows keeps them: the next run resumes from them.
  const std::string workDir = options.shard.active() && options.shard.index < options.shard.count
                                  ? shardDir(options.outDir, options.shard)
                                  : options.outDir;
  std::vector<std::string> fresh;
  std::error_code ec;
  if (!workDir.empty()) {
    if (!fs::exists(workDir, ec)) fresh.push_back(workDir);
    for (const char* name : {"rows.jsonl", "sweep.log", ".sweep.lock", "shard.json", "images"})
      if (!fs::exists(joinPath(workDir, name), ec)) fresh.push_back(joinPath(workDir, name));
  }
  size_t finished = 0;
  try {
    return runSweepIn(plan, runner, options, finished);
  } catch (const InputError&) {
    const bool journalIsNew = std::find(fresh.begin(), fresh.end(), joinPath(workDir, "rows.jsonl")) != fresh.end() ||
                              (!fresh.empty() && fresh.front() == workDir);
    if (finished == 0 && journalIsNew)
      for (auto it = fresh.rbegin(); it != fresh.rend(); ++it) fs::remove_all(*it, ec);
    throw;
  }
}

namespace {
SweepSummary runSweepIn(const SweepPlan& plan, SweepRunner& runner, const SweepOptions& options, size_t& finished) {
  const auto t0 = Clock::now();
  SweepSummary summary;
  const SweepShard& shard = options.shard;
  if (shard.active() && shard.index >= shard.count) throw InputError("--shard: error: I >= N; expected 0 <= I < N");
  for (size_t i = 0; i < plan.jobs.size(); ++i) summary.configurations += shard.owns(i) ? 1 : 0;
  if (options.outDir.empty()) throw InputError("shadowlab sweep: error: no output folder; expected -o DIR");
  // The report's Python starts now (the interpreter and the chart script's modules load) while the
  // device starts and the rows run (a core is mostly free then); it writes nothing unless the report
  // hands it the chart script.
  const std::unique_ptr<PrestartedCharts> charts = prestartCharts(options);
  // Device limits are input errors too: found before the output folder exists.
  for (const auto& c : plan.configs) runner.checkMethod(c.method, "shadowlab sweep: configuration " + c.config);
  // A shard works in its own folder with its own lock and journal: two shards never write one file.
  const std::string workDir = shard.active() ? shardDir(options.outDir, shard) : options.outDir;
  makeDirs(workDir);
  FolderLock lock(workDir);
  if (shard.active()) {
    // shard.json ties the journal to its plan; a shard folder of another plan is refused rather
    // than half-reused (the merge could not tell which rows belong to which plan).
    const std::string metaPath = joinPath(workDir, "shard.json");
    const std::string fingerprint = planFingerprint(plan);
    std::error_code ec;
    if (fs::exists(metaPath, ec)) {
      const nlohmann::json old = nlohmann::json::parse(readFile(metaPath), nullptr, false);
      const std::string oldFp = old.is_object() ? old.value("plan_fingerprint", std::string()) : std::string();
      if (oldFp != fingerprint)
        throw InputError(formatError(metaPath, "",
                                     "this shard folder holds plan " + (oldFp.empty() ? "(unreadable)" : oldFp) +
                                         " but this sweep is plan " + fingerprint +
                                         "; expected the same sweep arguments and inputs (or another -o)"));
    } else {
      nlohmann::json meta = {
          {"schema", "shadowlab.shard/1"}, {"plan_fingerprint", fingerprint},        {"shard_index", shard.index},
          {"shard_count", shard.count},    {"rows_planned", summary.configurations}, {"plan_rows", plan.jobs.size()},
          {"spec", sweepSpecToJson(plan)}};
      writeJsonAtomic(metaPath, meta);
    }
  }
  const std::string journalPath = joinPath(workDir, "rows.jsonl");
  auto stored = readJournal(journalPath);
  Journal journal(journalPath);
  std::ofstream log(joinPath(workDir, "sweep.log"), std::ios::app);
  const long pid = long(::getpid());
  const std::string device = runner.deviceName();

  // A stored row counts only for the same scene content and the same resolved method: editing a
  // scene file or a --set between runs must not mix old rows into new results.
  std::vector<nlohmann::json> methodJson(plan.configs.size());
  for (size_t i = 0; i < plan.configs.size(); ++i) methodJson[i] = methodToJson(plan.configs[i].method);
  std::vector<const StoredRow*> have(plan.jobs.size(), nullptr);
  for (size_t i = 0; i < plan.jobs.size(); ++i) {
    if (!shard.owns(i)) continue;
    const SweepJob& job = plan.jobs[i];
    auto it = stored.find(job.key());
    if (it == stored.end()) continue;
    if (it->second.sceneHash != plan.variants[job.variantIndex].hash) continue;
    // A technique file edited since the row was measured: the same config text, another file.
    // Refused, naming both, rather than silently measured again beside rows of the old one.
    const nlohmann::json &was = it->second.row.method, &now = methodJson[job.configIndex];
    if (was.contains("technique.hash") && now.contains("technique.hash") &&
        was["technique.hash"] != now["technique.hash"])
      throw InputError(formatError(
          journalPath, "",
          "row \"" + job.key() + "\" was measured with technique " + was["technique.hash"].get<std::string>() +
              " but " + now.value("technique", std::string()) + " is now " + now["technique.hash"].get<std::string>() +
              "; expected the same file (restore it, or use another -o folder)"));
    if (it->second.row.method != methodJson[job.configIndex]) continue;
    // Timings of two devices on one axis would compare a GPU with a CPU rasterizer: refuse rather
    // than mix (another -o folder, or the same --device, is what the user wants).
    if (it->second.device != device)
      throw InputError(formatError(
          journalPath, "",
          "row \"" + job.key() + "\" was measured on device \"" +
              (it->second.device.empty() ? std::string("(not recorded: an older shadowlab)") : it->second.device) +
              "\" but this sweep runs on \"" + device +
              "\"; expected one device per output folder (use another -o folder, or --device naming the first "
              "device)"));
    have[i] = &it->second;
    ++summary.resumed;
  }
  if (log)
    log << "pid " << pid << " begin: " << summary.configurations << " rows planned, " << summary.resumed
        << " already done\n";
  if (options.progress && summary.resumed > 0)
    std::fprintf(options.progress, "sweep: resuming: %zu of %zu rows are already in %s\n", summary.resumed,
                 summary.configurations, journalPath.c_str());

  Progress progress(options.progress, options.progressBar, summary.configurations, summary.resumed);
  std::vector<StoredRow> fresh(plan.jobs.size());
  std::vector<char> batched(plan.jobs.size(), 0);
  const auto loop0 = Clock::now();
  for (size_t i = 0; i < plan.jobs.size(); ++i) {
    if (have[i] || !shard.owns(i)) continue;
    if (options.stop && options.stop->load()) {
      summary.interrupted = true;
      break;
    }
    const SweepJob& job = plan.jobs[i];
    const SweepConfig& config = plan.configs[job.configIndex];
    const Scene& scene = plan.variants[job.variantIndex];
    // An outside renderer's rows of this scene and light that still need a frame: one batch of its
    // adapter (adapters/README.md), its request, frames and log under adapter/<scene>/.
    if (!config.method.renderer.empty() && !batched[i]) {
      std::vector<std::pair<std::string, Method>> batch;
      for (size_t j = i; j < plan.jobs.size(); ++j) {
        const SweepJob& other = plan.jobs[j];
        if (have[j] || !shard.owns(j) || other.variantIndex != job.variantIndex || other.light != job.light ||
            plan.configs[other.configIndex].method.renderer.empty())
          continue;
        batched[j] = 1;
        batch.emplace_back(other.config, plan.configs[other.configIndex].method);
      }
      runner.prefetch(scene, batch, job.light, joinPath(joinPath(workDir, "adapter"), slug(job.sceneName)));
    }
    const std::string what = job.sceneName + " " + job.config;
    if (log) log << "pid " << pid << " start " << job.key() << "\n" << std::flush;
    progress.start(what);
    std::string imagesDir;
    if (plan.spec.keepImages) {
      imagesDir = joinPath(joinPath(joinPath(options.outDir, "images"), slug(job.sceneName)), slug(job.config));
      makeDirs(imagesDir);
    }
    const auto c0 = Clock::now();
    SweepRunOutput out = runner.run(scene, config.method, job.light, imagesDir);
    const double seconds = secondsSince(c0);
    StoredRow s;
    s.row.scene = job.sceneName;
    s.row.config = job.config;
    s.row.light = job.light;
    s.row.method = methodJson[job.configIndex];
    s.row.metrics = out.metrics;
    s.row.timings = out.timings;
    s.row.timings[timing::kConfigWallMs] = seconds * 1000.0;  // wall time of this configuration in the sweep
    s.sceneHash = scene.hash;
    s.configWallSeconds = seconds;
    s.device = device;
    nlohmann::json line = {{"scene_hash", s.sceneHash},
                           {"config_wall_seconds", seconds},
                           {"pid", pid},
                           {"device", device},
                           {"row", s.row.toJson()}};
    if (shard.active()) line["shard"] = std::to_string(shard.index) + "/" + std::to_string(shard.count);
    journal.append(line.dump());
    if (log) log << "pid " << pid << " done " << job.key() << " " << seconds << " s\n" << std::flush;
    // null when the row compared nothing (compare/METRICS.md "Nothing compared")
    const auto rateIt = out.metrics.find("error_rate");
    const double errorRate = rateIt != out.metrics.end() && rateIt->is_number() ? rateIt->get<double>() : std::nan("");
    fresh[i] = std::move(s);
    have[i] = &fresh[i];
    ++summary.ran;
    ++finished;
    progress.finish(what, errorRate, seconds);
  }
  progress.end();
  // Timing where it decides something (sweep.h, rowsWhoseTimeDecides): the rows near each scene's
  // Pareto front, and those the caller names, timed again to a median unless they already carry
  // one (a resumed row). Their journal line is written again with the new timings: a later line
  // for the same key wins, so a resumed sweep keeps the median.
  if (!summary.interrupted && !shard.active() && options.timingRepetitions > 1) {
    // One row per job (null: not run, another shard's); the pointers follow the rows timed again.
    std::vector<const ResultRow*> rows(plan.jobs.size(), nullptr);
    for (size_t i = 0; i < plan.jobs.size(); ++i)
      if (have[i]) rows[i] = &have[i]->row;
    std::vector<char> wanted(plan.jobs.size(), 0);
    if (options.retimeFront && options.writeResults)
      for (size_t i : jobsWhoseTimeDecides(plan, rows)) wanted[i] = 1;
    for (size_t i = 0; i < plan.jobs.size(); ++i)
      if (have[i] && std::find(options.retimeKeys.begin(), options.retimeKeys.end(), plan.jobs[i].key()) !=
                         options.retimeKeys.end())
        wanted[i] = 1;
    const auto r0 = Clock::now();
    // Then the front itself (factor 1, no model) with the medians in: a row the first pass left with
    // its single sample that is on a front now is timed too, until every front row carries a median
    // (a few rounds at most: each round only adds rows).
    for (int round = 0; round < 4 && !summary.interrupted; ++round) {
      if (round > 0) {
        if (!(options.retimeFront && options.writeResults)) break;
        std::vector<const ResultRow*> present;
        std::vector<size_t> jobOf;
        for (size_t i = 0; i < rows.size(); ++i)
          if (rows[i]) present.push_back(rows[i]), jobOf.push_back(i);
        bool more = false;
        for (size_t k : rowsWhoseTimeDecides(present, {}, 1.0))
          if (!present[k]->timings.contains(timing::kMethodGpuMsMin) && !wanted[jobOf[k]])
            wanted[jobOf[k]] = 1, more = true;
        if (!more) break;
      }
      for (size_t i = 0; i < plan.jobs.size(); ++i) {
        if (!wanted[i] || have[i]->device != device) continue;
        if (have[i]->row.timings.contains(timing::kMethodGpuMsMin)) continue;  // a median already
        if (options.stop && options.stop->load()) {
          summary.interrupted = true;
          break;
        }
        const SweepJob& job = plan.jobs[i];
        const std::vector<MethodSample> more =
            runner.timeAgain(plan.variants[job.variantIndex], plan.configs[job.configIndex].method, job.light,
                             options.timingRepetitions - 1);
        if (more.empty()) continue;
        if (&fresh[i] != have[i]) fresh[i] = *have[i];
        fresh[i].row.timings = withMedianTiming(fresh[i].row.timings, more);
        have[i] = &fresh[i];
        rows[i] = &fresh[i].row;
        nlohmann::json line = {{"scene_hash", fresh[i].sceneHash},
                               {"config_wall_seconds", fresh[i].configWallSeconds},
                               {"pid", pid},
                               {"device", device},
                               {"timed_again", true},
                               {"row", fresh[i].row.toJson()}};
        journal.append(line.dump());
        summary.retimedTimings[job.key()] = fresh[i].row.timings;
        ++summary.retimed;
      }
    }
    if (summary.retimed > 0) {
      if (log) log << "pid " << pid << " timed " << summary.retimed << " rows again\n";
      if (options.progress && options.writeResults)
        std::fprintf(options.progress,
                     "sweep: timed %zu of %zu rows again (%d runs each, %.1f s): the rows near each scene's "
                     "Pareto front\n",
                     summary.retimed, summary.resumed + summary.ran, options.timingRepetitions, secondsSince(r0));
    }
  }
  journal.close();  // every row run is synced before anything is read from or written about them
  const double loopSeconds = secondsSince(loop0);
  if (!options.writeResults && !shard.active()) {
    summary.rows.resize(plan.jobs.size());
    for (size_t i = 0; i < plan.jobs.size(); ++i)
      if (have[i]) summary.rows[i] = have[i]->row;
  }
  if (summary.interrupted) {
    if (log) log << "pid " << pid << " interrupted after " << summary.ran << " rows\n";
    summary.commandWallSeconds = secondsSince(t0);
    return summary;
  }
  if (shard.active()) {
    // The merge writes results and the report once every shard is done.
    if (log) log << "pid " << pid << " shard end: " << summary.ran << " rows run\n";
    summary.commandWallSeconds = secondsSince(t0);
    return summary;
  }

  if (options.writeResults)
    writeSweepOutputs(plan, have, runner, options, loopSeconds, t0, nlohmann::json::object(), summary, charts.get());
  summary.commandWallSeconds = secondsSince(t0);
  if (log) log << "pid " << pid << " end: " << summary.ran << " rows run, " << summary.commandWallSeconds << " s\n";
  return summary;
}

}  // namespace

SweepSummary mergeSweepShards(const SweepPlan& plan, SweepRunner& runner, const SweepOptions& options) {
  const auto t0 = Clock::now();
  SweepSummary summary;
  summary.configurations = plan.jobs.size();
  if (options.outDir.empty()) throw InputError("shadowlab merge: error: no output folder; expected OUT_DIR");
  const std::string fingerprint = planFingerprint(plan);
  const fs::path shardsDir = fs::path(options.outDir) / "shards";

  // Every problem is gathered first and reported together, each naming its file; nothing is
  // written unless there is none.
  std::vector<std::string> problems;
  struct Shard {
    std::string dir, meta;
    size_t index = 0, count = 0;
  };
  std::vector<Shard> shards;
  std::error_code ec;
  std::vector<fs::path> dirs;
  if (fs::is_directory(shardsDir, ec))
    for (const auto& e : fs::directory_iterator(shardsDir, ec))
      if (e.is_directory(ec)) dirs.push_back(e.path());
  std::sort(dirs.begin(), dirs.end());
  for (const auto& d : dirs) {
    Shard sh;
    sh.dir = d.string();
    sh.meta = (d / "shard.json").string();
    const nlohmann::json meta =
        fs::exists(sh.meta, ec) ? nlohmann::json::parse(readFile(sh.meta), nullptr, false) : nlohmann::json();
    if (!meta.is_object() || !meta.value("plan_fingerprint", nlohmann::json()).is_string() ||
        !meta.value("shard_index", nlohmann::json()).is_number_unsigned() ||
        !meta.value("shard_count", nlohmann::json()).is_number_unsigned()) {
      problems.push_back(formatError(sh.meta, "",
                                     "missing or damaged shard description; expected the shard.json "
                                     "`shadowlab sweep --shard I/N` writes"));
      continue;
    }
    sh.index = meta.at("shard_index").get<size_t>();
    sh.count = meta.at("shard_count").get<size_t>();
    const std::string fp = meta.at("plan_fingerprint").get<std::string>();
    if (fp != fingerprint)
      problems.push_back(formatError(sh.meta, "/plan_fingerprint",
                                     "plan " + fp + " differs from plan " + fingerprint +
                                         " (the sweep recorded in the first shard.json, planned again from the "
                                         "files as they are now); expected shards of one sweep (same arguments, "
                                         "same scene and method files)"));
    shards.push_back(sh);
  }
  if (shards.empty() && problems.empty())
    throw InputError(formatError(shardsDir.string(), "",
                                 "no shard folders; expected the output of "
                                 "`shadowlab sweep ... --shard I/N -o " +
                                     options.outDir + "`"));
  const size_t count = shards.empty() ? 0 : shards.front().count;
  for (const auto& sh : shards)
    if (sh.count != count)
      problems.push_back(formatError(sh.meta, "/shard_count",
                                     "N is " + std::to_string(sh.count) + " but " + shards.front().meta + " has N = " +
                                         std::to_string(count) + "; expected every shard of one sweep to share N"));
  if (!problems.empty()) {
    std::string all;
    for (const auto& p : problems) all += (all.empty() ? "" : "\n") + p;
    throw InputError(all);
  }
  std::vector<const Shard*> byIndex(count, nullptr);
  for (const auto& sh : shards) {
    if (sh.index >= count || byIndex[sh.index])
      problems.push_back(formatError(
          sh.meta, "/shard_index",
          "shard " + std::to_string(sh.index) + " of " + std::to_string(count) +
              (sh.index >= count ? " is out of range" : " appears twice (also " + byIndex[sh.index]->meta + ")") +
              "; expected one folder per shard I < N"));
    else byIndex[sh.index] = &sh;
  }
  if (!problems.empty()) {
    std::string all;
    for (const auto& p : problems) all += (all.empty() ? "" : "\n") + p;
    throw InputError(all);
  }
  std::string missing;
  for (size_t i = 0; i < count; ++i)
    if (!byIndex[i]) missing += (missing.empty() ? "" : ", ") + std::to_string(i);
  if (!missing.empty())
    throw InputError(formatError(shardsDir.string(), "",
                                 "missing shard(s) " + missing + " of " + std::to_string(count) +
                                     "; expected one folder I-of-" + std::to_string(count) + " for every I in 0.." +
                                     std::to_string(count - 1) + " (run `shadowlab sweep ... --shard I/" +
                                     std::to_string(count) + "` for each)"));

  // Rows: each must belong to the plan (same scene content and method); a configuration held by
  // two journals must agree in every metric.
  std::vector<nlohmann::json> methodJson(plan.configs.size());
  for (size_t i = 0; i < plan.configs.size(); ++i) methodJson[i] = methodToJson(plan.configs[i].method);
  std::map<std::string, size_t> jobOf;
  for (size_t i = 0; i < plan.jobs.size(); ++i) jobOf[plan.jobs[i].key()] = i;
  std::vector<std::map<std::string, StoredRow>> journals(count);
  std::vector<const StoredRow*> have(plan.jobs.size(), nullptr);
  std::vector<std::string> haveFrom(plan.jobs.size());
  for (size_t si = 0; si < count; ++si) {
    const std::string path = joinPath(byIndex[si]->dir, "rows.jsonl");
    journals[si] = readJournal(path, /*repair=*/false);
    size_t own = 0, share = 0;
    for (size_t i = 0; i < plan.jobs.size(); ++i) share += i % count == si ? 1 : 0;
    for (const auto& [key, row] : journals[si]) {
      auto j = jobOf.find(key);
      if (j == jobOf.end() || row.sceneHash != plan.variants[plan.jobs[j->second].variantIndex].hash ||
          row.row.method != methodJson[plan.jobs[j->second].configIndex]) {
        problems.push_back(formatError(path, "",
                                       "row \"" + key + "\" is not a row of plan " + fingerprint +
                                           " (unknown configuration, or another scene content or method)"));
        continue;
      }
      const size_t i = j->second;
      if (i % count == si) ++own;
      if (have[i]) {
        if (have[i]->row.metrics != row.row.metrics)
          problems.push_back(formatError(path, "",
                                         "row \"" + key + "\" is also in " + haveFrom[i] +
                                             " with different metrics; expected one result per configuration"));
        if (i % count != si) continue;  // the owner's row is the one kept
      }
      have[i] = &row;
      haveFrom[i] = path;
    }
    if (own < share)
      problems.push_back(formatError(path, "",
                                     "shard " + std::to_string(si) + "/" + std::to_string(count) +
                                         " is incomplete: " + std::to_string(own) + " of its " + std::to_string(share) +
                                         " rows; expected it finished (run the "
                                         "same `shadowlab sweep ... --shard " +
                                         std::to_string(si) + "/" + std::to_string(count) + "` again to complete it)"));
  }
  // One time axis never holds two devices (as runSweep refuses to resume across devices).
  std::string device;
  std::string deviceFrom;
  for (size_t i = 0; i < have.size(); ++i) {
    if (!have[i]) continue;
    if (deviceFrom.empty()) {
      device = have[i]->device;
      deviceFrom = haveFrom[i];
    } else if (have[i]->device != device) {
      problems.push_back(formatError(haveFrom[i], "",
                                     "rows measured on device \"" + have[i]->device + "\" but " + deviceFrom +
                                         " has rows of \"" + device +
                                         "\"; expected every shard on one device (--device)"));
      break;
    }
  }
  if (!problems.empty()) {
    std::string all;
    for (const auto& p : problems) all += (all.empty() ? "" : "\n") + p;
    throw InputError(all);
  }
  for (size_t i = 0; i < have.size(); ++i)
    if (!have[i])
      throw DriverError("shadowlab merge: error: row " + plan.jobs[i].key() + " not found after the checks");

  makeDirs(options.outDir);
  FolderLock lock(options.outDir);
  summary.resumed = plan.jobs.size();
  nlohmann::json extra = {{"shards", count}, {"plan_fingerprint", fingerprint}};
  writeSweepOutputs(plan, have, runner, options, 0.0, t0, extra, summary);
  summary.commandWallSeconds = secondsSince(t0);
  return summary;
}

}  // namespace shadowlab
