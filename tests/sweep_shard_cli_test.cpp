// Sharded sweeps through the real binary with the real renderers: a bad --shard exits 2 and
// writes nothing; 3 shards merged by `shadowlab merge` give exactly the metrics of an unsharded run
// of the same plan (2 scenes x 4 configurations at 64x48); a doctored shard journal makes the merge
// exit 2 naming the file; a truncated or foreign reference cache entry is traced again and the
// metrics stay identical; a process that misses a reference another one is tracing waits for it
// instead of tracing it too; a shard SIGKILLed midway resumes and the merge still equals the
// unsharded run.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <thread>

#include <nlohmann/json.hpp>

#include "shadowlab/compare/results.h"
#include "shadowlab/scenes/frame.h"
#include "shadowlab/scenes/io.h"
#include "support/cli.h"

namespace sweep_shard_cli_test {

namespace fs = std::filesystem;
using namespace shadowlab;
using shadowlab::testing::runShadowlab;

namespace {

fs::path tempDir(const std::string& name) {
  fs::path d = fs::temp_directory_path() / ("shadowlab_shard_cli_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

// The small plan: 2 scenes x 4 configurations at a small camera.
const std::string kPlan =
    "sphere_on_plane contact --grid map.size=128,512 --grid bias.slope=0,2 "
    "--set scene:/camera/width=64 --set scene:/camera/height=48 --no-report";

double seconds(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

void expectSameMetrics(const fs::path& a, const fs::path& b) {
  auto ra = loadResultRows(a.string()), rb = loadResultRows(b.string());
  ASSERT_EQ(ra.size(), rb.size());
  for (size_t i = 0; i < ra.size(); ++i) {
    EXPECT_EQ(ra[i].key(), rb[i].key());
    EXPECT_EQ(ra[i].method, rb[i].method) << ra[i].key();
    EXPECT_EQ(ra[i].metrics, rb[i].metrics) << ra[i].key() << ": every metric must match exactly";
  }
}

// Complete lines (ending in a newline) of a journal; a torn last line does not count.
size_t completeLines(const fs::path& journal) {
  const std::string text = shadowlab::testing::slurp(journal);
  return size_t(std::count(text.begin(), text.end(), '\n'));
}

// Starts SHADOWLAB_BINARY with `args` (no shell), stdout and stderr into `dir`; returns its pid.
pid_t spawnShadowlab(const std::vector<std::string>& args, const fs::path& dir) {
  std::vector<std::string> all = {SHADOWLAB_BINARY};
  all.insert(all.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& a : all) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t files;
  posix_spawn_file_actions_init(&files);
  posix_spawn_file_actions_addopen(&files, STDOUT_FILENO, (dir / "spawn_stdout.txt").c_str(),
                                   O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&files, STDERR_FILENO, (dir / "spawn_stderr.txt").c_str(),
                                   O_WRONLY | O_CREAT | O_TRUNC, 0644);
  pid_t pid = -1;
  const int rc = posix_spawn(&pid, SHADOWLAB_BINARY, &files, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&files);
  return rc == 0 ? pid : -1;
}

}  // namespace

TEST(SweepShardCli, BadShardExitsTwoAndWritesNothing) {
  const fs::path dir = tempDir("bad");
  for (const char* bad : {"3/3", "0/0", "two", "1/", "-1/2"}) {
    const fs::path out = dir / "out";
    auto r = runShadowlab("sweep sphere_on_plane --grid map.size=128,256 --shard '" + std::string(bad) + "' -o '" +
                              out.string() + "' --cache '" + (dir / "cache").string() + "'",
                          dir);
    EXPECT_EQ(r.code, 2) << bad << "\n" << r.err;
    EXPECT_NE(r.err.find(std::string("--shard ") + bad), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out)) << bad << ": nothing may be written";
    EXPECT_FALSE(fs::exists(dir / "cache")) << bad;
  }
  auto r = runShadowlab("merge '" + (dir / "nothing").string() + "'", dir);
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("shards"), std::string::npos) << r.err;
  fs::remove_all(dir);
}

TEST(SweepShardCli, ThreeShardsMergedEqualAnUnshardedRunInEveryMetric) {
  const fs::path dir = tempDir("merge");
  const std::string cache = " --cache '" + (dir / "cache").string() + "'";
  // Warm the reference cache first so neither timing below includes tracing.
  auto warm = runShadowlab("sweep sphere_on_plane contact --grid map.size=16 --set scene:/camera/width=64 "
                           "--set scene:/camera/height=48 --no-report -o '" + (dir / "warm").string() + "'" + cache, dir);
  ASSERT_EQ(warm.code, 0) << warm.err;

  auto t0 = std::chrono::steady_clock::now();
  auto one = runShadowlab("sweep " + kPlan + " -o '" + (dir / "one").string() + "'" + cache, dir);
  const double unsharded = seconds(t0);
  ASSERT_EQ(one.code, 0) << one.err;

  const fs::path many = dir / "many";
  double slowest = 0;
  for (int i = 0; i < 3; ++i) {
    t0 = std::chrono::steady_clock::now();
    auto r =
        runShadowlab("sweep " + kPlan + " --shard " + std::to_string(i) + "/3 -o '" + many.string() + "'" + cache, dir);
    slowest = std::max(slowest, seconds(t0));
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.out.find("shadowlab merge"), std::string::npos) << r.out;
    EXPECT_TRUE(fs::exists(many / "shards" / (std::to_string(i) + "-of-3") / "rows.jsonl"));
  }
  EXPECT_FALSE(fs::exists(many / "results.json")) << "shards write no results";
  EXPECT_FALSE(fs::exists(many / "report.html"));
  t0 = std::chrono::steady_clock::now();
  auto m = runShadowlab("merge '" + many.string() + "' --no-report" + cache, dir);
  const double merge = seconds(t0);
  ASSERT_EQ(m.code, 0) << m.err;
  std::printf(
      "timing: unsharded %.2f s; slowest of 3 shards %.2f s; merge %.2f s (shards run one after another here)\n",
      unsharded, slowest, merge);
  expectSameMetrics(dir / "one" / "results.json", many / "results.json");
  EXPECT_EQ(loadResultRows((many / "results.json").string()).size(), 8u);

