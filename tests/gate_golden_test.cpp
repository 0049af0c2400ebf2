// The project gates itself: the golden configurations (tests/golden/*.sweep.json: the default
// method, zero bias, pcf 5x5, on every bundled scene at 480x270) are re-run through the real
// binary and gated against tests/golden/baseline.json under tests/golden/tolerances.json. A change
// to the rasterizer or the classifier that moves a metric fails here, with the metric's name and
// both values on stderr. Missing golden files, a failed sweep and an out-of-tolerance metric are
// distinct failures, all red. Update on purpose with tests/golden/update.sh.
#include <gtest/gtest.h>
#include <sched.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

namespace gate_golden_test {

namespace {

namespace fs = std::filesystem;

const fs::path kGolden = fs::path(SHADOWLAB_SOURCE_DIR) / "tests" / "golden";
// The rows' configuration names (config_name.h): the method keys off their defaults and the
// sweeps' fixed 480x270 camera.
constexpr const char* kDefault = "scene:/camera/height=270,scene:/camera/width=480";
constexpr const char* kZeroBias = "bias.compare=0,bias.slope=0,scene:/camera/height=270,scene:/camera/width=480";

std::string slurp(const fs::path& p) {
  std::ifstream f(p);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

// CPU 0 may not be ours in a container with a cpuset: pin to the first CPU we may run on.
std::string firstAllowedCpu() {
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof set, &set) == 0)
    for (int cpu = 0; cpu < CPU_SETSIZE; ++cpu)
      if (CPU_ISSET(cpu, &set)) return std::to_string(cpu);
  return "0";
}

struct Cmd {
  int code = -1;
  std::string out, err;
};

class Golden : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("shadowlab_golden_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    for (const char* name :
         {"baseline.json", "tolerances.json", "default.sweep.json", "zero_bias.sweep.json", "pcf5.sweep.json"})
      ASSERT_TRUE(fs::exists(kGolden / name))
          << "golden file missing: " << (kGolden / name) << " (regenerate with tests/golden/update.sh)";
  }
  void TearDown() override {
    if (!HasFailure()) fs::remove_all(dir_);
  }

  Cmd shadowlab(const std::string& args, const std::string& prefix = "") {
    Cmd r;
    std::string cmd = prefix + std::string(SHADOWLAB_BINARY) + " " + args + " >" + (dir_ / "stdout.txt").string() +
                      " 2>" + (dir_ / "stderr.txt").string();
    int status = std::system(cmd.c_str());
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.out = slurp(dir_ / "stdout.txt");
    r.err = slurp(dir_ / "stderr.txt");
    return r;
  }

  // Runs one golden sweep; returns its results.json (empty after a fatal failure or a skip).
  // `prefix` goes before the binary on the shell line (environment, taskset).
  std::string sweep(const std::string& name, const std::string& outName, const std::string& cacheName,
                    const std::string& prefix = "") {
    fs::path out = dir_ / outName;
    Cmd r = shadowlab("sweep --sweep " + (kGolden / (name + ".sweep.json")).string() + " -o " + out.string() +
                          " --cache " + (dir_ / cacheName).string() + " --no-report",
                      prefix);
    if (r.code == 3 && r.err.find("no Vulkan device") != std::string::npos) {
      skipReason_ = "no Vulkan device, the golden sweeps cannot run: " + r.err;
      return "";
    }
    EXPECT_EQ(r.code, 0) << "golden sweep " << name << " failed:\n" << r.out << r.err;
    EXPECT_TRUE(fs::exists(out / "results.json")) << "golden sweep " << name << " wrote no results.json";
    return (out / "results.json").string();
  }

  fs::path dir_;
  std::string skipReason_;
};

