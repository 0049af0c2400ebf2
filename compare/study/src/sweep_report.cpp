// The sweep's readable outputs: results.csv, the charts (compare/report/charts.py, run as a child
// process so that the C++ side needs no Python), the triptychs and report.html.
//
// report.html must open from disk with no network: no external scripts, fonts or styles; every
// picture is a relative file under figures/ (the folder travels together). A small inline script
// marks document.body.dataset.imagesOk after checking every <img>, so a headless browser can tell
// a broken report from a good one (tests/report_chromium_test.cpp).
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <thread>

#include "json_number.h"
#include "shadowlab/compare/compare.h"
#include "shadowlab/compare/sweep.h"
#include "shadowlab/compare/timings.h"
#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/io.h"
#include "shadowlab/scenes/json_reader.h"

namespace shadowlab {
namespace {

namespace fs = std::filesystem;

std::string csvField(const std::string& s) {
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string out = "\"";
  for (char c : s) {
    if (c == '"') out += "\"\"";
    else out += c;
  }
  return out + "\"";
}

std::string valueText(const nlohmann::json& v) {
  if (v.is_null()) return "";
  if (v.is_string()) return v.get<std::string>();
  if (v.is_boolean()) return v.get<bool>() ? "true" : "false";
  if (v.is_number_float()) {
    if (!std::isfinite(v.get<double>())) return "";
    return v.dump();  // shortest text that reads back to the same double
  }
  return v.dump();
}

// Flattens nested objects into dotted names (a later metric may hold per-cascade objects).
void flatten(const nlohmann::json& j, const std::string& prefix,
             std::vector<std::pair<std::string, nlohmann::json>>& out) {
  for (auto it = j.begin(); it != j.end(); ++it) {
    std::string name = prefix.empty() ? it.key() : prefix + "." + it.key();
    if (it.value().is_object()) flatten(it.value(), name, out);
    else out.emplace_back(name, it.value());
  }
}

std::string fmt(double v, const char* f = "%.4g") {
  if (!std::isfinite(v)) return "&ndash;";
  char buf[64];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

// A rate as a percentage with three significant digits (0.0123 -> "1.23%", 0.46 -> "46%").
std::string pctCell(double rate) {
  if (!std::isfinite(rate)) return "&ndash;";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.3g%%", rate * 100.0);
  return buf;
}

// A number with three significant digits (the report's tables).
std::string sig3(double v) { return fmt(v, "%.3g"); }

// Escaped text that may break after ',', '_', '/' and '=' (configurations, paths, metric names):
// long names wrap inside their cell instead of widening the table past the page.
std::string breakable(const std::string& s) {
  std::string out;
  for (char c : s) {
    std::string one(1, c);
    out += escapeMarkup(one);
    if (c == ',' || c == '_' || c == '/' || c == '=') out += "<wbr>";
  }
  return out;
}

// The error classes' rate metrics (classes.h), in table order: the report's class columns.
std::vector<const char*> errorRateMetrics() {
  std::vector<const char*> names;
  for (const PixelClassInfo& c : kPixelClasses)
    if (c.error && c.rateMetric) names.push_back(c.rateMetric);
  return names;
}

// The class columns a table shows: those with a nonzero rate in one of its rows. A column that is
// 0 (or absent) in every row says nothing a reader needs (leak, bleed, coverage and the penumbra
// classes on most scenes); `hidden` gets its names, which the table's caption lists once.
std::vector<const char*> classColumns(const std::vector<const ResultRow*>& rows, std::vector<const char*>* hidden) {
  std::vector<const char*> shown;
  for (const char* k : errorRateMetrics()) {
    bool any = false;
    for (const ResultRow* r : rows) {
      const double v = numberAt(r->metrics, k);
      any = any || (std::isfinite(v) && v != 0.0);
    }
    (any ? shown : *hidden).push_back(k);
  }
  return shown;
}

// "0 % in every row, not shown: leak_rate, bleed_rate." (empty when every column is shown).
std::string hiddenColumnsNote(const std::vector<const char*>& hidden) {
  if (hidden.empty()) return "";
  std::string out = "<p class=\"muted hidden-columns\">0 % in every row, not shown: ";
  for (size_t i = 0; i < hidden.size(); ++i) out += std::string(i ? ", " : "") + "<code>" + hidden[i] + "</code>";
  return out + ".</p>\n";
}

std::string headerCells(const std::vector<const char*>& names) {
  std::string h;
  for (const char* n : names) h += "<th>" + breakable(n) + "</th>";
  return h;
}

// Starts `argv` with stdout and stderr into `logPath`; returns its pid (-1 when fork failed).
pid_t spawnLogged(const std::vector<std::string>& argv, const std::string& logPath) {
  int logFd = ::open(logPath.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  pid_t pid = ::fork();
  if (pid < 0) {
    if (logFd >= 0) ::close(logFd);
    return -1;
  }
  if (pid == 0) {
    if (logFd >= 0) {
      ::dup2(logFd, 1);
      ::dup2(logFd, 2);
    }
    // The chart script must not read the terminal (a SIGINT meant for the sweep reaches it too,
    // which is what a user expects).
    int devnull = ::open("/dev/null", O_RDONLY);
    if (devnull >= 0) ::dup2(devnull, 0);
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    ::execv(args[0], args.data());
    std::fprintf(stderr, "cannot run %s: %s\n", args[0], std::strerror(errno));
    ::_exit(127);
  }
  if (logFd >= 0) ::close(logFd);
  return pid;
}

// The exit status of a spawned child (-1 when it could not start, 128 + signal when killed).
int waitExit(pid_t pid) {
  if (pid < 0) return -1;
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) return -1;
  }
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  if (WIFSIGNALED(status)) return 128 + WTERMSIG(status);
  return -1;
}

// The interpreter the chart script runs in: SweepOptions::python, else $SHADOWLAB_PYTHON, else
// /usr/bin/python3.
std::string chartPython(const SweepOptions& options) {
  if (!options.python.empty()) return options.python;
  const char* env = std::getenv("SHADOWLAB_PYTHON");
  return env && *env ? env : "/usr/bin/python3";
}

// What the prestarted Python runs (`python -c`): with SIGINT ignored and its output discarded, the
// standard modules charts.py imports (json, statistics, zlib: the script draws without a plotting
// library), then it reads "LOG\0SCRIPT\0ARG\0...\0run" from stdin (the sweep's report) and runs
// SCRIPT as `python SCRIPT ARG...` would, stdout and stderr into LOG, SIGINT back to its default.
// End of input without that message (the sweep ended without a report): it exits, having written
// nothing.
const char* kChartBootstrap = R"PY(
import os, signal, sys
signal.signal(signal.SIGINT, signal.SIG_IGN)
import json, math, statistics, zlib
data = b""
while True:
    chunk = os.read(0, 65536)
    if not chunk:
        break
    data += chunk
fields = data.split(b"\0")
if len(fields) < 3 or fields[-1] != b"run":
    os._exit(0)
fd = os.open(fields[0], os.O_WRONLY | os.O_CREAT | os.O_TRUNC | os.O_CLOEXEC, 0o644)
os.dup2(fd, 1)
os.dup2(fd, 2)
os.close(fd)
fd = os.open(os.devnull, os.O_RDONLY | os.O_CLOEXEC)
os.dup2(fd, 0)
os.close(fd)
signal.signal(signal.SIGINT, signal.default_int_handler)
sys.argv = [os.fsdecode(f) for f in fields[1:-1]]
sys.path[0] = os.path.dirname(os.path.abspath(sys.argv[0]))
import runpy
runpy.run_path(sys.argv[0], run_name="__main__")
)PY";

std::string tailOf(const std::string& path, size_t lines) {
  std::string text;
  try {
    text = readFile(path);
  } catch (const std::exception&) {
    return "";
  }
  size_t pos = text.size();
  while (pos > 0 && (text[pos - 1] == '\n')) --pos;
  size_t end = pos;
  for (size_t n = 0; n < lines && pos > 0; ++n) {
    pos = text.rfind('\n', pos - 1);
    if (pos == std::string::npos) {
      pos = 0;
      break;
    }
  }
  return text.substr(pos == 0 ? 0 : pos + 1, end - (pos == 0 ? 0 : pos + 1));
}

std::string fileSafe(const std::string& s) {
  std::string out;
  for (char c : s) out += (std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_') ? c : '_';
  return out;
}

// The page fits 900 px and 1400 px windows and print without horizontal scrolling: tables use
// small text, wrap long names at their separators (breakable) and never exceed the body's width;
// charts are inline SVG laid out in points (their text at least 8 pt printed), scaled down to fit.
const char* kStyle = R"CSS(
body { font-family: -apple-system, "Segoe UI", Roboto, "DejaVu Sans", Arial, sans-serif; margin: 1.5em auto;
       max-width: 1200px; padding: 0 1em; color: #1d1d1f; line-height: 1.4; }
h1 { font-size: 1.6em; margin-bottom: 0.2em; } h2 { margin-top: 1.6em; border-bottom: 1px solid #ddd; }
h3 { margin-bottom: 0.3em; }
table { border-collapse: collapse; margin: 0.6em 0 1.2em; font-size: 0.8em; max-width: 100%; }
th, td { border: 1px solid #d0d0d0; padding: 0.2em 0.4em; text-align: right; vertical-align: top;
         overflow-wrap: anywhere; }
td:not(.t) { white-space: nowrap; overflow-wrap: normal; }
th { background: #f3f3f3; font-weight: 600; } td.t, th.t { text-align: left; }
table.findings { width: 100%; font-size: 0.85em; } table.findings td { min-width: 5em; }
table.glance { width: 100%; font-size: 0.8em; line-height: 1.25; } table.glance td { padding: 0.1em 0.4em; }
table.rows td:nth-child(2) { min-width: 9em; } tr.empty td { color: #999; }
tr:target { background: #fff3b0; } .spread { color: #666; white-space: nowrap; }
figure { margin: 1em 0 2em; } figure img { max-width: 100%; height: auto; border: 1px solid #e3e3e3; }
figure.chart svg { display: block; max-width: 100%; height: auto; }
figcaption { font-size: 0.9em; color: #444; margin-top: 0.3em; max-width: 60em; }
.note { background: #fff8e1; border-left: 4px solid #f0b400; padding: 0.4em 0.8em; margin: 0.5em 0; }
.muted { color: #666; font-size: 0.9em; } code { font-family: "DejaVu Sans Mono", monospace; }
details summary { cursor: pointer; margin: 0.5em 0; }
@media print {
  body { max-width: none; margin: 0; padding: 0; font-size: 9pt; }
  table { font-size: 7.5pt; } figure { break-inside: avoid; } h2 { break-after: avoid; }
  figure.chart svg { max-width: 100%; }
}
)CSS";

// Marks the page for headless checks: imagesOk is "true" only when every picture decoded.
// Marks the page for headless checks: imagesOk is "true" only when every picture decoded, figures
// counts the inline charts that laid out, overflow is the page's width beyond the window (px). A
// link to a row opens the collapsed table of every row first.
const char* kImageCheck = R"JS(
function shadowlabOpenRow() {
  var t = location.hash && document.getElementById(location.hash.slice(1));
  if (t && t.id.indexOf('row-') === 0) { document.getElementById('all-rows').open = true; t.scrollIntoView(); }
}
window.addEventListener('hashchange', shadowlabOpenRow);
window.addEventListener('load', function () {
  shadowlabOpenRow();
  var images = document.images, bad = [];
  for (var i = 0; i < images.length; i++) {
    if (!(images[i].complete && images[i].naturalWidth > 0)) bad.push(images[i].getAttribute('src'));
  }
  var charts = document.querySelectorAll('figure.chart svg'), laid = 0;
  for (var k = 0; k < charts.length; k++) {
    var box = charts[k].getBoundingClientRect();
    if (box.width > 0 && box.height > 0) laid++;
  }
  var d = document.body.dataset;
  d.imagesOk = bad.length === 0 ? 'true' : 'false';
  d.imagesCount = String(images.length);
  d.figures = String(laid);
  d.tooltips = String(document.querySelectorAll('figure.chart svg title').length);
  d.overflow = String(Math.max(0, document.documentElement.scrollWidth - document.documentElement.clientWidth));
  // Numbers never wrap: a number cell (every td but the text ones) laid out on more than one line,
  // that is with a piece of it wholly below another (a raised superscript overlaps its line).
  var cells = document.querySelectorAll('td:not(.t)'), wrapped = 0;
  for (var c = 0; c < cells.length; c++) {
    var range = document.createRange(), lowestTop = -Infinity, highestBottom = Infinity;
    range.selectNodeContents(cells[c]);
    var rects = range.getClientRects();
    for (var q = 0; q < rects.length; q++) {
      if (!(rects[q].height > 0)) continue;
      lowestTop = Math.max(lowestTop, rects[q].top);
      highestBottom = Math.min(highestBottom, rects[q].bottom);
    }
    if (lowestTop >= highestBottom) { wrapped++; cells[c].dataset.wrapped = 'true'; }
  }
  d.wrappedNumbers = String(wrapped);
  var glance = document.getElementById('glance');
  if (glance) {
    d.glanceBottom = String(Math.ceil(glance.getBoundingClientRect().bottom + window.scrollY));
    d.glanceRows = String(glance.querySelectorAll('tr').length - 1);
  }
  if (bad.length) console.error('shadowlab report: pictures that did not load: ' + bad.join(', '));
});
)JS";

}  // namespace

PrestartedCharts::~PrestartedCharts() {
  if (goFd_ >= 0) ::close(goFd_);
  if (pid_ > 0) {
    ::kill(pid_, SIGTERM);  // no need to wait for its imports to finish
    waitExit(pid_);
  }
}

int PrestartedCharts::run(const std::vector<std::string>& argv, const std::string& logPath) {
  if (pid_ <= 0 || goFd_ < 0) return -1;
  std::string message = logPath;
  for (const auto& a : argv) message += std::string(1, '\0') + a;
  message += std::string(1, '\0') + "run";
  const char* p = message.data();
  size_t left = message.size();
  bool sent = true;
  while (left > 0) {
    ssize_t n = ::send(goFd_, p, left, MSG_NOSIGNAL);  // a Python gone away is EPIPE, not SIGPIPE
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      sent = false;
      break;
    }
    p += n;
    left -= size_t(n);
  }
  ::close(goFd_);  // end of the message
  goFd_ = -1;
  const int pid = pid_;
  if (!sent) return -1;  // the destructor ends and reaps it
  pid_ = -1;
  return pid;
}

std::unique_ptr<PrestartedCharts> prestartCharts(const SweepOptions& options) {
  std::error_code ec;
  if (!options.writeResults || !options.writeReport || options.shard.active() || options.reportScript.empty() ||
      !fs::is_regular_file(options.reportScript, ec))
    return nullptr;
  int sv[2];
  if (::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, sv) != 0) return nullptr;
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, sv[1], 0);
  posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  const std::string python = chartPython(options);
  std::vector<std::string> argv = {python, "-c", kChartBootstrap};
  std::vector<char*> args;
  for (auto& a : argv) args.push_back(a.data());
  args.push_back(nullptr);
  pid_t pid = -1;
  const int rc = ::posix_spawn(&pid, python.c_str(), &actions, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  ::close(sv[1]);
  if (rc != 0) {
    ::close(sv[0]);
    return nullptr;
  }
  return std::make_unique<PrestartedCharts>(int(pid), sv[0]);
}

// The report's time axis: the method's cost, what an engine would pay (method_gpu_ms = shadow pass
// + lookup pass, compare/TIMINGS.md), not the harness's evidence resolve, readback and compare;
// GPU timestamps, so CPU scheduling noise does not reorder the front; an outside renderer's row, its
// renderer_frame_ms. A row written before the
// lookup pass existed (a resumed journal) has no method_gpu_ms: its shadow pass alone.
double methodMs(const ResultRow& r) {
  const double method = numberAt(r.timings, timing::kMethodGpuMs);
  if (std::isfinite(method)) return method;
  // An outside renderer's row (adapters/README.md): the renderer's own time for its frame.
  const double renderer = numberAt(r.timings, timing::kRendererFrameMs);
  if (std::isfinite(renderer)) return renderer;
  return numberAt(r.timings, timing::kShadowGpuMs, 0.0) + numberAt(r.timings, timing::kLookupGpuMs, 0.0);
}

namespace {
// What the rows' times are: the built-in rasterizer's method_gpu_ms, an outside renderer's own
// renderer_frame_ms (adapters/README.md), or both.
std::string timeAxisSentence(const std::vector<ResultRow>& rows) {
  size_t outside = 0;
  for (const ResultRow& r : rows)
    outside += !r.timings.contains(timing::kMethodGpuMs) && r.timings.contains(timing::kRendererFrameMs) ? 1 : 0;
  const std::string builtIn = "<code>method_gpu_ms</code> (shadow pass + lookup pass, what an engine pays)";
  const std::string renderer = "<code>renderer_frame_ms</code> (an outside renderer's own time for its frame)";
  if (outside == 0) return builtIn + ".";
  if (outside == rows.size()) return renderer + ".";
  return builtIn + " for the built-in rasterizer's rows and " + renderer + " for the adapter's.";
}

// The method's time with three significant digits, and the range of its timed repetitions when the
// row has them ("1.23 (1.2&ndash;1.31)").
std::string timeWithSpread(const ResultRow& r) {
  std::string out = sig3(methodMs(r));
  const double lo = numberAt(r.timings, timing::kMethodGpuMsMin), hi = numberAt(r.timings, timing::kMethodGpuMsMax);
  if (std::isfinite(lo) && std::isfinite(hi))
    out += " <span class=\"spread\">(" + sig3(lo) + "&ndash;" + sig3(hi) + ")</span>";
  else out += "<sup class=\"spread\" title=\"one sample: the render's own timing\">1</sup>";
  return out;
}
// Which rows carry a median and which one sample (results.json "timing", written by runSweep).
std::string timingSentence(const nlohmann::json& results) {
  const auto t = results.find("timing");
  if (t == results.end() || !t->is_object()) return "";
  const long medians = t->value("rows_with_median", 0L), single = t->value("rows_single_sample", 0L);
  const int reps = t->value("repetitions", 0);
  std::string out = std::to_string(medians) + (medians == 1 ? " row carries" : " rows carry") + " the median of " +
                    std::to_string(reps) + " timed runs of its method, its range after it: the rows near each " +
                    "scene's Pareto front, whose time decides a ranking; ";
  out += std::to_string(single) + (single == 1 ? " row carries" : " rows carry") +
         " one sample, its render's own timing (marked <sup>1</sup>).";
  if (reps == 0) out = "Every row carries one sample, its render's own timing (--timing-repetitions 0).";
  return out;
}
}  // namespace

std::string methodFamily(const nlohmann::json& method) {
  auto text = [&](const char* key, const char* fallback) {
    auto it = method.find(key);
    return it != method.end() && it->is_string() && !it->get<std::string>().empty() ? it->get<std::string>()
                                                                                    : std::string(fallback);
  };
  const std::string technique = text("technique", "");
  if (!technique.empty()) return "technique " + technique;
  return text("filter", kindKey(filterKinds(), Filter::None)) + " / " + text("fit", kindKey(fitKinds(), Fit::Sphere));
}

nlohmann::json methodFamilies(const std::vector<ResultRow>& rows) {
  // Order: the kinds tables' (filter, then fit), unknown keys after them by name, techniques last.
  auto rank = [](const nlohmann::json& method) {
    auto index = [&](const auto& kinds, const char* key, const char* fallback) {
      auto it = method.find(key);
      const std::string k = it != method.end() && it->is_string() ? it->get<std::string>() : fallback;
      for (size_t i = 0; i < kinds.size(); ++i)
        if (k == kinds[i].key) return i;
      return kinds.size();
    };
    const bool technique = method.contains("technique") && method["technique"].is_string() &&
                           !method["technique"].get<std::string>().empty();
    return std::make_tuple(technique, index(filterKinds(), "filter", "none"), index(fitKinds(), "fit", "sphere"),
                           methodFamily(method));
  };
  std::map<std::string, decltype(rank(nlohmann::json()))> seen;
  for (const auto& r : rows) {
    std::string k = methodFamily(r.method);
    if (!seen.count(k)) seen.emplace(k, rank(r.method));
  }
  std::vector<std::pair<decltype(rank(nlohmann::json())), std::string>> order;
  for (const auto& [k, v] : seen) order.emplace_back(v, k);
  std::sort(order.begin(), order.end());
  // Ten colours that stay apart in print (matplotlib's tab10, its grey made near-black so that no
  // family looks like the charts' grid), and eight marker shapes: a family is told apart by both.
  static const char* kColours[] = {"#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd",
                                   "#8c564b", "#e377c2", "#222222", "#bcbd22", "#17becf"};
  static const char* kMarkers[] = {"circle",        "square",   "triangle", "diamond",
                                   "triangle_down", "pentagon", "hexagon",  "star"};
  nlohmann::json out = nlohmann::json::array();
  for (size_t i = 0; i < order.size(); ++i)
    out.push_back({{"key", order[i].second},
                   {"label", order[i].second},
                   {"color", kColours[i % std::size(kColours)]},
                   {"marker", kMarkers[i % std::size(kMarkers)]}});
  return out;
}

bool comparedSomething(const ResultRow& r) {
  const auto marked = r.metrics.find("nothing_compared");
  if (marked != r.metrics.end() && marked->is_boolean() && marked->get<bool>()) return false;
  const double pixels = numberAt(r.metrics, "pixels_compared");
  return !(std::isfinite(pixels) && pixels == 0.0);
}

std::string defaultReportScript(const std::string& sourceDir) {
  const char* env = std::getenv("SHADOWLAB_REPORT_SCRIPT");
  if (env && *env) return env;
  return joinPath(sourceDir, "compare/report/charts.py");
}

void writeResultsCsv(const std::string& path, const std::vector<ResultRow>& rows) {
  // Columns: scene, config, light, then the union of method keys, metrics and timings, each in
  // first-seen order. Names are bare (error_rate, map.size): one name everywhere.
  std::vector<std::string> methodCols, metricCols, timingCols;
  auto addCols = [](const nlohmann::json& j, std::vector<std::string>& cols) {
    std::vector<std::pair<std::string, nlohmann::json>> flat;
    flatten(j, "", flat);
    for (const auto& [k, v] : flat)
      if (std::find(cols.begin(), cols.end(), k) == cols.end()) cols.push_back(k);
  };
  for (const auto& r : rows) {
    addCols(r.method, methodCols);
    addCols(r.metrics, metricCols);
    addCols(r.timings, timingCols);
  }
  std::ostringstream out;
  out << "scene,config,light";
  for (const auto* cols : {&methodCols, &metricCols, &timingCols})
    for (const auto& c : *cols) out << "," << csvField(c);
  out << "\n";
  for (const auto& r : rows) {
    out << csvField(r.scene) << "," << csvField(r.config) << "," << csvField(r.light);
    const nlohmann::json* sources[3] = {&r.method, &r.metrics, &r.timings};
    const std::vector<std::string>* colSets[3] = {&methodCols, &metricCols, &timingCols};
    for (int s = 0; s < 3; ++s) {
      std::vector<std::pair<std::string, nlohmann::json>> flat;
      flatten(*sources[s], "", flat);
      std::map<std::string, nlohmann::json> byName(flat.begin(), flat.end());
      for (const auto& c : *colSets[s]) {
        auto it = byName.find(c);
        out << "," << (it == byName.end() ? "" : csvField(valueText(it->second)));
      }
    }
    out << "\n";
  }
  writeFileAtomic(path, out.str());
}

std::vector<size_t> paretoFront(const std::vector<ResultRow>& rows, const std::string& scene) {
  std::vector<size_t> idx;
  for (size_t i = 0; i < rows.size(); ++i)
    if (rows[i].scene == scene && comparedSomething(rows[i]) && std::isfinite(numberAt(rows[i].metrics, "error_rate")))
      idx.push_back(i);
  std::stable_sort(idx.begin(), idx.end(), [&](size_t a, size_t b) {
    double ta = methodMs(rows[a]), tb = methodMs(rows[b]);
    if (ta != tb) return ta < tb;
    return numberAt(rows[a].metrics, "error_rate") < numberAt(rows[b].metrics, "error_rate");
  });
  std::vector<size_t> front;
  double best = INFINITY;
  for (size_t i : idx) {
    double e = numberAt(rows[i].metrics, "error_rate");
    if (e < best) {
      front.push_back(i);
      best = e;
    }
  }
  return front;
}

std::vector<std::string> writeSweepReport(const SweepPlan& plan, const std::vector<ResultRow>& rows,
                                          const nlohmann::json& results, SweepRunner& runner,
                                          const SweepOptions& options, PrestartedCharts* prestarted,
                                          SweepReportTimings* timings) {
  using Clock = std::chrono::steady_clock;
  auto secondsSince = [](Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); };
  std::vector<std::string> notes;
  const std::string figuresDir = joinPath(options.outDir, "figures");
  makeDirs(figuresDir);
  const std::string resultsPath = joinPath(options.outDir, "results.json");
  const std::string manifestPath = joinPath(figuresDir, "charts.json");

  // The chart script takes the classes (keys, metric names, labels, colours) from classes.json
  // next to results.json, so that it never holds its own copy of the class table.
  writeJsonAtomic(joinPath(options.outDir, "classes.json"), pixelClassesJson());

  // Charts, in a child process that runs while the triptychs render (the two use different
  // resources: one Python thread against lavapipe's threads). A stale manifest from an earlier
  // run must not pass for this run's charts.
  std::error_code ec;
  fs::remove(manifestPath, ec);
  nlohmann::json manifest;
  pid_t charts = -1;
  Clock::time_point chartsStart;
  std::string chartsCommand;
  const std::string logPath = joinPath(figuresDir, "charts.log");
  if (options.reportScript.empty()) {
    notes.push_back("charts skipped: no chart script configured (set SHADOWLAB_REPORT_SCRIPT)");
  } else if (!fs::is_regular_file(options.reportScript, ec)) {
    notes.push_back("charts skipped: chart script " + options.reportScript + " not found");
  } else {
    const std::string python = chartPython(options);
    chartsStart = Clock::now();
    if (prestarted) charts = prestarted->run({options.reportScript, resultsPath, figuresDir}, logPath);
    if (charts < 0) charts = spawnLogged({python, options.reportScript, resultsPath, figuresDir}, logPath);
    chartsCommand = python + " " + options.reportScript;
    if (charts < 0) notes.push_back("charts failed: cannot start " + chartsCommand + ": " + std::strerror(errno));
  }
  // Reaped on a thread of its own, so that its exit time is known while the triptychs render.
  int chartsExit = -1;
  Clock::time_point chartsEnd;
  std::thread chartsReaper;
  struct JoinOnExit {  // also on the way out through an exception
    std::thread& t;
    ~JoinOnExit() {
      if (t.joinable()) t.join();
    }
  } joinReaper{chartsReaper};
  if (charts >= 0)
    chartsReaper = std::thread([&chartsExit, &chartsEnd, charts] {
      chartsExit = waitExit(charts);
      chartsEnd = Clock::now();
    });

  // Triptychs of the best and the worst configuration of each scene, rendered again now: the
  // sweep keeps no images.
  struct Pick {
    std::string label;
    size_t row;
    std::string file;  // relative to outDir, empty when not rendered
  };
  std::map<std::string, std::vector<Pick>> picks;
  std::map<std::string, size_t> jobOfKey;  // rows need not be in plan order
  for (size_t j = 0; j < plan.jobs.size(); ++j) jobOfKey[plan.jobs[j].key()] = j;
  const Clock::time_point triptychsStart = Clock::now();
  if (options.triptychs) {
    for (size_t s = 0; s < plan.sceneNames.size(); ++s) {
      const std::string& name = plan.sceneNames[s];
      std::optional<size_t> best, worst;
      for (size_t i = 0; i < rows.size(); ++i) {
        if (rows[i].scene != name) continue;
        double e = numberAt(rows[i].metrics, "error_rate");
        if (!std::isfinite(e) || !comparedSomething(rows[i])) continue;
        // The best: the first lowest error in row order, as the runner keeps it (keepForTriptych)
        // and as the findings name it.
        if (!best || e < numberAt(rows[*best].metrics, "error_rate")) best = i;
        if (!worst || e > numberAt(rows[*worst].metrics, "error_rate")) worst = i;
      }
      if (!best) continue;
      std::vector<Pick> list{{"best", *best, ""}};
      if (*worst != *best) list.push_back({"worst", *worst, ""});
      for (auto& p : list) {
        auto found = jobOfKey.find(rows[p.row].key());
        if (found == jobOfKey.end()) {
          notes.push_back("no triptych for " + rows[p.row].key() + ": the row is not part of this sweep's plan");
          continue;
        }
        const SweepJob& job = plan.jobs[found->second];
        std::string rel = "figures/triptych_" + fileSafe(name) + "_" + p.label + ".png";
        std::string abs = joinPath(options.outDir, rel);
        fs::remove(abs, ec);
        try {
          if (runner.writeTriptych(plan.variants[job.variantIndex], plan.configs[job.configIndex].method, job.light,
                                   abs) &&
              fs::is_regular_file(abs, ec))
            p.file = rel;
        } catch (const std::exception& e) {
          notes.push_back("triptych for " + name + " (" + rows[p.row].config + ") failed: " + e.what());
        }
      }
      picks[name] = list;
    }
    if (timings) timings->triptychsWallSeconds = secondsSince(triptychsStart);
  }

  if (chartsReaper.joinable()) {
    chartsReaper.join();
    const int rc = chartsExit;
    if (timings) timings->chartsWallSeconds = std::chrono::duration<double>(chartsEnd - chartsStart).count();
    if (rc != 0)
      notes.push_back("charts failed: " + chartsCommand + " exited with " + std::to_string(rc) +
                      "; see figures/charts.log: " + tailOf(logPath, 3));
  }
  if (fs::is_regular_file(manifestPath, ec)) {
    try {
      manifest = readJsonFile(manifestPath);
    } catch (const InputError& e) {
      notes.push_back(std::string("charts unusable: ") + e.what());
      manifest = nlohmann::json();
    }
  }

  // The page: findings first (what goes wrong, what fixes it, what it costs, what fails first), then
  // the best configurations, the charts (inline SVG: a tooltip and a link to its row on every point),
  // the triptychs, the run's facts and every row.
  std::ostringstream h;
  const std::time_t now = std::time(nullptr);
  char stamp[64];
  std::strftime(stamp, sizeof stamp, "%Y-%m-%d %H:%M:%S UTC", std::gmtime(&now));
  h << "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
    << "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
    << "<title>shadowlab sweep: " << escapeMarkup(std::to_string(plan.sceneNames.size())) << " scene(s) x "
    << plan.configs.size() << " configuration(s)</title>\n<style>" << kStyle << "</style>\n</head>\n<body>\n";
  h << "<h1>shadowlab sweep report</h1>\n<p class=\"muted\">" << rows.size() << " rows: " << plan.sceneNames.size()
    << " scene(s), " << plan.configs.size() << " configuration(s)"
    << (rows.size() == plan.sceneNames.size() * plan.configs.size() ? "" : " (some grids run on named scenes only)")
    << ". Generated " << stamp
    << ". Rates are fractions of the compared pixels; times are " << timeAxisSentence(rows) << " "
    << timingSentence(results) << " Each link goes to the chart, triptych or row that shows it.</p>\n";

  // Findings (from figures/charts.json: the chart script computes them from results.json).
  const nlohmann::json findings =
      manifest.is_object() ? manifest.value("findings", nlohmann::json::array()) : nlohmann::json::array();
  h << "<h2 id=\"findings\">Findings</h2>\n";
  if (findings.empty() || !findings.is_array()) {
    h << "<p class=\"note\">No findings: the chart script did not write them (see the notes under Charts).</p>\n";
  } else {
    auto pieces = [&](const nlohmann::json& sentences) {
      std::string out;
      if (!sentences.is_array()) return out;
      for (const auto& sentence : sentences) {
        if (!sentence.is_array()) continue;
        out += out.empty() ? "" : " ";
        for (const auto& p : sentence) {
          const std::string text = p.value("text", std::string());
          const std::string href = p.value("href", std::string());
          // Only links inside the page: a finding names a chart panel, triptych or row.
          if (!href.empty() && href[0] == '#')
            out += "<a href=\"" + escapeMarkup(href) + "\">" + breakable(text) + "</a>";
          else out += breakable(text);
        }
      }
      return out;
    };
    // At a glance: one short sentence per scene and question, so that every scene fits the first
    // screen; the table after it says the same at length.
    std::ostringstream glance;
    for (const auto& f : findings) {
      const nlohmann::json g = f.value("glance", nlohmann::json::object());
      if (!g.is_object() || g.empty()) continue;
      glance << "<tr><td class=\"t\"><a href=\"#finding-" << escapeMarkup(f.value("scene", std::string())) << "\">"
             << breakable(f.value("scene", std::string())) << "</a></td>";
      for (const char* k : {"wrong", "fixes", "costs", "fails"})
        glance << "<td class=\"t\">" << pieces(nlohmann::json::array({g.value(k, nlohmann::json::array())}))
               << "</td>";
      glance << "</tr>\n";
    }
    if (!glance.str().empty()) {
      h << "<table class=\"glance\" id=\"glance\">\n<tr><th class=\"t\">scene</th><th class=\"t\">what goes "
           "wrong (share of the errors)</th><th class=\"t\">what fixes it (lowest error_rate)</th><th "
           "class=\"t\">what it costs (cheapest within 2x of that error)</th><th class=\"t\">what fails "
           "first</th></tr>\n"
        << glance.str() << "</table>\n<h3>In detail</h3>\n";
    }
    h << "<table class=\"findings\">\n<tr><th class=\"t\">scene</th><th class=\"t\">what goes wrong</th>"
         "<th class=\"t\">what fixes it</th><th class=\"t\">what it costs</th><th class=\"t\">what fails "
         "first</th></tr>\n";
    for (const auto& f : findings) {
      h << "<tr id=\"finding-" << escapeMarkup(f.value("scene", std::string())) << "\"><td class=\"t\">"
        << breakable(f.value("scene", std::string())) << "</td>";
      for (const char* k : {"wrong", "fixes", "costs", "fails"})
        h << "<td class=\"t\">" << pieces(f.value(k, nlohmann::json::array())) << "</td>";
      h << "</tr>\n";
    }
    h << "</table>\n";
  }

  // Summary: the Pareto front per scene.
  h << "<h2>Best configurations per scene</h2>\n<p>For each scene, the configurations on the Pareto front of the "
       "method's time (<code>method_gpu_ms</code> = <code>shadow_gpu_ms</code> + <code>lookup_gpu_ms</code>: the "
       "shadow pass and a lookup pass that computes only the method's visibility, what an engine would pay) against "
       "<code>error_rate</code>: each row is the lowest error reachable within its time budget; every configuration "
       "not listed is slower, less accurate, or both. # is the point's number on the accuracy chart; the time is "
       "the median of the timed repetitions, their range after it (<sup>1</sup>: one sample). Rows that compared "
       "no pixel are not ranked.</p>\n";
  for (const auto& name : plan.sceneNames) {
    auto front = paretoFront(rows, name);
    h << "<h3>" << escapeMarkup(name) << "</h3>\n";
    if (front.empty()) {
      h << "<p class=\"note\">No row with an error rate.</p>\n";
      continue;
    }
    std::vector<const ResultRow*> frontRows;
    for (size_t i : front) frontRows.push_back(&rows[i]);
    std::vector<const char*> hidden;
    const std::vector<const char*> columns = classColumns(frontRows, &hidden);
    h << hiddenColumnsNote(hidden);
    h << "<table>\n<tr><th>#</th><th>time budget (method_gpu_ms)</th><th "
         "class=\"t\">configuration</th><th>error_rate</th>"
      << headerCells(columns) << "<th>m_p95 (px)</th><th>harness: camera_gpu_ms</th>"
      << headerCells({timing::kReadbackMs, timing::kCompareMs}) << "</tr>\n";
    int n = 0;
    for (size_t i : front) {
      const ResultRow& r = rows[i];
      h << "<tr><td>" << ++n << "</td><td>&le; " << timeWithSpread(r) << "</td><td class=\"t\"><a href=\"#row-" << i
        << "\">" << breakable(r.config) << "</a></td><td>" << pctCell(numberAt(r.metrics, "error_rate")) << "</td>";
      for (const char* k : columns) h << "<td>" << pctCell(numberAt(r.metrics, k)) << "</td>";
      h << "<td>" << sig3(numberAt(r.metrics, "m_p95")) << "</td>";
      for (const char* k : {timing::kCameraGpuMs, timing::kReadbackMs, timing::kCompareMs})
        h << "<td>" << sig3(numberAt(r.timings, k)) << "</td>";
      h << "</tr>\n";
    }
    h << "</table>\n";
  }

  // Failure frontiers (only when a scene: parameter is swept).
  const nlohmann::json frontiers = results.value("frontiers", nlohmann::json::array());
  if (frontiers.is_array() && !frontiers.empty()) {
    const nlohmann::json fr =
        results.value("sweep", nlohmann::json::object()).value("frontier", nlohmann::json::object());
    h << "<h2>Failure frontiers</h2>\n<p>For each scene parameter swept with <code>scene:</code> and each method "
         "configuration, the values walked from easy to hard (the direction of the scene's declared "
         "<code>failure</code> values; the grid's order for other parameters) and the first value where <code>"
      << escapeMarkup(fr.value("metric", std::string("error_rate"))) << "</code> exceeds "
      << pctCell(fr.value("threshold", 0.01))
      << ".</p>\n<table>\n<tr><th class=\"t\">scene</th><th class=\"t\">parameter</th>"
         "<th class=\"t\">method</th><th>holds to</th><th>breaks at</th><th class=\"t\">frontier</th></tr>\n";
    for (const auto& f : frontiers) {
      auto val = [](const nlohmann::json& v) {
        return v.is_null() ? std::string("&ndash;") : escapeMarkup(canonicalValueText(v));
      };
      h << "<tr><td class=\"t\">" << breakable(f.value("scene", std::string())) << "</td><td class=\"t\">"
        << breakable(f.value("parameter", std::string())) << "</td><td class=\"t\">"
        << breakable(f.value("method", std::string())) << "</td><td>" << val(f.value("holds_to", nlohmann::json()))
        << "</td><td>" << val(f.value("breaks_at", nlohmann::json())) << "</td><td class=\"t\">"
        << escapeMarkup(f.value("sentence", std::string())) << "</td></tr>\n";
    }
    h << "</table>\n";
  }

  // Charts: each SVG inline (its points' tooltips and links work in the page), its PDF for print.
  h << "<h2>Charts</h2>\n";
  for (const auto& n : notes)
    if (n.rfind("charts", 0) == 0) h << "<p class=\"note\">" << escapeMarkup(n) << "</p>\n";
  if (manifest.is_object()) {
    for (const auto& c : manifest.value("charts", nlohmann::json::array())) {
      const std::string id = c.value("id", std::string());
      const std::string svgFile = c.value("svg", std::string());
      std::string svg;
      // Only a file the script wrote into figures/, read from there (never a path outside it).
      if (svgFile.rfind("figures/", 0) == 0 && svgFile.find("..") == std::string::npos) {
        try {
          svg = readFile(joinPath(options.outDir, svgFile));
        } catch (const std::exception&) {
        }
      }
      h << "<figure class=\"chart\" id=\"" << escapeMarkup(id) << "\">\n<h3>"
        << escapeMarkup(c.value("title", std::string())) << "</h3>\n";
      if (svg.rfind("<svg", 0) == 0) h << svg;
      else  // an <img> that cannot load: the page's check reports it
        h << "<img src=\"" << escapeMarkup(svgFile) << "\" alt=\"" << escapeMarkup(c.value("title", std::string()))
          << " (missing)\">\n";
      h << "<figcaption>" << escapeMarkup(c.value("caption", std::string()));
      std::string links;
      for (const char* kind : {"pdf", "svg"}) {
        std::string f = c.value(kind, std::string());
        if (!f.empty())
          links += std::string(links.empty() ? "" : ", ") + "<a href=\"" + escapeMarkup(f) + "\">" + kind + "</a>";
      }
      if (!links.empty()) h << " For print: " << links << ".";
      h << "</figcaption>\n</figure>\n";
    }
    for (const auto& s : manifest.value("skipped", nlohmann::json::array())) {
      std::string text =
          "Chart \"" + s.value("title", std::string()) + "\" skipped: " + s.value("reason", std::string());
      notes.push_back(text);
      h << "<p class=\"note\">" << escapeMarkup(text) << "</p>\n";
    }
  }

  // Triptychs.
  h << "<h2>Best and worst configuration of each scene</h2>\n<p>Reference (Embree) | raster | errors, rendered again "
       "for this report. Error colours are explained by the legend drawn into the errors panel.</p>\n";
  if (!options.triptychs) h << "<p class=\"note\">Triptychs were not rendered for this report.</p>\n";
  for (const auto& name : plan.sceneNames) {
    auto it = picks.find(name);
    if (it == picks.end()) continue;
    for (const auto& p : it->second) {
      const ResultRow& r = rows[p.row];
      h << "<figure id=\"triptych-" << escapeMarkup(name) << "-" << p.label << "\">\n<h3>" << escapeMarkup(name) << ": "
        << p.label << " (<a href=\"#row-" << p.row << "\">" << breakable(r.config) << "</a>)</h3>\n";
      if (p.file.empty()) {
        h << "<p class=\"note\">No triptych: this sweep's runner makes no pictures, or rendering it failed (see the "
             "notes).</p>\n";
      } else {
        h << "<img src=\"" << escapeMarkup(p.file) << "\" alt=\"" << escapeMarkup(name + " " + p.label + " triptych")
          << "\">\n";
      }
      std::string byClass;
      for (const PixelClassInfo& c : kPixelClasses)
        if (c.error && c.rateMetric)
          byClass +=
              (byClass.empty() ? "" : ", ") + std::string(c.key) + " " + pctCell(numberAt(r.metrics, c.rateMetric));
      h << "<figcaption>error_rate " << pctCell(numberAt(r.metrics, "error_rate")) << " (" << escapeMarkup(byClass)
        << "); method " << sig3(methodMs(r)) << " ms (method_gpu_ms).</figcaption>\n</figure>\n";
    }
  }

  // Run facts.
  h << "<h2>Run</h2>\n";
  const nlohmann::json machine = results.value("machine", nlohmann::json::object());
  const nlohmann::json runInfo = results.value("runner", nlohmann::json::object());
  h << "<table>\n";
  auto fact = [&](const std::string& k, const std::string& v) {
    h << "<tr><th class=\"t\">" << escapeMarkup(k) << "</th><td class=\"t\">" << v << "</td></tr>\n";
  };
  fact("machine", escapeMarkup(machine.value("cpu", std::string("?")) + ", " +
                               std::to_string(machine.value("hardware_threads", 0)) + " threads, " +
                               machine.value("os", std::string("?"))));
  if (runInfo.contains("device") && runInfo["device"].is_string())
    fact("raster device", escapeMarkup(runInfo["device"].get<std::string>()));
  if (runInfo.contains("reference_cache") && runInfo["reference_cache"].is_string())
    fact("reference cache", breakable(runInfo["reference_cache"].get<std::string>()) + " (" +
                                std::to_string(runInfo.value("references_traced", 0)) + " traced, " +
                                std::to_string(runInfo.value("references_loaded", 0)) + " loaded)");
  fact("rows run / resumed",
       std::to_string(results.value("rows_run", 0)) + " / " + std::to_string(results.value("rows_resumed", 0)));
  const double sweepSeconds = results.value("loop_wall_seconds", 0.0);
  const size_t ran = results.value("rows_run", size_t(0));
  fact("configuration loop", fmt(sweepSeconds, "%.3g") + " s" +
                                 (ran ? " (" + fmt(sweepSeconds / double(ran) * 1000.0, "%.3g") + " ms per row)" : ""));
  fact("outputs",
       "<a href=\"results.json\">results.json</a>, <a href=\"results.csv\">results.csv</a>, "
       "<a href=\"rows.jsonl\">rows.jsonl</a>, <a href=\"classes.json\">classes.json</a>");
  h << "</table>\n";

  // Scenes.
  h << "<h2>Scenes</h2>\n<table>\n<tr><th class=\"t\">scene</th><th class=\"t\">file</th><th>triangles</th>"
       "<th>camera</th><th class=\"t\">light</th><th class=\"t\">scene hash</th></tr>\n";
  for (size_t s = 0; s < plan.sceneNames.size(); ++s) {
    const Scene* scene = nullptr;
    std::string light;
    for (const auto& job : plan.jobs)
      if (job.sceneIndex == s) {
        scene = &plan.variants[job.variantIndex];
        light = job.light;
        break;
      }
    if (!scene) continue;
    h << "<tr><td class=\"t\">" << breakable(plan.sceneNames[s]) << "</td><td class=\"t\">"
      << breakable(plan.scenePaths[s]) << "</td><td>" << scene->triangleCount() << "</td><td>" << scene->camera.width
      << "&times;" << scene->camera.height << "</td><td class=\"t\">" << escapeMarkup(light) << "</td><td class=\"t\">"
      << breakable(scene->hash.substr(0, 16)) << "</td></tr>\n";
  }
  h << "</table>\n";

  // Grid.
  h << "<h2>Grid</h2>\n";
  if (plan.spec.grid.empty()) {
    h << "<p>Nothing swept: one configuration (<code>default</code>) per scene.</p>\n";
  } else {
    h << "<table>\n<tr><th class=\"t\">key</th><th class=\"t\">values</th></tr>\n";
    const nlohmann::json grid = results.value("sweep", nlohmann::json::object()).value("grid", nlohmann::json::array());
    for (const auto& axis : grid) {
      std::string values;
      for (const auto& v : axis.value("values", nlohmann::json::array()))
        values += (values.empty() ? "" : ", ") + valueText(v);
      h << "<tr><td class=\"t\">" << escapeMarkup(axis.value("key", std::string())) << "</td><td class=\"t\">"
        << escapeMarkup(values) << "</td></tr>\n";
    }
    h << "</table>\n";
  }
  if (!plan.spec.fixed.empty() || !plan.spec.methodFile.empty()) {
    h << "<p>Fixed for every configuration:";
    if (!plan.spec.methodFile.empty()) h << " method file <code>" << escapeMarkup(plan.spec.methodFile) << "</code>";
    for (const auto& s : plan.spec.fixed)
      h << " <code>" << escapeMarkup(s.key + "=" + canonicalValueText(s.value)) << "</code>";
    h << "</p>\n";
  }
  h << "<p class=\"muted\">Every other method key keeps its default (raster/METHODS.md). Each row's full method is in "
       "results.json.</p>\n";

  // Every row (its anchor row-<index in results.json>: the charts' points and the findings link here).
  std::vector<const ResultRow*> allRows;
  for (const ResultRow& r : rows) allRows.push_back(&r);
  std::vector<const char*> hiddenAll;
  const std::vector<const char*> allColumns = classColumns(allRows, &hiddenAll);
  h << "<h2>All rows</h2>\n<details id=\"all-rows\">\n<summary>" << rows.size()
    << " rows (every column in results.csv)</summary>\n"
    << hiddenColumnsNote(hiddenAll) << "<table class=\"rows\">\n"
    << "<tr><th class=\"t\">scene</th><th class=\"t\">configuration</th><th class=\"t\">family</th><th>error_rate</th>"
    << headerCells(allColumns) << "<th>m_p95</th><th>method_gpu_ms</th>"
    << headerCells({timing::kCameraGpuMs, timing::kReadbackMs, timing::kCompareMs, timing::kConfigWallMs}) << "</tr>\n";
  for (size_t i = 0; i < rows.size(); ++i) {
    const ResultRow& r = rows[i];
    h << "<tr id=\"row-" << i << "\"" << (comparedSomething(r) ? "" : " class=\"empty\"") << "><td class=\"t\">"
      << breakable(r.scene) << "</td><td class=\"t\">" << breakable(r.config) << "</td><td class=\"t\">"
      << breakable(methodFamily(r.method)) << "</td>";
    h << "<td>" << pctCell(numberAt(r.metrics, "error_rate")) << "</td>";
    for (const char* k : allColumns) h << "<td>" << pctCell(numberAt(r.metrics, k)) << "</td>";
    h << "<td>" << sig3(numberAt(r.metrics, "m_p95")) << "</td><td>" << timeWithSpread(r) << "</td>";
    for (const char* k : {timing::kCameraGpuMs, timing::kReadbackMs, timing::kCompareMs, timing::kConfigWallMs})
      h << "<td>" << sig3(numberAt(r.timings, k)) << "</td>";
    h << "</tr>\n";
  }
  h << "</table>\n</details>\n";

  std::vector<std::string> otherNotes;
  for (const auto& n : notes)
    if (n.rfind("charts", 0) != 0 && n.rfind("Chart ", 0) != 0) otherNotes.push_back(n);
  if (!otherNotes.empty()) {
    h << "<h2>Notes</h2>\n";
    for (const auto& n : otherNotes) h << "<p class=\"note\">" << escapeMarkup(n) << "</p>\n";
  }
  h << "<script>" << kImageCheck << "</script>\n</body>\n</html>\n";
  writeFileAtomic(joinPath(options.outDir, "report.html"), h.str());
  return notes;
}

}  // namespace shadowlab
