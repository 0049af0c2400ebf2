// `shadowlab sweep` through the real binary (fork/exec): bad grids exit 2 and write nothing; a
// small sweep's rows carry the same error numbers as `shadowlab run` on each configuration; a
// sweep interrupted by SIGINT and then SIGKILL resumes with no row lost, none duplicated and no
// finished configuration run twice.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <thread>

#include <nlohmann/json.hpp>

#include "shadowlab/compare/results.h"
#include "shadowlab/scenes/io.h"

namespace sweep_cli_test {

namespace fs = std::filesystem;
using namespace shadowlab;

namespace {

struct Child {
  pid_t pid = -1;
  std::string out, err;  // paths of captured stdout / stderr
};

Child spawn(const std::vector<std::string>& args, const std::string& logBase) {
  Child c;
  c.out = logBase + ".out";
  c.err = logBase + ".err";
  c.pid = ::fork();
  if (c.pid == 0) {
    FILE* o = std::freopen(c.out.c_str(), "w", stdout);
    FILE* e = std::freopen(c.err.c_str(), "w", stderr);
    (void)o;
    (void)e;
    std::vector<char*> argv;
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  return c;
}

// Exit status (128 + signal when killed); kills the child and fails after `timeoutS`.
int waitFor(const Child& c, double timeoutS = 120) {
  auto t0 = std::chrono::steady_clock::now();
  int status = 0;
  while (true) {
    pid_t r = ::waitpid(c.pid, &status, WNOHANG);
    if (r == c.pid) break;
    if (std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() > timeoutS) {
      ::kill(c.pid, SIGKILL);
      ::waitpid(c.pid, &status, 0);
      ADD_FAILURE() << "child did not finish in " << timeoutS << " s";
      return -1;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  if (WIFSIGNALED(status)) return 128 + WTERMSIG(status);
  return -1;
}

std::string slurp(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

size_t lineCount(const std::string& path) {
  std::ifstream in(path);
  size_t n = 0;
  std::string line;
  while (std::getline(in, line))
    if (!line.empty()) ++n;
  return n;
}

// Waits until `path` has at least `n` lines (the child still running); false on timeout/exit.
bool waitForLines(const Child& c, const std::string& path, size_t n, double timeoutS = 120) {
  auto t0 = std::chrono::steady_clock::now();
  while (std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() < timeoutS) {
    if (lineCount(path) >= n) return true;
    int status = 0;
    if (::waitpid(c.pid, &status, WNOHANG) == c.pid) return false;  // exited early
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  return false;
}

std::string tempDir(const std::string& name) {
  fs::path d = fs::temp_directory_path() / ("shadowlab_sweep_cli_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d.string();
}

const std::string kBinary = SHADOWLAB_BINARY;

// sphere_on_plane at a quarter of its pixels (480x270), written as DIR/sphere_on_plane.json: the
// same scene name and geometry, cheap enough for the suite. `run` reads the same file.
std::string smallScene(const std::string& dir) {
  auto doc = nlohmann::json::parse(readFile(std::string(SHADOWLAB_SOURCE_DIR) + "/scenes/data/sphere_on_plane.json"),
                                   nullptr, true, /*ignore_comments=*/true);
  doc["camera"]["width"] = 480;
  doc["camera"]["height"] = 270;
  const std::string path = dir + "/sphere_on_plane.json";
  std::ofstream(path) << doc.dump(2);
  return path;
}

std::vector<std::string> sweepArgs(std::vector<std::string> extra) {
  std::vector<std::string> a{kBinary, "sweep"};
  a.insert(a.end(), extra.begin(), extra.end());
  return a;
}

}  // namespace

TEST(SweepCli, BadGridValuesExit2AndWriteNothing) {
  const std::string dir = tempDir("bad");
  const std::string badFile = dir + "/bad_sweep.json";
  std::ofstream(badFile) << "{\n  \"grid\": {\"map.size\": [256, \"big\"]}\n}\n";
  // A scene that declares no "failure": scene:failure names nothing in it.
  const std::string plainScene = dir + "/plain.json";
  std::ofstream(plainScene) << R"({"camera": {"position": [0, 2, 5], "look_at": [0, 0, 0], "vfov_deg": 45,
    "width": 64, "height": 48}, "objects": [{"type": "plane", "size": [10, 10]}],
    "lights": [{"type": "directional", "elevation_deg": 45}]})";
  struct Case {
    std::vector<std::string> args;
    std::string message;
  };
  const std::vector<Case> cases = {
      {{"--grid", "map.sise=256,512"}, "--grid map.sise=256,512: error: unknown key \"map.sise\""},
      {{"--grid", "map.size="}, "--grid map.size=: error: empty list of values for \"map.size\""},
      {{"--grid", "map.size=256,huge"}, "got \"huge\"; expected an integer"},
      {{"--grid", "map.size=256", "--grid", "bias.slope=0,,1"}, "value 2 of \"bias.slope\" is empty"},
      {{"--sweep", badFile}, badFile + ": /grid/map.size/1"},
      {{"--light", "moon"}, "no light named \"moon\""},
      {{plainScene, "--grid", "scene:failure=30,20"},
       plainScene + ": error: the scene declares no \"failure\", so scene:failure names nothing in it"},
  };
  int i = 0;
  for (const auto& c : cases) {
    std::vector<std::string> args = sweepArgs({"sphere_on_plane"});
    args.insert(args.end(), c.args.begin(), c.args.end());
    args.push_back("-o");
    args.push_back(dir + "/out");
    Child child = spawn(args, dir + "/log" + std::to_string(i++));
    EXPECT_EQ(waitFor(child), 2) << slurp(child.err);
    std::string err = slurp(child.err);
    EXPECT_NE(err.find(c.message), std::string::npos) << "stderr: " << err << "\nexpected to contain: " << c.message;
    // Nothing written: neither the output folder nor the cache beside it.
    EXPECT_FALSE(fs::exists(dir + "/out")) << err;
    EXPECT_FALSE(fs::exists(dir + "/.shadowlab-cache")) << err;
  }
  fs::remove_all(dir);
}

TEST(SweepCli, SmallSweepRowsMatchShadowlabRunExactly) {
  const std::string dir = tempDir("small");
  const std::string scene = smallScene(dir);
  Child sweep = spawn(sweepArgs({scene, "--grid", "map.size=256,512", "--grid", "bias.slope=0,2", "-o", dir + "/sweep",
                                 "--cache", dir + "/cache", "--no-report", "--keep-images"}),
                      dir + "/sweep");
  int rc = waitFor(sweep);
  if (rc == 3) GTEST_SKIP() << "no Vulkan device (shadowlab exit 3): " << slurp(sweep.err);
  ASSERT_EQ(rc, 0) << slurp(sweep.err);
  EXPECT_NE(slurp(sweep.err).find("sweep: 4/4 sphere_on_plane"), std::string::npos)
      << "plain progress lines when stderr is not a terminal: " << slurp(sweep.err);

  auto rows = loadResultRows(dir + "/sweep/results.json");
  ASSERT_EQ(rows.size(), 4u);
  // --keep-images: the raster frame and the error picture of every configuration.
  for (const char* config : {"bias.slope=0,map.size=256", "bias.slope=2,map.size=512"})
    for (const char* file : {"raster.exr", "errors.png"})
      EXPECT_TRUE(fs::is_regular_file(dir + "/sweep/images/sphere_on_plane/" + config + "/" + file)) << config << file;
  const std::vector<std::pair<std::string, std::string>> configs = {
      {"256", "0"}, {"256", "2"}, {"512", "0"}, {"512", "2"}};
  // Columns of results.csv: identification, the method, every metric, every timing.
  std::string csv = slurp(dir + "/sweep/results.csv");
  std::string header = csv.substr(0, csv.find('\n'));
  for (const char* col : {"scene", "config", "light", "map.size", "bias.slope", "error_rate", "acne_rate", "leak_rate",
                          "aliasing_rate", "coverage_rate", "m_p95", "shadow_gpu_ms", "lookup_gpu_ms", "method_gpu_ms",
                          "camera_gpu_ms", "visibility_gpu_ms", "readback_ms", "compare_ms", "config_wall_ms"})
    EXPECT_NE(("," + header + ",").find(std::string(",") + col + ","), std::string::npos) << col << " in " << header;
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 5);

  for (size_t i = 0; i < configs.size(); ++i) {
    const auto& [size, slope] = configs[i];
    const std::string config = "bias.slope=" + slope + ",map.size=" + size;
    EXPECT_EQ(rows[i].config, config);
    EXPECT_EQ(rows[i].scene, "sphere_on_plane");
    EXPECT_EQ(rows[i].light, "sun");
    const std::string runDir = dir + "/run" + std::to_string(i);
    Child run = spawn({kBinary, "run", scene, "--set", "map.size=" + size, "--set", "bias.slope=" + slope, "-o", runDir,
                       "--cache", dir + "/cache"},
                      runDir);
    ASSERT_EQ(waitFor(run), 0) << slurp(run.err);
    auto single = loadResultRows(runDir + "/metrics.json");
    ASSERT_EQ(single.size(), 1u);
    EXPECT_EQ(single[0].config, config) << "run names the same configuration the same way";
    EXPECT_EQ(single[0].method, rows[i].method);
    // Every metric identical: same reference, same raster, same classification.
    EXPECT_EQ(single[0].metrics, rows[i].metrics)
        << config << "\nrun:   " << single[0].metrics.dump() << "\nsweep: " << rows[i].metrics.dump();
  }
  // The bias must matter on this scene (else the comparison above proves little): slope 0 at 256
  // shows acne that slope 2 removes.
  EXPECT_GT(rows[0].metrics.at("acne_rate").get<double>(), rows[1].metrics.at("acne_rate").get<double>());
  fs::remove_all(dir);
}

// A configuration whose camera sees only sky has nothing to compare: the sweep stops with exit 2
// naming the scene (the reference cache's rule, the same message as run and tune: compare_cli_test),
// rather than going on with a row of null rates. (A row whose renderers disagree on every surface
// still compares nothing and is marked "nothing_compared", never ranked.)
TEST(SweepCli, ConfigurationWhoseCameraSeesOnlySkyExits2NamingTheScene) {
  const std::string dir = tempDir("nothing");
  const std::string scene = smallScene(dir);
  // look_at y = 60: the camera looks steeply up, past the sphere and the ground.
  Child sweep = spawn(sweepArgs({scene, "--grid", "scene:/camera/look_at/1=0.5,60", "--set", "map.size=256", "-o",
                                 dir + "/sweep", "--cache", dir + "/cache"}),
                      dir + "/sweep");
  int rc = waitFor(sweep, 300);
  if (rc == 3) GTEST_SKIP() << "no Vulkan device (shadowlab exit 3): " << slurp(sweep.err);
  ASSERT_EQ(rc, 2) << slurp(sweep.err);
  const std::string err = slurp(sweep.err);
  EXPECT_NE(err.find(scene + ": /camera: error: scene \"sphere_on_plane\": the camera sees no surface"),
            std::string::npos)
      << err;
  EXPECT_FALSE(fs::exists(dir + "/sweep/results.json"));
  fs::remove_all(dir);
}

// The report's triptychs: each scene's best and worst row as the loop kept them (sweep_runner.cpp,
// keepForTriptych), or rendered again with evidence on demand where the runner did not run the row
// (here: the same sweep run again, every row resumed), are the same pictures, byte for byte, as
// those rendered from the full frames of --full-evidence. The runner's counters say which path drew
// them (both triptychs each time, or the comparison would prove nothing). The charts are skipped
// (no script): the triptychs are the point.
TEST(SweepCli, ReportTriptychsOnDemandEqualFullFrameOnes) {
  const std::string dir = tempDir("triptychs");
  const std::string scene = smallScene(dir);
  ::setenv("SHADOWLAB_REPORT_SCRIPT", (dir + "/no_charts.py").c_str(), 1);
  std::map<std::string, std::map<std::string, std::string>> pictures;  // mode -> pick -> PNG bytes
  std::map<std::string, nlohmann::json> runners;
  for (const char* mode : {"kept", "resumed", "full"}) {
    const std::string out = dir + "/" + (std::string(mode) == "full" ? "full" : "on_demand");
    std::vector<std::string> args = sweepArgs({scene, "--grid", "map.size=256,512", "--grid", "filter=none,pcf", "--grid",
                                               "bias.slope=0,2", "-o", out, "--cache", dir + "/cache"});
    if (std::string(mode) == "full") args.push_back("--full-evidence");
    Child sweep = spawn(args, dir + "/" + mode);
    const int rc = waitFor(sweep);
    if (rc == 3) {
      ::unsetenv("SHADOWLAB_REPORT_SCRIPT");
      GTEST_SKIP() << "no Vulkan device (shadowlab exit 3): " << slurp(sweep.err);
    }
    ASSERT_EQ(rc, 0) << slurp(sweep.err);
    const auto results = nlohmann::json::parse(slurp(out + "/results.json"));
    runners[mode] = results.at("runner");
    EXPECT_EQ(results.at("rows_run").get<int>(), std::string(mode) == "resumed" ? 0 : 8) << mode;
    for (const char* pick : {"best", "worst"})
      pictures[mode][pick] = slurp(out + "/figures/triptych_sphere_on_plane_" + pick + ".png");
  }
  ::unsetenv("SHADOWLAB_REPORT_SCRIPT");
  EXPECT_EQ(runners["kept"].value("triptychs_kept", -1), 2) << runners["kept"].dump();
  EXPECT_EQ(runners["kept"].value("triptychs_on_demand", -1), 0) << runners["kept"].dump();
  EXPECT_EQ(runners["resumed"].value("triptychs_kept", -1), 0) << runners["resumed"].dump();
  EXPECT_EQ(runners["resumed"].value("triptychs_on_demand", -1), 2) << runners["resumed"].dump();
  EXPECT_EQ(runners["full"].value("triptychs_kept", -1), 0) << runners["full"].dump();
  EXPECT_EQ(runners["full"].value("triptychs_on_demand", -1), 0) << runners["full"].dump();
  for (const char* pick : {"best", "worst"}) {
    ASSERT_FALSE(pictures["full"][pick].empty()) << pick;
    EXPECT_TRUE(pictures["kept"][pick] == pictures["full"][pick]) << pick << ": the kept triptych differs";
    EXPECT_TRUE(pictures["resumed"][pick] == pictures["full"][pick]) << pick << ": the re-rendered triptych differs";
  }
  fs::remove_all(dir);
}

// Rows rendered on demand are compared through a CompareContext kept per evidence group
// (compare/METRICS.md "Comparing a group"): the filter fastest, then the map size, so two groups
// alternate every two rows and each keeps its context. Every row's metrics equal those of the
// same sweep with --full-evidence (full frames, no group, the full compareFrames).
TEST(SweepCli, RowsComparedThroughGroupContextsMatchFullEvidence) {
  const std::string dir = tempDir("contexts");
  const std::string scene = smallScene(dir);
  auto sweepInto = [&](const std::string& out, bool full) {
    std::vector<std::string> args =
        sweepArgs({scene, "--grid", "bias.slope=0,1.5,4", "--grid", "map.size=256,512", "--grid", "filter=none,pcf",
                   "-o", dir + "/" + out, "--cache", dir + "/cache", "--no-report"});
    if (full) args.push_back("--full-evidence");
    Child sweep = spawn(args, dir + "/" + out);
    return std::make_pair(waitFor(sweep), slurp(sweep.err));
  };
  auto [rc, err] = sweepInto("demand", false);
  if (rc == 3) GTEST_SKIP() << "no Vulkan device (shadowlab exit 3): " << err;
  ASSERT_EQ(rc, 0) << err;
  auto [rcFull, errFull] = sweepInto("full", true);
  ASSERT_EQ(rcFull, 0) << errFull;
  const auto demand = loadResultRows(dir + "/demand/results.json");
  const auto full = loadResultRows(dir + "/full/results.json");
  ASSERT_EQ(demand.size(), 12u);
  ASSERT_EQ(full.size(), 12u);
  for (size_t i = 0; i < demand.size(); ++i) {
    EXPECT_EQ(demand[i].config, full[i].config);
    EXPECT_EQ(demand[i].metrics, full[i].metrics)
        << demand[i].config << "\non demand: " << demand[i].metrics.dump() << "\nfull:      " << full[i].metrics.dump();
  }
  // Two groups (map sizes 256 and 512): 12 rows, the first of each group compared in full. The
  // first group's context is built on its second row; the second group's on its first, sharing the
  // first one's decisions (the same camera), and used from its second row on.
  const auto runner = nlohmann::json::parse(readFile(dir + "/demand/results.json")).at("runner");
  EXPECT_EQ(runner.at("compare_contexts_built"), 2) << runner.dump();
  EXPECT_EQ(runner.at("compare_contexts_shared"), 1) << runner.dump();
  EXPECT_EQ(runner.at("compare_context_rows"), 10) << runner.dump();
  const auto runnerFull = nlohmann::json::parse(readFile(dir + "/full/results.json")).at("runner");
  EXPECT_EQ(runnerFull.at("compare_context_rows"), 0) << runnerFull.dump();
  // The biases and filters matter (else equal rows prove little): slope 0 shows acne that 4 removes.
  EXPECT_GT(demand[0].metrics.at("acne_rate").get<double>(), demand[8].metrics.at("acne_rate").get<double>());
  EXPECT_NE(demand[0].metrics, demand[1].metrics);
  fs::remove_all(dir);
}

// `run` takes scene: values like a sweep (the same --set parser, shadowlab::applySetArguments) and
// names the row the same way: a run with a smaller image equals the sweep row that swept it.
TEST(SweepCli, RunWithASceneValueMatchesTheSweepRowThatSweptIt) {
  const std::string dir = tempDir("scenevalue");
  const std::string scene = smallScene(dir);
  Child sweep = spawn(sweepArgs({scene, "--grid", "scene:/camera/width=320", "--grid", "map.size=512", "-o",
                                 dir + "/sweep", "--cache", dir + "/cache", "--no-report"}),
                      dir + "/sweep");
  int rc = waitFor(sweep);
  if (rc == 3) GTEST_SKIP() << "no Vulkan device (shadowlab exit 3): " << slurp(sweep.err);
  ASSERT_EQ(rc, 0) << slurp(sweep.err);
  auto rows = loadResultRows(dir + "/sweep/results.json");
  ASSERT_EQ(rows.size(), 1u);
  Child run = spawn({kBinary, "run", scene, "--set", "map.size=512", "--set", "scene:/camera/width=320", "-o",
                     dir + "/run", "--cache", dir + "/cache"},
                    dir + "/run");
  ASSERT_EQ(waitFor(run), 0) << slurp(run.err);
  auto single = loadResultRows(dir + "/run/metrics.json");
  ASSERT_EQ(single.size(), 1u);
  EXPECT_EQ(single[0].config, "map.size=512,scene:/camera/width=320");
  EXPECT_EQ(single[0].config, rows[0].config);
  EXPECT_EQ(single[0].metrics, rows[0].metrics);
  // The width was applied: 320x270 pixels compared at most, not 480x270.
  EXPECT_LE(single[0].metrics.at("pixels_compared").get<double>(), 320.0 * 270.0);
  fs::remove_all(dir);
}

TEST(SweepCli, InterruptedAndKilledSweepResumesWithNothingLostOrRepeated) {
  const std::string dir = tempDir("kill");
  const std::string out = dir + "/sweep";
  const std::string journal = out + "/rows.jsonl";
  // 40 configurations: slow enough to be caught midway.
  std::vector<std::string> args =
      sweepArgs({smallScene(dir), "--grid", "map.size=64,128,256,512,1024", "--grid",
                 "bias.slope=0,0.25,0.5,1,1.5,2,3,4", "-o", out, "--cache", dir + "/cache", "--no-report"});
  const size_t total = 40;

  // 1. SIGINT after a few rows: a clean stop, exit 130, the rows so far kept.
  Child a = spawn(args, dir + "/a");
  if (!waitForLines(a, journal, 3)) {
    int rc = waitFor(a);
    if (rc == 3) GTEST_SKIP() << "no Vulkan device (shadowlab exit 3): " << slurp(a.err);
    FAIL() << "the sweep ended (exit " << rc << ") before 3 rows: " << slurp(a.err);
  }
  ::kill(a.pid, SIGINT);
  EXPECT_EQ(waitFor(a), 130) << slurp(a.err);
  EXPECT_NE(slurp(a.err).find("run the same command again to continue"), std::string::npos) << slurp(a.err);
  const size_t afterInt = lineCount(journal);
  EXPECT_GE(afterInt, 3u);
  EXPECT_LT(afterInt, total) << "the sweep was not interrupted midway";
  EXPECT_FALSE(fs::exists(out + "/results.json"));

  // 2. Resume, then SIGKILL a few rows later: no chance to clean up at all.
  Child b = spawn(args, dir + "/b");
  ASSERT_TRUE(waitForLines(b, journal, afterInt + 3)) << slurp(b.err);
  ::kill(b.pid, SIGKILL);
  EXPECT_EQ(waitFor(b), 128 + SIGKILL);
  const size_t afterKill = lineCount(journal);
  EXPECT_LT(afterKill, total) << "the sweep was not killed midway";
  EXPECT_NE(slurp(b.err).find("resuming: " + std::to_string(afterInt) + " of 40 rows"), std::string::npos)
      << slurp(b.err);

  // 3. Resume to the end.
  Child c = spawn(args, dir + "/c");
  ASSERT_EQ(waitFor(c), 0) << slurp(c.err);
  auto rows = loadResultRows(out + "/results.json");
  ASSERT_EQ(rows.size(), total);
  std::set<std::string> keys;
  for (const auto& r : rows) EXPECT_TRUE(keys.insert(r.key()).second) << "duplicate row " << r.key();
  // Each row appended once when it finished, and once more by the rows near the front timed
  // again at the end (marked "timed_again").
  size_t timedAgain = 0;
  {
    std::ifstream in(journal);
    std::string line;
    while (std::getline(in, line)) timedAgain += nlohmann::json::parse(line).value("timed_again", false) ? 1 : 0;
  }
  EXPECT_GT(timedAgain, 0u);
  EXPECT_EQ(lineCount(journal), total + timedAgain) << "each row appended once, and once when timed again";

  // Who ran what: rows.jsonl records the pid that finished each row, sweep.log every start. Each
  // configuration finished exactly once; the only one started twice is the one SIGKILL cut short
  // (started by the killed process, finished by the last one).
  std::map<std::string, long> finishedBy;
  {
    std::ifstream in(journal);
    std::string line;
    while (std::getline(in, line)) {
      auto j = nlohmann::json::parse(line);
      ResultRow r = ResultRow::fromJson(j.at("row"), journal);
      if (j.value("timed_again", false)) {
        EXPECT_EQ(finishedBy.count(r.key()), 1u) << r.key() << " timed again before it finished";
        continue;
      }
      EXPECT_EQ(finishedBy.count(r.key()), 0u) << r.key() << " finished twice";
      finishedBy[r.key()] = j.at("pid").get<long>();
    }
  }
  ASSERT_EQ(finishedBy.size(), total);
  std::map<std::string, std::vector<long>> startedBy;
  std::ifstream log(out + "/sweep.log");
  std::string line;
  while (std::getline(log, line)) {
    auto at = line.find(" start ");
    if (at != std::string::npos) startedBy[line.substr(at + 7)].push_back(std::stol(line.substr(4)));
  }
  ASSERT_EQ(startedBy.size(), total);
  int startedTwice = 0;
  for (const auto& [key, pids] : startedBy) {
    ASSERT_EQ(finishedBy.count(key), 1u) << key;
    if (pids.size() == 1) {
      EXPECT_EQ(pids[0], finishedBy[key]) << key;
      continue;
    }
    ++startedTwice;
    ASSERT_EQ(pids.size(), 2u) << key;
    EXPECT_EQ(pids[0], long(b.pid)) << key << ": only the killed process may leave a configuration unfinished";
    EXPECT_EQ(pids[1], long(c.pid)) << key;
    EXPECT_EQ(finishedBy[key], long(c.pid)) << key;
  }
  EXPECT_LE(startedTwice, 1);
  fs::remove_all(dir);
}

}  // namespace sweep_cli_test