TEST_F(Golden, GoldenConfigurationsPassTheGateAndAMovedMetricFails) {
  std::string currents;
  for (const char* name : {"default", "zero_bias", "pcf5"}) {
    std::string results = sweep(name, name, "cache");
    if (!skipReason_.empty()) GTEST_SKIP() << skipReason_;
    ASSERT_FALSE(HasFailure());
    currents += results + " ";
  }
  const std::string baseline = (kGolden / "baseline.json").string();
  const std::string tolerances = (kGolden / "tolerances.json").string();
  Cmd gate = shadowlab("gate " + currents + "--baseline " + baseline + " --tolerances " + tolerances + " --json " +
                       (dir_ / "gate.json").string() + " --junit " + (dir_ / "gate.xml").string() + " --brief");
  EXPECT_EQ(gate.code, 0) << "the golden gate failed: a change moved these metrics (if on purpose, run "
                             "tests/golden/update.sh and commit the reviewed baseline):\n"
                          << gate.err << gate.out;
  ASSERT_TRUE(fs::exists(dir_ / "gate.json")) << gate.err;
  nlohmann::json report = nlohmann::json::parse(slurp(dir_ / "gate.json"));
  nlohmann::json golden = nlohmann::json::parse(slurp(baseline));
  // Every golden row was compared (3 methods x every bundled scene), and nothing is new.
  EXPECT_EQ(report["counts"]["rows_compared"].get<size_t>(), golden["rows"].size());
  EXPECT_EQ(report["counts"]["rows_new"], 0) << gate.out;
  EXPECT_GE(golden["rows"].size(), 3u * 10u);

  // The golden data must show what the scenes are for, or gating them proves nothing: zero bias
  // on the grazing scene has acne, the default method on it (almost) none.
  auto metricOf = [&](const std::string& config, const char* metric) {
    for (const auto& row : golden["rows"])
      if (row["scene"] == "grazing" && row["config"] == config) return row["metrics"][metric].get<double>();
    ADD_FAILURE() << "golden baseline has no grazing row for " << config;
    return 0.0;
  };
  const double zeroBiasAcne = metricOf(kZeroBias, "acne_rate");
  EXPECT_GT(zeroBiasAcne, 0.05);
  EXPECT_LT(metricOf(kDefault, "acne_rate"), 0.01);

  // A moved metric fails with its name and both values, in either direction (the golden
  // tolerances are "equal": an improvement must be recorded too). Doctor the baseline as if a
  // change had doubled one row's acne and removed another row's aliasing errors.
  golden["schema"] = "shadowlab.results/1";
  double aliasing = -1;
  for (auto& row : golden["rows"]) {
    if (row["scene"] == "grazing" && row["config"] == kZeroBias) row["metrics"]["acne_rate"] = zeroBiasAcne / 2;
    if (row["scene"] == "grazing" && row["config"] == kDefault) {
      aliasing = row["metrics"]["aliasing"].get<double>();
      row["metrics"]["aliasing"] = aliasing * 2 + 100;  // beyond max(50, 2%)
    }
  }
  std::ofstream(dir_ / "doctored.json") << golden.dump(2);
  Cmd caught =
      shadowlab("gate " + currents + "--baseline " + (dir_ / "doctored.json").string() + " --tolerances " + tolerances);
  EXPECT_EQ(caught.code, 1) << caught.out << caught.err;
  EXPECT_NE(caught.err.find("shadowlab gate: error: grazing | " + std::string(kZeroBias) +
                            " | sun: metric \"acne_rate\" is "),
            std::string::npos)
      << caught.err;
  std::ostringstream aliasingLine;
  aliasingLine << "shadowlab gate: error: grazing | " << kDefault << " | sun: metric \"aliasing\" is " << aliasing
               << ", not the baseline " << aliasing * 2 + 100 << " +/- tolerance ";
  EXPECT_NE(caught.err.find(aliasingLine.str()), std::string::npos) << aliasingLine.str() << "\n" << caught.err;
  EXPECT_NE(caught.out.find("FAIL: 2 regressions,"), std::string::npos) << caught.out;
}

TEST_F(Golden, TwoRunsOfTheSameSweepPassEachOtherExactly) {
  // Separate reference caches: the Embree reference is traced twice too. The second run uses one
  // CPU (TBB follows the affinity mask) and one lavapipe thread, the first every core: results
  // must not depend on the thread count. Built-in tolerances are exact for metrics and only report
  // timings, which differ between the runs.
  std::string first = sweep("default", "first", "cache1");
  if (!skipReason_.empty()) GTEST_SKIP() << skipReason_;
  std::string second = sweep("default", "second", "cache2", "LP_NUM_THREADS=1 taskset -c " + firstAllowedCpu() + " ");
  ASSERT_FALSE(HasFailure());
  Cmd gate = shadowlab("gate " + second + " --baseline " + first + " --json " + (dir_ / "gate.json").string());
  EXPECT_EQ(gate.code, 0) << gate.err << gate.out;
  EXPECT_EQ(gate.err, "");
  nlohmann::json report = nlohmann::json::parse(slurp(dir_ / "gate.json"));
  EXPECT_EQ(report["counts"]["regressions"], 0);
  EXPECT_EQ(report["counts"]["improvements"], 0);  // exactly equal: neither better nor worse
  EXPECT_GE(report["counts"]["rows_compared"].get<int>(), 8);
  EXPECT_GT(report["counts"]["reported"].get<int>(), 0);  // the timings, reported only
  for (const auto& check : report["checks"]) {
    if (check["kind"] == "metric") {
      EXPECT_EQ(check["baseline"], check["current"]) << check.dump();
    }
  }
}

}  // namespace

}  // namespace gate_golden_test
