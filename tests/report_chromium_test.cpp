// report.html in a real browser: a small real sweep (through the binary) writes its report, headless
// Chromium opens it from disk with the network machinery off, and the page must load every
// picture (the page's own check sets body[data-images-ok]) without a console message. The same
// check must catch a report with a missing figure. Skips loudly when Chromium is not installed.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <thread>

#include "shadowlab/compare/sweep.h"
#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/frame.h"
#include "shadowlab/scenes/io.h"

namespace report_chromium_test {

namespace fs = std::filesystem;
using namespace shadowlab;

namespace {

const char* kChromium = "/usr/bin/chromium";

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Runs argv with stdout/stderr to files; exit status, or -1 after killing it on timeout.
int runCommand(const std::vector<std::string>& args, const std::string& outPath, const std::string& errPath,
               double timeoutS = 120) {
  pid_t pid = ::fork();
  if (pid == 0) {
    if (!std::freopen(outPath.c_str(), "w", stdout) || !std::freopen(errPath.c_str(), "w", stderr)) ::_exit(126);
    ::setpgid(0, 0);  // chromium forks helpers: a timeout kills the whole group
    std::vector<char*> argv;
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  auto t0 = std::chrono::steady_clock::now();
  int status = 0;
  while (::waitpid(pid, &status, WNOHANG) != pid) {
    if (std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() > timeoutS) {
      ::kill(-pid, SIGKILL);
      ::waitpid(pid, &status, 0);
      return -1;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

struct PageCheck {
  int rc = 0;
  std::string imagesOk;  // body data-images-ok
  int imagesCount = -1;  // body data-images-count
  int figures = -1;      // body data-figures: inline SVG charts laid out
  int tooltips = -1;     // body data-tooltips: <title>s in them
  int overflow = -1;     // body data-overflow: px the page is wider than the window
  int wrappedNumbers = -1;  // body data-wrapped-numbers: number cells laid out on more than one line
  std::vector<std::string> consoleLines;
  std::string dom, log;
};

std::vector<std::string> chromiumArgs(const std::string& profile) {
  return {kChromium,
          "--headless",
          "--no-sandbox",
          "--disable-gpu",
          "--disable-background-networking",
          "--disable-component-update",
          "--disable-sync",
          "--no-first-run",
          "--disable-default-apps",
          "--user-data-dir=" + profile,
          "--enable-logging=stderr",
          "--v=0",
          "--virtual-time-budget=10000"};
}

PageCheck openInChromium(const std::string& html, const std::string& work,
                         const std::string& windowSize = "1280,1000") {
  PageCheck c;
  fs::create_directories(work);
  auto args = chromiumArgs(work + "/profile");
  args.push_back("--window-size=" + windowSize);
  args.push_back("--dump-dom");
  args.push_back("file://" + fs::absolute(html).string());
  c.rc = runCommand(args, work + "/dom.html", work + "/chromium.log");
  c.dom = slurp(work + "/dom.html");
  c.log = slurp(work + "/chromium.log");
  std::smatch m;
  static const std::regex ok(R"re(<body[^>]*data-images-ok="([a-z]+)")re");
  static const std::regex count(R"re(<body[^>]*data-images-count="([0-9]+)")re");
  if (std::regex_search(c.dom, m, ok)) c.imagesOk = m[1];
  if (std::regex_search(c.dom, m, count)) c.imagesCount = std::stoi(m[1]);
  static const std::regex figures(R"re(<body[^>]*data-figures="([0-9]+)")re");
  static const std::regex tooltips(R"re(<body[^>]*data-tooltips="([0-9]+)")re");
  static const std::regex overflow(R"re(<body[^>]*data-overflow="([0-9]+)")re");
  if (std::regex_search(c.dom, m, figures)) c.figures = std::stoi(m[1]);
  if (std::regex_search(c.dom, m, tooltips)) c.tooltips = std::stoi(m[1]);
  if (std::regex_search(c.dom, m, overflow)) c.overflow = std::stoi(m[1]);
  static const std::regex wrapped(R"re(<body[^>]*data-wrapped-numbers="([0-9]+)")re");
  if (std::regex_search(c.dom, m, wrapped)) c.wrappedNumbers = std::stoi(m[1]);
  // Console messages (console.error, uncaught exceptions, failed loads reported by the page)
  // appear as "...:INFO:CONSOLE..." lines; the report itself logs nothing when all is well.
  std::istringstream lines(c.log);
  std::string line;
  while (std::getline(lines, line))
    if (line.find(":CONSOLE") != std::string::npos) c.consoleLines.push_back(line);
  return c;
}

std::string tempDir(const std::string& name) {
  fs::path d = fs::temp_directory_path() / ("shadowlab_report_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d.string();
}

}  // namespace

// A fake runner (no renderer): the report machinery alone, on a grid without map.size or bias.
class FakeRunner : public SweepRunner {
 public:
  SweepRunOutput run(const Scene&, const Method& m, const std::string&, const std::string&) override {
    SweepRunOutput out;
    double e = (m.filter == Filter::None ? 0.02 : 0.01) + 0.001 * m.biasSlope + 1.0 / m.mapSize;
    out.metrics = {{"error_rate", e},      {"acne_rate", e / 2}, {"leak_rate", e / 4}, {"aliasing_rate", e / 4},
                   {"coverage_rate", 0.0}, {"m_median", 2.0},    {"m_p95", 5.0},       {"m_max", 40.0}};
    const double shadow = m.filter == Filter::None ? 5.0 : 6.0;
    out.timings = {{"shadow_gpu_ms", shadow}, {"lookup_gpu_ms", 1.0},     {"method_gpu_ms", shadow + 1.0},
                   {"camera_gpu_ms", 10.0},   {"visibility_gpu_ms", 2.0}, {"readback_ms", 3.0},
                   {"compare_ms", 1.0},       {"config_wall_ms", 25.0}};
    return out;
  }
  // A small picture stands in for reference | raster | errors when asked for one.
  bool writeTriptych(const Scene&, const Method&, const std::string&, const std::string& path) override {
    if (failTriptychs) throw DriverError("deliberate triptych failure");
    if (!pictures) return false;
    writeRgbPng(path, 12, 4, std::vector<uint8_t>(12 * 4 * 3, 200));
    return true;
  }
  bool pictures = false;
  bool failTriptychs = false;
};

TEST(ReportChromium, RealSweepReportLoadsEveryPictureWithoutConsoleErrors) {
  if (!fs::exists(kChromium))
    GTEST_SKIP() << "SKIPPED LOUDLY: " << kChromium << " is not installed (apt-get install chromium)";
  const std::string dir = tempDir("real");
  const std::string out = dir + "/sweep";
  // Two sizes x two biases at a quarter of the scene's pixels: every chart has its key.
  int rc = runCommand(
      {SHADOWLAB_BINARY, "sweep", "sphere_on_plane", "--grid", "map.size=256,1024", "--grid", "bias.slope=0,2", "--set",
       "scene:/camera/width=480", "--set", "scene:/camera/height=270", "-o", out, "--cache", dir + "/cache"},
      dir + "/sweep.out", dir + "/sweep.err");
  if (rc == 3) {
    // No Vulkan device: the browser check still runs, on the same grid through a fake runner.
    std::fprintf(stderr,
                 "report_chromium_test: NO VULKAN DEVICE (shadowlab exit 3), checking a report made with a "
                 "fake runner instead:\n%s\n",
                 slurp(dir + "/sweep.err").c_str());
    SweepSpec spec;
    spec.scenes = {"sphere_on_plane"};
    spec.grid = {parseGridArgument("map.size=256,1024"), parseGridArgument("bias.slope=0,2")};
    FakeRunner fake;
    fake.pictures = true;
    SweepOptions o;
    o.outDir = out;
    o.progress = nullptr;
    o.reportScript = defaultReportScript(SHADOWLAB_SOURCE_DIR);
    fs::remove_all(out);
    runSweep(planSweep(spec), fake, o);
    std::ofstream(dir + "/sweep.out") << "report: " << fs::absolute(out + "/report.html").string() << "\n";
    rc = 0;
  }
  ASSERT_EQ(rc, 0) << slurp(dir + "/sweep.err");
  EXPECT_NE(slurp(dir + "/sweep.out").find("report: " + fs::absolute(out + "/report.html").string()), std::string::npos)
      << "the sweep prints where the report is: " << slurp(dir + "/sweep.out");

  // The charts, as SVG (inline in the page) and PDF (for print), and both triptychs.
  for (const char* chart :
       {"accuracy_vs_time", "class_mix", "bias_bias_slope", "error_by_size", "time_breakdown", "m_footprint"})
    for (const char* ext : {"svg", "pdf"}) {
      std::string f = out + "/figures/" + chart + "." + ext;
      EXPECT_TRUE(fs::is_regular_file(f)) << f << "\n" << slurp(out + "/figures/charts.log");
    }
  EXPECT_TRUE(fs::is_regular_file(out + "/figures/triptych_sphere_on_plane_best.png"));
  EXPECT_TRUE(fs::is_regular_file(out + "/figures/triptych_sphere_on_plane_worst.png"));
  // Every row names its family, and results.json carries the families' table (one colour and
  // marker each): filter none and the fit the grid keeps (sphere).
  {
    const nlohmann::json results = nlohmann::json::parse(slurp(out + "/results.json"));
    ASSERT_EQ(results["families"].size(), 1u) << results["families"].dump();
    EXPECT_EQ(results["families"][0]["key"], "none / sphere");
    EXPECT_EQ(results["families"][0]["marker"], "circle");
    for (const auto& r : results["rows"]) EXPECT_EQ(r["family"], "none / sphere") << r.dump();
  }

  // Self-contained: nothing fetched from a network.
  const std::string html = slurp(out + "/report.html");
  EXPECT_EQ(html.find("src=\"http"), std::string::npos);
  EXPECT_EQ(html.find("href=\"http"), std::string::npos);
  EXPECT_EQ(html.find("<link"), std::string::npos);
  EXPECT_EQ(html.find("@import"), std::string::npos);
  EXPECT_EQ(html.find("url("), std::string::npos);
  // Findings first, then the summary, the grid and the charts.
  const size_t findings = html.find("<h2 id=\"findings\">Findings</h2>");
  ASSERT_NE(findings, std::string::npos);
  EXPECT_LT(findings, html.find("Best configurations per scene"));
  EXPECT_NE(html.find("what goes wrong"), std::string::npos);
  EXPECT_NE(html.find("href=\"#triptych-sphere_on_plane-best\""), std::string::npos);
  EXPECT_NE(html.find("id=\"triptych-sphere_on_plane-best\""), std::string::npos);
  EXPECT_NE(html.find("bias.slope=<wbr>2,<wbr>map.size=<wbr>1024"), std::string::npos);
  EXPECT_NE(html.find("Pareto front"), std::string::npos);
  // Every chart point's link leads to a row of the page.
  {
    std::smatch m;
    std::string rest = html;
    int links = 0;
    static const std::regex rowLink("href=\"#(row-[0-9]+)\"");
    while (std::regex_search(rest, m, rowLink)) {
      EXPECT_NE(html.find("id=\"" + m[1].str() + "\""), std::string::npos) << m[1];
      rest = m.suffix();
      ++links;
    }
    EXPECT_GT(links, 8);
  }

  // At 1400 and 900 px: every picture loads, the 6 charts lay out with their tooltips, and nothing
  // is wider than the window.
  for (const char* width : {"1400", "900"}) {
    PageCheck page = openInChromium(out + "/report.html", dir + "/chromium" + width, std::string(width) + ",1000");
    ASSERT_EQ(page.rc, 0) << page.log;
    EXPECT_EQ(page.imagesOk, "true") << width << ": a picture did not load; chromium log:\n" << page.log;
    EXPECT_EQ(page.imagesCount, 2) << "2 triptychs (the charts are inline SVG)";
    EXPECT_EQ(page.figures, 6) << width;
    EXPECT_GT(page.tooltips, 8) << width;
    EXPECT_EQ(page.overflow, 0) << width << " px: the page is wider than the window";
    EXPECT_EQ(page.wrappedNumbers, 0) << width << " px: a number broke across lines";
    EXPECT_TRUE(page.consoleLines.empty()) << "console messages:\n" << page.consoleLines.front();
  }
  // Class columns that are 0 % in every row of a table are left out, named once above it. The
  // table of every row (the fronts depend on the timings; the rows' metrics do not): bias.slope 0
  // has acne, filter none no bleed and the camera sees only what the map covers.
  {
    const size_t all = html.find("<h2>All rows</h2>");
    const size_t note = html.find("0 % in every row, not shown: ", all);
    ASSERT_NE(note, std::string::npos) << "filter none on sphere_on_plane has no bleed or coverage error";
    const std::string names = html.substr(note, html.find("</p>", note) - note);
    const size_t tableEnd = html.find("</table>", note);
    const std::string table = html.substr(note, tableEnd - note);
    for (const char* k : {"bleed_rate", "coverage_rate"}) {
      EXPECT_NE(names.find(std::string("<code>") + k + "</code>"), std::string::npos) << k << " in " << names;
      std::string header = "<th>";
      for (char ch : std::string(k)) header += ch == '_' ? std::string("_<wbr>") : std::string(1, ch);
      EXPECT_EQ(table.find(header + "</th>"), std::string::npos) << k << " is all 0 % yet shown";
    }
    EXPECT_NE(table.find("<th>acne_<wbr>rate</th>"), std::string::npos) << "a column with errors is shown";
  }

  // A screenshot renders (proof the page lays out, and an artifact to look at when it fails).
  auto shot = chromiumArgs(dir + "/chromium/profile2");
  shot.push_back("--window-size=1280,3000");
  shot.push_back("--screenshot=" + dir + "/report.png");
  shot.push_back("file://" + fs::absolute(out + "/report.html").string());
  ASSERT_EQ(runCommand(shot, dir + "/shot.out", dir + "/shot.err"), 0) << slurp(dir + "/shot.err");
  const std::string png = slurp(dir + "/report.png");
  ASSERT_GT(png.size(), 10000u);
  EXPECT_EQ(png.substr(1, 3), "PNG");

  // The deliberate failures: a report with a triptych removed, and one with a table wider than
  // 900 px, must be caught.
  fs::remove(out + "/figures/triptych_sphere_on_plane_worst.png");
  PageCheck broken = openInChromium(out + "/report.html", dir + "/chromium_broken");
  EXPECT_EQ(broken.imagesOk, "false") << "a missing figure must be detected";
  ASSERT_FALSE(broken.consoleLines.empty()) << "the page reports the missing picture on the console";
  EXPECT_NE(broken.consoleLines.front().find("triptych_sphere_on_plane_worst.png"), std::string::npos)
      << broken.consoleLines.front();
  std::string wide = html;
  wide.replace(wide.find("<h2 id=\"findings\">"), 0,
               "<table><tr><td style=\"white-space:nowrap\">" + std::string(300, 'W') + "</td></tr></table>");
  std::ofstream(out + "/wide.html") << wide;
  PageCheck overflowing = openInChromium(out + "/wide.html", dir + "/chromium_wide", "900,1000");
  EXPECT_GT(overflowing.overflow, 0) << "a table wider than the window must be detected";
  std::string narrow = html;
  narrow.replace(narrow.find("<h2 id=\"findings\">"), 0,
                 "<table><tr><td style=\"white-space:normal;width:2em;max-width:2em\">0.048 / 5%</td></tr></table>");
  std::ofstream(out + "/narrow.html") << narrow;
  PageCheck wrapping = openInChromium(out + "/narrow.html", dir + "/chromium_narrow", "1400,1000");
  EXPECT_GT(wrapping.wrappedNumbers, 0) << "a number broken across lines must be detected";
  fs::remove_all(dir);
}

// The findings' first table answers every bundled scene on the first screen (1400 x 900): one
// row per scene, its bottom above the window's. The configurations are as long as the main job's.
TEST(ReportChromium, FindingsAtAGlanceFitTheFirstScreenForEveryBundledScene) {
  if (!fs::exists(kChromium))
    GTEST_SKIP() << "SKIPPED LOUDLY: " << kChromium << " is not installed (apt-get install chromium)";
  const std::string dir = tempDir("glance");
  SweepSpec spec;  // no scenes: every bundled scene
  spec.grid = {parseGridArgument("map.size=512,1024"), parseGridArgument("bias.slope=0,2"),
               parseGridArgument("filter=none,pcf"), parseGridArgument("fit=sphere,psm")};
  SweepPlan plan = planSweep(spec);
  ASSERT_GE(plan.sceneNames.size(), 10u);
  FakeRunner fake;
  SweepOptions o;
  o.outDir = dir + "/sweep";
  o.progress = nullptr;
  o.reportScript = defaultReportScript(SHADOWLAB_SOURCE_DIR);
  SweepSummary s = runSweep(plan, fake, o);
  ASSERT_EQ(s.reportHtml, o.outDir + "/report.html");
  const std::string html = slurp(s.reportHtml);
  ASSERT_NE(html.find("<table class=\"glance\""), std::string::npos) << slurp(o.outDir + "/figures/charts.log");
  // Each glance row links to its scene's detailed finding.
  for (const auto& name : plan.sceneNames)
    EXPECT_NE(html.find("href=\"#finding-" + name + "\""), std::string::npos) << name;
  PageCheck page = openInChromium(s.reportHtml, dir + "/chromium", "1400,900");
  ASSERT_EQ(page.rc, 0) << page.log;
  std::smatch m;
  static const std::regex rowsAttr(R"re(<body[^>]*data-glance-rows="([0-9]+)")re");
  static const std::regex bottomAttr(R"re(<body[^>]*data-glance-bottom="([0-9]+)")re");
  ASSERT_TRUE(std::regex_search(page.dom, m, rowsAttr)) << "the page measures the glance table";
  EXPECT_EQ(size_t(std::stoi(m[1])), plan.sceneNames.size());
  ASSERT_TRUE(std::regex_search(page.dom, m, bottomAttr));
  const int bottom = std::stoi(m[1]);
  EXPECT_LE(bottom, 900) << "the glance table ends below the first screen";
  std::fprintf(stderr, "glance table: %zu scenes, bottom at %d px of 900\n", plan.sceneNames.size(), bottom);
  fs::remove_all(dir);
}

TEST(ReportChromium, ChartsWhoseKeyIsNotSweptAreSkippedWithANote) {
  const std::string dir = tempDir("skip");
  SweepSpec spec;
  spec.scenes = {"sphere_on_plane"};
  spec.grid.push_back(parseGridArgument("filter=none,hw2x2"));
  SweepPlan plan = planSweep(spec);
  FakeRunner runner;
  SweepOptions o;
  o.outDir = dir + "/sweep";
  o.progress = nullptr;
  o.reportScript = defaultReportScript(SHADOWLAB_SOURCE_DIR);
  SweepSummary s = runSweep(plan, runner, o);
  ASSERT_EQ(s.reportHtml, o.outDir + "/report.html");
  const std::string html = slurp(s.reportHtml);
  EXPECT_NE(html.find("skipped: map.size is not in the grid"), std::string::npos)
      << slurp(o.outDir + "/figures/charts.log");
  EXPECT_NE(html.find("skipped: no bias key"), std::string::npos);
  // The charts that need no particular key are made.
  EXPECT_TRUE(fs::is_regular_file(o.outDir + "/figures/accuracy_vs_time.svg"))
      << slurp(o.outDir + "/figures/charts.log");
  EXPECT_TRUE(fs::is_regular_file(o.outDir + "/figures/m_footprint.svg"));
  EXPECT_FALSE(fs::exists(o.outDir + "/figures/error_by_size.svg"));
  // Pareto table by the method's time (method_gpu_ms), not shadow + camera (15 and 16 ms): hw2x2
  // (7 ms, 1%) beats none (6 ms, 2%) only at the larger budget: both listed, numbered as on the chart.
  // The fake runner cannot time a row again: each time is marked as its row's single sample.
  const std::string single = "<sup class=\"spread\" title=\"one sample: the render's own timing\">1</sup>";
  EXPECT_NE(html.find("<td>1</td><td>&le; 6" + single + "</td><td class=\"t\"><a href=\"#row-0\">default</a>"),
            std::string::npos);
  EXPECT_NE(
      html.find("<td>2</td><td>&le; 7" + single + "</td><td class=\"t\"><a href=\"#row-1\">filter=<wbr>hw2x2</a>"),
      std::string::npos);
  // Two families (none and hw2x2, fit sphere), each in its own colour and marker.
  const nlohmann::json results = nlohmann::json::parse(slurp(o.outDir + "/results.json"));
  ASSERT_EQ(results["families"].size(), 2u);
  EXPECT_EQ(results["families"][0]["key"], "none / sphere");
  EXPECT_EQ(results["families"][1]["key"], "hw2x2 / sphere");
  EXPECT_NE(results["families"][0]["color"], results["families"][1]["color"]);
  EXPECT_NE(results["families"][0]["marker"], results["families"][1]["marker"]);
  // "Where the time goes": made, shown, and stacked from every stage the rows carry (the evidence
  // resolve is camera - visibility). The loop measures config_wall_ms itself, shorter than the fake's
  // stages, so no "other" remainder is drawn.
  EXPECT_TRUE(fs::is_regular_file(o.outDir + "/figures/time_breakdown.svg"));
  EXPECT_NE(html.find("<figure class=\"chart\" id=\"time_breakdown\">"), std::string::npos);
  const nlohmann::json manifest = nlohmann::json::parse(slurp(o.outDir + "/figures/charts.json"));
  std::vector<std::string> stages;
  for (const auto& c : manifest["charts"])
    if (c["id"] == "time_breakdown") stages = c["stages"].get<std::vector<std::string>>();
  ASSERT_EQ(stages.size(), 6u) << manifest.dump(1);
  for (const char* want :
       {"shadow_gpu_ms", "lookup_gpu_ms", "(visibility_gpu_ms)", "evidence_gpu_ms", "readback_ms", "compare_ms"}) {
    bool found = false;
    for (const std::string& s : stages) found = found || s.find(want) != std::string::npos;
    EXPECT_TRUE(found) << want;
  }
  fs::remove_all(dir);
}

TEST(ReportChromium, FailingChartScriptIsANoteNotACrash) {
  const std::string dir = tempDir("fail");
  const std::string script = dir + "/broken_charts.py";
  std::ofstream(script) << "import sys\nsys.stderr.write('deliberate failure\\n')\nsys.exit(4)\n";
  SweepSpec spec;
  spec.scenes = {"sphere_on_plane"};
  SweepPlan plan = planSweep(spec);
  FakeRunner runner;
  SweepOptions o;
  o.outDir = dir + "/sweep";
  o.progress = nullptr;
  o.reportScript = script;
  SweepSummary s = runSweep(plan, runner, o);
  ASSERT_FALSE(s.notes.empty());
  EXPECT_NE(s.notes[0].find("exited with 4"), std::string::npos) << s.notes[0];
  EXPECT_NE(s.notes[0].find("deliberate failure"), std::string::npos) << s.notes[0];
  EXPECT_NE(slurp(s.reportHtml).find("deliberate failure"), std::string::npos);
  EXPECT_TRUE(fs::is_regular_file(s.resultsJson));
  fs::remove_all(dir);
}

// The chart script runs in the Python prestarted before the loop (sweep.h, PrestartedCharts): it
// finds the standard modules charts.py uses imported before its first line, gets its arguments as
// `python SCRIPT RESULTS_JSON FIGURES_DIR` would (as __main__, its folder first on sys.path), and
// its exit status and output still reach the report's note.
TEST(ReportChromium, ChartScriptRunsInThePrestartedPython) {
  const std::string dir = tempDir("prestart");
  const std::string script = dir + "/probe_charts.py";
  std::ofstream(script) << "import os, sys\n"
                           "warm = 'statistics' in sys.modules\n"
                           "open(os.path.join(sys.argv[2], 'probe.txt'), 'w').write(\n"
                           "    f'{warm} {__name__} {len(sys.argv)} {sys.path[0] == os.path.dirname(__file__)}')\n"
                           "sys.stderr.write('probe ran\\n')\n"
                           "sys.exit(3)\n";
  SweepSpec spec;
  spec.scenes = {"sphere_on_plane"};
  FakeRunner runner;
  SweepOptions o;
  o.outDir = dir + "/sweep";
  o.progress = nullptr;
  o.reportScript = script;
  SweepSummary s = runSweep(planSweep(spec), runner, o);
  EXPECT_EQ(slurp(o.outDir + "/figures/probe.txt"), "True __main__ 3 True");
  ASSERT_FALSE(s.notes.empty());
  EXPECT_NE(s.notes[0].find("exited with 3"), std::string::npos) << s.notes[0];
  EXPECT_NE(s.notes[0].find("probe ran"), std::string::npos) << s.notes[0];
  fs::remove_all(dir);
}

// A prestarted Python that is never handed the script (here: the sweep is interrupted before its
// report) writes nothing and is reaped: no figures folder, no child process left behind.
TEST(ReportChromium, UnusedPrestartedPythonWritesNothingAndIsReaped) {
  const std::string dir = tempDir("unused");
  SweepSpec spec;
  spec.scenes = {"sphere_on_plane"};
  spec.grid = {parseGridArgument("map.size=256,1024")};
  FakeRunner runner;
  std::atomic<bool> stop{true};
  SweepOptions o;
  o.outDir = dir + "/sweep";
  o.progress = nullptr;
  o.stop = &stop;
  o.reportScript = defaultReportScript(SHADOWLAB_SOURCE_DIR);
  SweepSummary s = runSweep(planSweep(spec), runner, o);
  EXPECT_TRUE(s.interrupted);
  EXPECT_FALSE(fs::exists(o.outDir + "/figures"));
  EXPECT_FALSE(fs::exists(o.outDir + "/report.html"));
  errno = 0;
  EXPECT_EQ(::waitpid(-1, nullptr, WNOHANG), -1) << "a child process is left";
  EXPECT_EQ(errno, ECHILD);
  // The prestarted Python is ended without a report in a fraction of its warm-up, not waited for.
  {
    auto charts = prestartCharts(o);
    ASSERT_NE(charts, nullptr);
    const auto t0 = std::chrono::steady_clock::now();
    charts.reset();
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 5.0);
  }
  EXPECT_EQ(::waitpid(-1, nullptr, WNOHANG), -1);
  fs::remove_all(dir);
}

// The chart script runs while the triptychs render (writeSweepReport): both still reach the
// report, a failure of either is a note while the other's output stays, and results.json says how
// long each took (report_charts_wall_seconds, report_triptychs_wall_seconds; compare/TIMINGS.md).
// The script below waits for the best triptych to appear before it fails: a report that rendered
// the triptychs only after the charts would leave it waiting the full 20 s and "never" in its mark.
TEST(ReportChromium, ChartsRunWhileTriptychsRenderAndEitherFailureIsANote) {
  const std::string dir = tempDir("overlap");
  const std::string script = dir + "/waiting_charts.py";
  std::ofstream(script) << "import os, sys, time\n"
                           "want = os.path.join(sys.argv[2], 'triptych_sphere_on_plane_best.png')\n"
                           "t0 = time.time()\n"
                           "while not os.path.exists(want) and time.time() - t0 < 20:\n"
                           "    time.sleep(0.01)\n"
                           "time.sleep(0.3)\n"
                           "open(os.path.join(sys.argv[2], 'mark.txt'), 'w').write(\n"
                           "    'seen' if os.path.exists(want) else 'never')\n"
                           "sys.stderr.write('charts gave up on purpose\\n')\n"
                           "sys.exit(5)\n";
  SweepSpec spec;
  spec.scenes = {"sphere_on_plane"};
  spec.grid = {parseGridArgument("map.size=256,1024")};
  const SweepPlan plan = planSweep(spec);
  FakeRunner runner;
  runner.pictures = true;
  SweepOptions o;
  o.outDir = dir + "/sweep";
  o.progress = nullptr;
  o.reportScript = script;
  SweepSummary s = runSweep(plan, runner, o);
  EXPECT_EQ(slurp(o.outDir + "/figures/mark.txt"), "seen");
  for (const char* pick : {"best", "worst"})
    EXPECT_TRUE(fs::is_regular_file(o.outDir + "/figures/triptych_sphere_on_plane_" + pick + ".png")) << pick;
  ASSERT_EQ(s.notes.size(), 1u);
  EXPECT_NE(s.notes[0].find("exited with 5"), std::string::npos) << s.notes[0];
  EXPECT_NE(s.notes[0].find("charts gave up on purpose"), std::string::npos) << s.notes[0];
  std::string html = slurp(s.reportHtml);
  EXPECT_NE(html.find("charts gave up on purpose"), std::string::npos);
  EXPECT_NE(html.find("src=\"figures/triptych_sphere_on_plane_worst.png\""), std::string::npos);
  nlohmann::json results = nlohmann::json::parse(slurp(s.resultsJson));
  ASSERT_TRUE(results["report_charts_wall_seconds"].is_number()) << results.dump(1);
  ASSERT_TRUE(results["report_triptychs_wall_seconds"].is_number());
  // The script's own time (its 0.3 s sleep at least), not the triptychs' nor the whole report's.
  EXPECT_GE(results["report_charts_wall_seconds"].get<double>(), 0.3);
  EXPECT_LE(results["report_charts_wall_seconds"].get<double>(), results["report_wall_seconds"].get<double>());
  EXPECT_LE(results["report_triptychs_wall_seconds"].get<double>(), results["report_wall_seconds"].get<double>());

  // Now the triptychs fail and the charts succeed: the chart is shown, the failure is a note.
  const std::string okScript = dir + "/one_chart.py";
  std::ofstream(okScript) << "import json, os, sys\n"
                             "open(os.path.join(sys.argv[2], 'only.svg'), 'w').write('<svg id=\"only-chart\"></svg>')\n"
                             "json.dump({'charts': [{'id': 'only', 'title': 'The only chart', 'caption': 'c',\n"
                             "           'svg': 'figures/only.svg'}], 'skipped': []},\n"
                             "          open(os.path.join(sys.argv[2], 'charts.json'), 'w'))\n";
  runner.failTriptychs = true;
  o.outDir = dir + "/sweep2";
  o.reportScript = okScript;
  s = runSweep(plan, runner, o);
  ASSERT_EQ(s.notes.size(), 2u) << "one per triptych";
  for (const auto& n : s.notes) EXPECT_NE(n.find("deliberate triptych failure"), std::string::npos) << n;
  html = slurp(s.reportHtml);
  EXPECT_NE(html.find("<figure class=\"chart\" id=\"only\">\n<h3>The only chart</h3>\n<svg id=\"only-chart\">"),
            std::string::npos)
      << "the chart's SVG inline";
  EXPECT_NE(html.find("deliberate triptych failure"), std::string::npos);
  EXPECT_FALSE(fs::exists(o.outDir + "/figures/triptych_sphere_on_plane_best.png"));
  results = nlohmann::json::parse(slurp(s.resultsJson));
  EXPECT_TRUE(results["report_charts_wall_seconds"].is_number());
  EXPECT_TRUE(results["report_triptychs_wall_seconds"].is_number());

  // Without a report, none of the three.
  o.outDir = dir + "/sweep3";
  o.writeReport = false;
  s = runSweep(plan, runner, o);
  results = nlohmann::json::parse(slurp(s.resultsJson));
  for (const char* k : {"report_wall_seconds", "report_charts_wall_seconds", "report_triptychs_wall_seconds"})
    EXPECT_TRUE(results.contains(k) && results[k].is_null()) << k;
  fs::remove_all(dir);
}

// Timings free of the grid's order: the same grid swept forwards and backwards (map sizes and
// filters reversed, so each map size's first row, which touches fresh map memory, is another
// configuration) gives the same Pareto front of method_gpu_ms against error_rate within the
// spread of the timed repetitions. The errors are the same bits in both orders; a configuration
// on one order's front must not be beaten in the other order by one whose slowest run is faster
// than its fastest (the ranges of both orders taken together; a row with one sample is its own
// range). Every row on either order's front carries its median and range (method_gpu_ms_min <=
// method_gpu_ms <= method_gpu_ms_max), and so does every row within the noise band of its front;
// the others carry their render's single sample (sweep.h, rowsWhoseTimeDecides).
TEST(ReportTimings, ReversedGridFindsTheSameParetoFrontsWithinTheSpread) {
  const std::string dir = tempDir("order");
  auto sweep = [&](const std::string& name, const std::string& sizes, const std::string& filters) {
    int rc = runCommand({SHADOWLAB_BINARY, "sweep", "sphere_on_plane", "--grid", "map.size=" + sizes, "--grid",
                         "filter=" + filters, "--set", "scene:/camera/width=480", "--set", "scene:/camera/height=270",
                         "-o", dir + "/" + name, "--cache", dir + "/cache", "--no-report"},
                        dir + "/" + name + ".out", dir + "/" + name + ".err", 300);
    return rc;
  };
  const int rc = sweep("forward", "256,512,1024,2048", "none,pcf,vsm");
  if (rc == 3) GTEST_SKIP() << "SKIPPED LOUDLY: no Vulkan device (shadowlab exit 3): " << slurp(dir + "/forward.err");
  ASSERT_EQ(rc, 0) << slurp(dir + "/forward.err");
  ASSERT_EQ(sweep("backward", "2048,1024,512,256", "vsm,pcf,none"), 0) << slurp(dir + "/backward.err");
  struct Timing {
    double error, median, lo, hi;
    bool repeated;
  };
  auto load = [&](const std::string& name) {
    std::map<std::string, Timing> out;
    const nlohmann::json results = nlohmann::json::parse(slurp(dir + "/" + name + "/results.json"));
    for (const auto& r : results["rows"]) {
      const auto& t = r["timings"];
      const double median = t["method_gpu_ms"].get<double>();
      const bool repeated = t.contains("method_gpu_ms_min");
      EXPECT_EQ(repeated, t.contains("method_gpu_ms_max")) << r["config"];
      Timing v{r["metrics"]["error_rate"].get<double>(), median,
               repeated ? t["method_gpu_ms_min"].get<double>() : median,
               repeated ? t["method_gpu_ms_max"].get<double>() : median, repeated};
      EXPECT_LE(v.lo, v.median) << r["config"];
      EXPECT_LE(v.median, v.hi) << r["config"];
      out[r["config"].get<std::string>()] = v;
    }
    EXPECT_EQ(results["timing"]["repetitions"], 3);
    return out;
  };
  const auto forward = load("forward"), backward = load("backward");
  ASSERT_EQ(forward.size(), 12u);
  ASSERT_EQ(backward.size(), 12u);
  auto front = [](const std::map<std::string, Timing>& rows) {
    std::vector<std::pair<std::string, Timing>> v(rows.begin(), rows.end());
    std::sort(v.begin(), v.end(), [](const auto& a, const auto& b) {
      return a.second.median != b.second.median ? a.second.median < b.second.median : a.second.error < b.second.error;
    });
    std::vector<std::string> out;
    double best = INFINITY;
    for (const auto& [config, t] : v)
      if (t.error < best) out.push_back(config), best = t.error;
    return out;
  };
  for (const auto& [config, t] : forward) EXPECT_EQ(t.error, backward.at(config).error) << config;
  auto lo = [&](const std::string& c) { return std::min(forward.at(c).lo, backward.at(c).lo); };
  auto hi = [&](const std::string& c) { return std::max(forward.at(c).hi, backward.at(c).hi); };
  for (const auto* fr : {&forward, &backward}) {
    for (const std::string& c : front(*fr)) {
      EXPECT_TRUE(fr->at(c).repeated) << c << " is on a front but carries a single sample";
      for (const auto& [d, t] : forward)
        EXPECT_FALSE(t.error < forward.at(c).error && hi(d) < lo(c))
            << c << " is on one order's front, yet " << d << " is both more accurate and faster beyond the spread ("
            << hi(d) << " < " << lo(c) << " ms)";
    }
  }
  std::string a, b;
  for (const auto& c : front(forward)) a += c + "; ";
  for (const auto& c : front(backward)) b += c + "; ";
  std::fprintf(stderr, "forward front: %s\nbackward front: %s\n", a.c_str(), b.c_str());
  fs::remove_all(dir);
}

}  // namespace report_chromium_test