  // A doctored journal: shard 2 gains a copy of shard 0's first row with another error_rate.
  const fs::path journal0 = many / "shards" / "0-of-3" / "rows.jsonl",
                 journal2 = many / "shards" / "2-of-3" / "rows.jsonl";
  std::string first;
  {
    std::ifstream in(journal0);
    std::getline(in, first);
  }
  auto row = nlohmann::json::parse(first);
  row["row"]["metrics"]["error_rate"] = row["row"]["metrics"]["error_rate"].get<double>() + 0.25;
  std::ofstream(journal2, std::ios::app) << row.dump() << "\n";
  fs::remove(many / "results.json");
  fs::remove(many / "results.csv");
  auto bad = runShadowlab("merge '" + many.string() + "' --no-report" + cache, dir);
  EXPECT_EQ(bad.code, 2) << bad.err;
  EXPECT_NE(bad.err.find(journal2.string()), std::string::npos) << bad.err;
  EXPECT_NE(bad.err.find("different metrics"), std::string::npos) << bad.err;
  EXPECT_FALSE(fs::exists(many / "results.json")) << "a refused merge writes nothing";

  // A missing shard is named.
  fs::remove_all(many / "shards" / "1-of-3");
  bad = runShadowlab("merge '" + many.string() + "' --no-report" + cache, dir);
  EXPECT_EQ(bad.code, 2) << bad.err;
  EXPECT_NE(bad.err.find("missing shard(s) 1 of 3"), std::string::npos) << bad.err;
  fs::remove_all(dir);
}

TEST(SweepShardCli, DamagedReferenceCacheEntriesAreTracedAgainWithIdenticalMetrics) {
  const fs::path dir = tempDir("cache");
  const fs::path cache = dir / "cache";
  const std::string args =
      "sweep sphere_on_plane contact --grid map.size=256 --set scene:/camera/width=64 "
      "--set scene:/camera/height=48 --no-report --cache '" +
      cache.string() + "'";
  auto first = runShadowlab(args + " -o '" + (dir / "a").string() + "'", dir);
  ASSERT_EQ(first.code, 0) << first.err;
  std::vector<fs::path> entries;
  for (const auto& e : fs::directory_iterator(cache))
    if (e.path().extension() == ".exr") entries.push_back(e.path());
  std::sort(entries.begin(), entries.end());
  ASSERT_EQ(entries.size(), 2u) << "one reference per scene";
  // No temporary file is left beside the entries (they are written under a temp name, then renamed).
  for (const auto& e : fs::directory_iterator(cache)) EXPECT_EQ(e.path().extension(), ".exr") << e.path();
  const auto size0 = fs::file_size(entries[0]);
  const nlohmann::json hash0 = readFrameExr(entries[0].string()).meta.at("scene_hash");
  const nlohmann::json hash1 = readFrameExr(entries[1].string()).meta.at("scene_hash");

  // Entry 0 truncated to half; entry 1 replaced by entry 0's intact bytes (a readable frame whose
  // scene_hash names the other scene).
  fs::copy_file(entries[0], entries[1], fs::copy_options::overwrite_existing);
  fs::resize_file(entries[0], size0 / 2);
  auto second = runShadowlab(args + " -o '" + (dir / "b").string() + "'", dir);
  ASSERT_EQ(second.code, 0) << second.err;
  expectSameMetrics(dir / "a" / "results.json", dir / "b" / "results.json");
  // Both entries were traced again and replaced by whole files naming their own scenes again.
  const Frame a = readFrameExr(entries[0].string()), b = readFrameExr(entries[1].string());
  EXPECT_EQ(a.meta.at("scene_hash"), hash0);
  EXPECT_EQ(b.meta.at("scene_hash"), hash1);
  EXPECT_NE(hash0, hash1);
  fs::remove_all(dir);
}

// A scene's reference is read on a thread of its own while its first row renders
// (compare/study/src/sweep_runner.cpp). When that read fails (here: the second scene's entry is a
// folder, so the trace cannot be stored), the sweep still exits 2 naming the entry, after the
// first scene's rows, and writes no row of the failed scene and no results.
TEST(SweepShardCli, AReferenceThatCannotBeReadMidSweepExits2NamingTheEntry) {
  const fs::path dir = tempDir("unreadable");
  const fs::path cache = dir / "cache";
  const std::string args =
      "sweep sphere_on_plane contact --grid map.size=256,512 --set scene:/camera/width=64 "
      "--set scene:/camera/height=48 --no-report --cache '" +
      cache.string() + "'";
  auto first = runShadowlab(args + " -o '" + (dir / "a").string() + "'", dir);
  ASSERT_EQ(first.code, 0) << first.err;
  fs::path contactEntry;
  for (const auto& e : fs::directory_iterator(cache))
    if (readFrameExr(e.path().string()).meta.value("scene", "") == "contact") contactEntry = e.path();
  ASSERT_FALSE(contactEntry.empty()) << "no cache entry names the scene contact";
  fs::remove(contactEntry);
  fs::create_directories(contactEntry / "in-the-way");

  const fs::path out = dir / "b";
  auto r = runShadowlab(args + " -o '" + out.string() + "'", dir);
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find(contactEntry.string() + ": error: cannot write image"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out / "results.json"));
  const std::string journal = readFile((out / "rows.jsonl").string());
  EXPECT_EQ(std::count(journal.begin(), journal.end(), '\n'), 2) << "the two rows of sphere_on_plane only:\n"
                                                                 << journal;
  EXPECT_EQ(journal.find("contact"), std::string::npos) << journal;
  fs::remove_all(dir);
}

