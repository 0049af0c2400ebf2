// SIGTERM or SIGINT during `reference` or `run`: the command removes what it created and has not
// finished (its new output folder, its reference cache lock) and exits 128 + the signal's number;
// a lock file left by a process killed outright (SIGKILL) does not stop the next run. Before, a
// killed command left an empty output folder and an `<entry>.exr.lock` in the cache.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

namespace robustness_signals_test {

namespace {

namespace fs = std::filesystem;

class Signals : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("shadowlab_signals_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    if (!HasFailure()) fs::remove_all(dir_);
  }

  // Starts shadowlab with `args` in dir_ (stdout and stderr to dir_/log.txt), SHADOWLAB_CACHE=dir_/cache.
  pid_t start(const std::vector<std::string>& args) {
    const pid_t pid = ::fork();
    if (pid == 0) {
      if (::chdir(dir_.c_str()) != 0) _exit(99);
      ::setenv("SHADOWLAB_CACHE", (dir_ / "cache").c_str(), 1);
      const std::string log = (dir_ / "log.txt").string();
      if (!std::freopen(log.c_str(), "a", stdout) || !std::freopen(log.c_str(), "a", stderr)) _exit(99);
      std::vector<char*> argv{const_cast<char*>(SHADOWLAB_BINARY)};
      for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
      argv.push_back(nullptr);
      ::execv(SHADOWLAB_BINARY, argv.data());
      _exit(98);
    }
    return pid;
  }
  // Waits until `path` exists (the command is past its checks and tracing), at most 60 s.
  bool waitFor(const fs::path& path) {
    for (int i = 0; i < 600 && !fs::exists(path); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(100));
    return fs::exists(path);
  }
  // The lock files in the cache: "<entry>.exr.lock".
  std::vector<fs::path> locks() const {
    std::vector<fs::path> out;
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(dir_ / "cache", ec))
      if (e.path().extension() == ".lock") out.push_back(e.path());
    return out;
  }
  int finish(pid_t pid) {
    int status = 0;
    ::waitpid(pid, &status, 0);
    return WIFEXITED(status) ? WEXITSTATUS(status) : 1000 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
  }
  fs::path dir_;
};

// soft_post at 4096 light samples per pixel: a trace of many seconds, time enough to interrupt it.
const std::vector<std::string> kLongReference = {"soft_post", "--light-samples", "4096"};

TEST_F(Signals, ReferenceInterruptedBySigtermRemovesItsNewFolderAndExits143) {
  std::vector<std::string> args{"reference"};
  args.insert(args.end(), kLongReference.begin(), kLongReference.end());
  args.insert(args.end(), {"-o", "out/ref"});
  const pid_t pid = start(args);
  ASSERT_TRUE(waitFor(dir_ / "out/ref"));  // claimed: the trace has begun
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  ::kill(pid, SIGTERM);
  EXPECT_EQ(finish(pid), 128 + SIGTERM);
  EXPECT_FALSE(fs::exists(dir_ / "out")) << "the output folder (and its new parent) stayed";
  EXPECT_EQ(std::system(("grep -q 'shadowlab reference: interrupted (SIGTERM): removed 1 unfinished output' '" +
                         (dir_ / "log.txt").string() + "'")
                            .c_str()),
            0);
}

TEST_F(Signals, RunInterruptedBySigintRemovesItsFolderAndLockAndTheNextRunSucceeds) {
  std::vector<std::string> args{"run"};
  args.insert(args.end(), kLongReference.begin(), kLongReference.end());
  args.insert(args.end(), {"--set", "map.size=256", "-o", "out/run"});
  const pid_t pid = start(args);
  ASSERT_TRUE(waitFor(dir_ / "out/run"));
  for (int i = 0; i < 600 && locks().empty(); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(100));
  ASSERT_EQ(locks().size(), 1u) << "the trace never took the cache lock";
  ::kill(pid, SIGINT);
  EXPECT_EQ(finish(pid), 128 + SIGINT);
  EXPECT_FALSE(fs::exists(dir_ / "out"));
  EXPECT_TRUE(locks().empty()) << locks().front();
  EXPECT_TRUE(fs::is_directory(dir_ / "cache")) << "the cache outlives the command";

  // A process killed outright (SIGKILL) leaves its lock file behind, but not the lock: the kernel
  // releases a dead process's flock. The next run of that entry takes it, traces and removes it.
  const std::vector<std::string> small = {"run",   "soft_post",
                                          "--set", "map.size=256",
                                          "--set", "scene:/camera/width=64",
                                          "--set", "scene:/camera/height=36",
                                          "-o",    "out/small"};
  ASSERT_EQ(finish(start(small)), 0);
  std::vector<fs::path> entries;
  for (const auto& e : fs::directory_iterator(dir_ / "cache"))
    if (e.path().extension() == ".exr") entries.push_back(e.path());
  ASSERT_EQ(entries.size(), 1u);
  fs::remove(entries[0]);
  const fs::path stale = entries[0].string() + ".lock";
  {
    std::ofstream(stale) << "";  // what a SIGKILLed trace leaves
  }
  fs::remove_all(dir_ / "out");
  ASSERT_EQ(finish(start(small)), 0);
  EXPECT_TRUE(fs::exists(entries[0])) << "traced again";
  EXPECT_FALSE(fs::exists(stale));
  EXPECT_TRUE(fs::exists(dir_ / "out/small/metrics.json"));
}

}  // namespace

}  // namespace robustness_signals_test