TEST(SweepShardCli, SlurmScriptsRunAsAnArrayThenMergeToTheUnshardedMetrics) {
  const fs::path dir = tempDir("slurm");
  const std::string cache = " --cache '" + (dir / "cache").string() + "'";
  const fs::path gen = dir / "gen";
  auto r = runShadowlab(
      "sweep " + kPlan + " --slurm 3 --slurm-opt='--partition=debug --time=10' -o '" + gen.string() + "'" + cache, dir);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_FALSE(fs::exists(gen / "rows.jsonl")) << "--slurm runs nothing";
  EXPECT_FALSE(fs::exists(gen / "shards" / "0-of-3")) << "--slurm runs nothing";
  const std::string sweep = readFile((gen / "sweep.sbatch").string()),
                    merge = readFile((gen / "merge.sbatch").string());
  for (const char* want :
       {"#!/bin/bash\n", "\n#SBATCH --array=0-2\n", "\n#SBATCH --partition=debug\n", "\n#SBATCH --time=10\n",
        " sweep 'sphere_on_plane' 'contact' --grid 'map.size=128,512' "
        "--grid 'bias.slope=0,2' --set 'scene:/camera/width=64' --set 'scene:/camera/height=48' ",
        " --shard \"$SLURM_ARRAY_TASK_ID/3\"\n"})
    EXPECT_NE(sweep.find(want), std::string::npos) << "missing: " << want << "\n" << sweep;
  EXPECT_NE(sweep.find("-o '" + gen.string() + "'"), std::string::npos) << sweep;
  for (const char* want : {"#!/bin/bash\n", "\n#SBATCH --partition=debug\n", " merge '", " --no-report\n"})
    EXPECT_NE(merge.find(want), std::string::npos) << "missing: " << want << "\n" << merge;
  EXPECT_EQ(merge.find("--array"), std::string::npos) << merge;
  EXPECT_NE(r.out.find("sbatch --parsable '" + (gen / "sweep.sbatch").string() + "'"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("sbatch --dependency=afterok:$jobid '" + (gen / "merge.sbatch").string() + "'"),
            std::string::npos)
      << r.out;

  // What Slurm would do: each array task with its SLURM_ARRAY_TASK_ID, then the merge.
  for (int i = 0; i < 3; ++i) {
    const std::string cmd = "SLURM_ARRAY_TASK_ID=" + std::to_string(i) + " bash '" + (gen / "sweep.sbatch").string() +
                            "' >'" + (dir / "task.log").string() + "' 2>&1";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << readFile((dir / "task.log").string());
  }
  ASSERT_EQ(
      std::system(
          ("bash '" + (gen / "merge.sbatch").string() + "' >'" + (dir / "merge.log").string() + "' 2>&1").c_str()),
      0)
      << readFile((dir / "merge.log").string());
  auto one = runShadowlab("sweep " + kPlan + " -o '" + (dir / "one").string() + "'" + cache, dir);
  ASSERT_EQ(one.code, 0) << one.err;
  expectSameMetrics(dir / "one" / "results.json", gen / "results.json");
  fs::remove_all(dir);
}

TEST(SweepShardCli, SlurmSubmitWithoutSbatchExitsTwoAndWritesNothing) {
  const fs::path dir = tempDir("nosbatch");
  auto r = runShadowlab("sweep sphere_on_plane --slurm 2 --submit -o '" + (dir / "out").string() + "'", dir,
                        "PATH=/nonexistent ");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("no Slurm installed (sbatch not found"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "out"));
  for (const char* bad : {"0", "x", "-1"}) {
    r = runShadowlab("sweep sphere_on_plane --slurm=" + std::string(bad) + " -o '" + (dir / "out").string() + "'", dir);
    EXPECT_EQ(r.code, 2) << bad << "\n" << r.err;
    EXPECT_NE(r.err.find(std::string("--slurm ") + bad), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir / "out")) << bad;
  }
  r = runShadowlab("sweep sphere_on_plane --slurm 2 --shard 0/2 -o '" + (dir / "out").string() + "'", dir);
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_FALSE(fs::exists(dir / "out"));
  fs::remove_all(dir);
}

TEST(SweepShardCli, SlurmSubmitRunsTheArrayThenTheMergeAfterIt) {
  const fs::path dir = tempDir("submit");
  // A stand-in sbatch: records its arguments, answers job id 4242 (then 4243) like --parsable.
  fs::create_directories(dir / "bin");
  const fs::path calls = dir / "calls.txt";
  {
    std::ofstream f(dir / "bin" / "sbatch");
    f << "#!/bin/sh\necho \"$*\" >> '" << calls.string() << "'\nn=$(wc -l < '" << calls.string()
      << "')\necho $((4241 + n))\n";
  }
  fs::permissions(dir / "bin" / "sbatch", fs::perms::owner_all);
  const fs::path out = dir / "out";
  auto r = runShadowlab("sweep sphere_on_plane --grid map.size=128,256 --slurm 2 --submit -o '" + out.string() + "'",
                        dir, "PATH='" + (dir / "bin").string() + "':\"$PATH\" ");
  ASSERT_EQ(r.code, 0) << r.err;
  std::ifstream in(calls);
  std::string first, second;
  std::getline(in, first);
  std::getline(in, second);
  EXPECT_EQ(first, "--parsable " + (out / "sweep.sbatch").string());
  EXPECT_EQ(second, "--parsable --dependency=afterok:4242 " + (out / "merge.sbatch").string());
  EXPECT_NE(r.out.find("job 4242"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("job 4243"), std::string::npos) << r.out;
  fs::remove_all(dir);
}

// A shard killed (SIGKILL) midway: the test freezes the running shard with SIGSTOP, reads its
// journal while it cannot write, and kills it only once it holds at least a third of its rows and
// fewer than all (else it lets it go on with SIGCONT and looks again). So the kill always lands midway,
// perhaps in the middle of appending a row, whatever the machine's speed. Running the same command
// again resumes the rows already saved; the merge then equals an unsharded run in every metric.
TEST(SweepShardCli, AShardKilledMidwayResumesAndTheMergeStillEqualsTheUnshardedRun) {
  const fs::path dir = tempDir("kill");
  const std::vector<std::string> plan = {"sphere_on_plane",
                                         "contact",
                                         "--grid",
                                         "map.size=128,256,512,1024",
                                         "--grid",
                                         "bias.slope=0,1,2",
                                         "--set",
                                         "scene:/camera/width=128",
                                         "--set",
                                         "scene:/camera/height=96",
                                         "--no-report",
                                         "--cache",
                                         (dir / "cache").string()};
  std::string planLine;
  for (const auto& a : plan) planLine += " '" + a + "'";
  const fs::path many = dir / "many";
  const fs::path journal = many / "shards" / "0-of-2" / "rows.jsonl";
  const size_t share = 12;  // 2 scenes x 12 configurations, every 2nd row

  std::vector<std::string> shard0 = {"sweep"};
  shard0.insert(shard0.end(), plan.begin(), plan.end());
  for (const char* a : {"--shard", "0/2", "-o"}) shard0.push_back(a);
  shard0.push_back(many.string());
  const pid_t pid = spawnShadowlab(shard0, dir);
  ASSERT_GT(pid, 0) << "cannot start " << SHADOWLAB_BINARY;
  size_t rowsAtKill = 0;
  bool killed = false;
  for (int look = 0; look < 200000 && !killed; ++look) {
    ASSERT_EQ(::kill(pid, SIGSTOP), 0);
    int status = 0;
    ASSERT_EQ(::waitpid(pid, &status, WUNTRACED), pid);
    ASSERT_TRUE(WIFSTOPPED(status)) << "the shard ended before it could be stopped midway (status " << status
                                    << "); stderr:\n"
                                    << shadowlab::testing::slurp(dir / "spawn_stderr.txt");
    const size_t rows = fs::exists(journal) ? completeLines(journal) : 0;
    ASSERT_LT(rows, share) << "the shard saved all its rows between two looks";
    if (rows >= share / 3) {
      rowsAtKill = rows;
      ASSERT_EQ(::kill(pid, SIGKILL), 0);
      killed = true;
    }
    ASSERT_EQ(::kill(pid, SIGCONT), 0);
    if (!killed) std::this_thread::sleep_for(std::chrono::milliseconds(2));  // pacing only: each look is exact
  }
  ASSERT_TRUE(killed) << "no row after 200000 looks";
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL) << "status " << status;
  std::printf("killed shard 0/2 with %zu of its %zu rows saved\n", rowsAtKill, share);

  // The merge refuses the incomplete shard (naming it), then the same command resumes it.
  auto r = runShadowlab("sweep" + planLine + " --shard 1/2 -o '" + many.string() + "'", dir);
  ASSERT_EQ(r.code, 0) << r.err;
  auto m = runShadowlab("merge '" + many.string() + "' --no-report --cache '" + (dir / "cache").string() + "'", dir);
  EXPECT_EQ(m.code, 2) << m.err;
  EXPECT_NE(m.err.find("0-of-2"), std::string::npos) << m.err;
  EXPECT_FALSE(fs::exists(many / "results.json"));
  r = runShadowlab("sweep" + planLine + " --shard 0/2 -o '" + many.string() + "'", dir);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("sweep: " + std::to_string(share) + " rows (" + std::to_string(share - rowsAtKill) + " run, " +
                       std::to_string(rowsAtKill) + " resumed)"),
            std::string::npos)
      << r.out;
  EXPECT_EQ(completeLines(journal), share) << "one complete line per row, the torn one (if any) replaced";
  m = runShadowlab("merge '" + many.string() + "' --no-report --cache '" + (dir / "cache").string() + "'", dir);
  ASSERT_EQ(m.code, 0) << m.err;

  auto one = runShadowlab("sweep" + planLine + " -o '" + (dir / "one").string() + "'", dir);
  ASSERT_EQ(one.code, 0) << one.err;
  expectSameMetrics(dir / "one" / "results.json", many / "results.json");
  EXPECT_EQ(loadResultRows((many / "results.json").string()).size(), 2 * share);
  fs::remove_all(dir);
}

// Two processes that miss the same reference at once trace it once: the second waits on the
// entry's lock file and then reads the entry. The test holds that lock itself (as a process that is
// tracing would), waits until the kernel lists the sweep as blocked on it (/proc/locks), puts the
// entry in place and lets go: the sweep must load it (references_traced 0). A sweep that traced
// instead of waiting never shows up as blocked and fails here.
TEST(SweepShardCli, AProcessMissingAReferenceAnotherIsTracingWaitsForItInsteadOfTracingItToo) {
  const fs::path dir = tempDir("lock");
  const fs::path cache = dir / "cache";
  const std::vector<std::string> args = {
      "sweep", "sphere_on_plane",         "--grid",      "map.size=256", "--set",       "scene:/camera/width=64",
      "--set", "scene:/camera/height=48", "--no-report", "--cache",      cache.string()};
  std::string line;
  for (const auto& a : args) line += " '" + a + "'";
  auto first = runShadowlab(line.substr(1) + " -o '" + (dir / "a").string() + "'", dir);
  ASSERT_EQ(first.code, 0) << first.err;
  fs::path entry;
  for (const auto& e : fs::directory_iterator(cache)) entry = e.path();
  ASSERT_EQ(entry.extension(), ".exr");
  fs::rename(entry, dir / "saved.exr");

  const fs::path lockPath = entry.string() + ".lock";
  const int fd = ::open(lockPath.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::flock(fd, LOCK_EX), 0);
  struct stat st {};
  ASSERT_EQ(::fstat(fd, &st), 0);
  const std::string inode = ":" + std::to_string(st.st_ino) + " ";

  std::vector<std::string> second = args;
  second.push_back("-o");
  second.push_back((dir / "b").string());
  const pid_t pid = spawnShadowlab(second, dir);
  ASSERT_GT(pid, 0);
  bool blocked = false;
  int status = 0;
  for (int look = 0; look < 300000 && !blocked; ++look) {
    std::ifstream locks("/proc/locks");
    std::string l;
    while (std::getline(locks, l))
      if (l.find("->") != std::string::npos && l.find(" " + std::to_string(pid) + " ") != std::string::npos &&
          l.find(inode) != std::string::npos)
        blocked = true;
    if (blocked) break;
    if (::waitpid(pid, &status, WNOHANG) == pid) break;  // it ended without waiting
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  // The entry appears (atomically, as a tracing process writes it), then the lock is let go.
  fs::copy_file(dir / "saved.exr", dir / "entry.tmp");
  fs::rename(dir / "entry.tmp", entry);
  ::close(fd);
  if (blocked) {
    ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  }
  EXPECT_TRUE(blocked) << "the second sweep traced the reference itself instead of waiting on " << lockPath;
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "status " << status << "\n"
                                                             << shadowlab::testing::slurp(dir / "spawn_stderr.txt");
  const auto runner = nlohmann::json::parse(readFile((dir / "b" / "results.json").string())).at("runner");
  EXPECT_EQ(runner.at("references_traced"), 0) << runner.dump();
  EXPECT_EQ(runner.at("references_loaded"), 1) << runner.dump();
  expectSameMetrics(dir / "a" / "results.json", dir / "b" / "results.json");
  EXPECT_FALSE(fs::exists(lockPath)) << "the lock file is removed once the entry is there";
  fs::remove_all(dir);
}

}  // namespace sweep_shard_cli_test
