// Sharded sweeps with an injected fake runner (no renderer): --shard parsing, the round-robin
// share, shards merged equal an unsharded run row for row, and every refusal of the merge
// (missing shard, incomplete shard, another plan, another N, a doctored duplicate row) exits as an
// InputError naming the file and writes no results.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "shadowlab/compare/sweep.h"
#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/io.h"
#include "support/fake_sweep_runner.h"

namespace sweep_shard_test {

namespace fs = std::filesystem;
using namespace shadowlab;

namespace {

using FakeRunner = shadowlab::testing::FakeSweepRunner;

std::string tempDir(const std::string& name) {
  fs::path d = fs::temp_directory_path() / ("shadowlab_sweep_shard_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  return d.string();
}

SweepPlan plan(std::vector<std::string> grid = {"map.size=256,512", "bias.slope=0,1,2"}) {
  SweepSpec spec;
  spec.scenes = {"sphere_on_plane", "contact"};
  for (const auto& g : grid) spec.grid.push_back(parseGridArgument(g));
  return planSweep(spec);
}

SweepOptions quiet(const std::string& dir, size_t index = 0, size_t count = 0) {
  SweepOptions o;
  o.outDir = dir;
  o.progress = nullptr;
  o.writeReport = false;
  o.shard.index = index;
  o.shard.count = count;
  return o;
}

void runShards(const SweepPlan& p, const std::string& dir, size_t n) {
  for (size_t i = 0; i < n; ++i) {
    FakeRunner r;
    runSweep(p, r, quiet(dir, i, n));
  }
}

// The merge's InputError text; fails the test when the merge succeeds.
std::string mergeError(const SweepPlan& p, const std::string& dir) {
  FakeRunner r;
  try {
    mergeSweepShards(p, r, quiet(dir));
  } catch (const InputError& e) {
    return e.what();
  }
  ADD_FAILURE() << "merge of " << dir << " succeeded; expected an InputError";
  return "";
}

std::vector<std::string> lines(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::string> out;
  std::string line;
  while (std::getline(in, line)) out.push_back(line);
  return out;
}

void writeLines(const std::string& path, const std::vector<std::string>& ls) {
  std::ofstream out(path, std::ios::trunc);
  for (const auto& l : ls) out << l << "\n";
}

}  // namespace

TEST(SweepShard, ParsesIOverNAndRefusesTheRest) {
  SweepShard s = parseShardArgument("2/3");
  EXPECT_EQ(s.index, 2u);
  EXPECT_EQ(s.count, 3u);
  EXPECT_TRUE(s.active());
  EXPECT_EQ(parseShardArgument("0/1").count, 1u);
  for (const char* bad : {"3/3", "4/3", "0/0", "1", "a/b", "-1/3", "1/", "/3", "1/3/5", " 1/3", "1/3 ", "+1/3"}) {
    try {
      parseShardArgument(bad);
      ADD_FAILURE() << bad << " was accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(std::string("--shard ") + bad), std::string::npos) << e.what();
    }
  }
  EXPECT_NE(std::string([] {
              try {
                parseShardArgument("3/3");
              } catch (const InputError& e) {
                return std::string(e.what());
              }
              return std::string();
            }())
                .find("0 <= I < N = 3"),
            std::string::npos);
}

TEST(SweepShard, EachShardRunsEveryNthJobIntoItsOwnFolder) {
  const std::string dir = tempDir("share");
  SweepPlan p = plan();  // 2 scenes x 6 configs = 12 jobs
  ASSERT_EQ(p.jobs.size(), 12u);
  size_t sum = 0;
  for (size_t i = 0; i < 5; ++i) {
    FakeRunner r;
    SweepSummary s = runSweep(p, r, quiet(dir, i, 5));
    const size_t share = i < 2 ? 3 : 2;  // 12 = 3 + 3 + 2 + 2 + 2
    EXPECT_EQ(s.configurations, share);
    EXPECT_EQ(s.ran, share);
    EXPECT_EQ(size_t(r.total), share);
    EXPECT_TRUE(s.resultsJson.empty()) << "a shard writes no results";
    const std::string sd = shardDir(dir, {i, 5});
    EXPECT_EQ(sd, dir + "/shards/" + std::to_string(i) + "-of-5");
    auto journal = lines(sd + "/rows.jsonl");
    ASSERT_EQ(journal.size(), share);
    // Row k of shard i is job i + 5k of the plan.
    for (size_t k = 0; k < share; ++k) {
      auto j = nlohmann::json::parse(journal[k]);
      EXPECT_EQ(j.at("row").at("scene").get<std::string>() + " | " + j.at("row").at("config").get<std::string>() +
                    " | " + j.at("row").at("light").get<std::string>(),
                p.jobs[i + 5 * k].key());
      EXPECT_EQ(j.at("shard"), std::to_string(i) + "/5");
    }
    auto meta = nlohmann::json::parse(readFile(sd + "/shard.json"));
    EXPECT_EQ(meta.at("plan_fingerprint"), planFingerprint(p));
    EXPECT_EQ(meta.at("shard_index"), i);
    EXPECT_EQ(meta.at("shard_count"), 5);
    EXPECT_EQ(meta.at("rows_planned"), share);
    sum += share;
  }
  EXPECT_EQ(sum, p.jobs.size());
  EXPECT_FALSE(fs::exists(dir + "/results.json"));
  EXPECT_FALSE(fs::exists(dir + "/rows.jsonl"));
  // Resumable like an unsharded sweep: running a shard again runs nothing.
  FakeRunner again;
  SweepSummary s = runSweep(p, again, quiet(dir, 1, 5));
  EXPECT_EQ(again.total, 0);
  EXPECT_EQ(s.resumed, 3u);
  fs::remove_all(dir);
}

TEST(SweepShard, FingerprintFollowsThePlanNotThePaths) {
  EXPECT_EQ(planFingerprint(plan()), planFingerprint(plan()));
  EXPECT_NE(planFingerprint(plan()), planFingerprint(plan({"map.size=256,1024", "bias.slope=0,1,2"})));
  SweepSpec spec = plan().spec;
  spec.fixed.push_back(parseSetArgument("filter=pcf"));
  EXPECT_NE(planFingerprint(plan()), planFingerprint(planSweep(spec)));
  // The recorded spec plans the same sweep again.
  SweepPlan p = plan();
  SweepSpec back = sweepSpecFromJson(sweepSpecToJson(p), "shard.json");
  EXPECT_EQ(planFingerprint(planSweep(back)), planFingerprint(p));
}

// A union of grids (sweep files' "grid" as an array) survives the shard description: each axis keeps
// its block, so a shard plans the same configurations (without the block, block 1's fit axis would
// join block 0 and the plan would grow).
TEST(SweepShard, UnionOfGridsRoundTripsThroughTheShardDescription) {
  SweepSpec spec;
  spec.scenes = {"sphere_on_plane"};
  SweepAxis size = parseGridArgument("map.size=256,512"), filter = parseGridArgument("filter=none,pcf"),
            fit = parseGridArgument("fit=lispsm,tight");
  size.block = 0;
  filter.block = 0;
  fit.block = 1;
  spec.grid = {size, filter, fit};
  SweepPlan p = planSweep(spec);
  ASSERT_EQ(p.configs.size(), 6u);  // 2 x 2, then 2
  SweepSpec back = sweepSpecFromJson(sweepSpecToJson(p), "shard.json");
  ASSERT_EQ(back.grid.size(), 3u);
  EXPECT_EQ(back.grid[2].block, 1);
  SweepPlan again = planSweep(back);
  ASSERT_EQ(again.configs.size(), p.configs.size());
  for (size_t i = 0; i < p.configs.size(); ++i) EXPECT_EQ(again.configs[i].config, p.configs[i].config);
  EXPECT_EQ(planFingerprint(again), planFingerprint(p));
}

TEST(SweepShard, MergedShardsEqualAnUnshardedRun) {
  const std::string one = tempDir("unsharded"), many = tempDir("merged");
  SweepPlan p = plan();
  FakeRunner r;
  runSweep(p, r, quiet(one));
  runShards(p, many, 3);
  SweepPlan again = planSweep(loadShardedSpec(many));
  FakeRunner m;
  SweepSummary s = mergeSweepShards(again, m, quiet(many));
  EXPECT_EQ(m.total, 0) << "the merge runs nothing";
  EXPECT_EQ(s.resultsJson, many + "/results.json");
  auto a = loadResultRows(one + "/results.json"), b = loadResultRows(many + "/results.json");
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].key(), b[i].key());
    EXPECT_EQ(a[i].method, b[i].method);
    EXPECT_EQ(a[i].metrics, b[i].metrics) << a[i].key();
  }
  auto results = nlohmann::json::parse(readFile(many + "/results.json"));
  EXPECT_EQ(results.at("shards"), 3);
  EXPECT_EQ(results.at("plan_fingerprint"), planFingerprint(p));
  // The CSV agrees apart from the timing columns.
  auto ca = lines(one + "/results.csv"), cb = lines(many + "/results.csv");
  ASSERT_EQ(ca.size(), cb.size());
  EXPECT_EQ(ca[0], cb[0]);
  fs::remove_all(one);
  fs::remove_all(many);
}

TEST(SweepShard, MergeRefusesAMissingShardNamingIt) {
  const std::string dir = tempDir("missing");
  SweepPlan p = plan();
  for (size_t i : {0u, 2u}) {
    FakeRunner r;
    runSweep(p, r, quiet(dir, i, 4));
  }
  const std::string err = mergeError(p, dir);
  EXPECT_NE(err.find("missing shard(s) 1, 3 of 4"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(dir + "/results.json"));
  fs::remove_all(dir);
}

TEST(SweepShard, MergeRefusesAnIncompleteShard) {
  const std::string dir = tempDir("incomplete");
  SweepPlan p = plan();
  runShards(p, dir, 3);
  const std::string journal = shardDir(dir, {1, 3}) + "/rows.jsonl";
  auto ls = lines(journal);
  ASSERT_EQ(ls.size(), 4u);
  ls.pop_back();
  writeLines(journal, ls);
  const std::string err = mergeError(p, dir);
  EXPECT_NE(err.find(journal), std::string::npos) << err;
  EXPECT_NE(err.find("incomplete: 3 of its 4 rows"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(dir + "/results.json"));
  // A torn last line (a shard killed mid-append) is incomplete too, and the merge leaves it as is.
  std::ofstream(journal, std::ios::app) << "{\"row\": {\"sce";
  const auto size = fs::file_size(journal);
  EXPECT_NE(mergeError(p, dir).find("incomplete: 3 of its 4 rows"), std::string::npos);
  EXPECT_EQ(fs::file_size(journal), size) << "the merge never writes into a shard's journal";
  // Running the shard again completes it, and the merge then succeeds.
  FakeRunner r;
  EXPECT_EQ(runSweep(p, r, quiet(dir, 1, 3)).ran, 1u);
  FakeRunner m;
  EXPECT_NO_THROW(mergeSweepShards(p, m, quiet(dir)));
  fs::remove_all(dir);
}

TEST(SweepShard, MergeRefusesShardsOfAnotherPlanOrAnotherN) {
  const std::string dir = tempDir("plans");
  SweepPlan p = plan(), other = plan({"map.size=256,1024", "bias.slope=0,1,2"});
  {
    FakeRunner r;
    runSweep(p, r, quiet(dir, 0, 2));
    runSweep(other, r, quiet(dir, 1, 2));
  }
  std::string err = mergeError(p, dir);
  EXPECT_NE(err.find(shardDir(dir, {1, 2}) + "/shard.json"), std::string::npos) << err;
  EXPECT_NE(err.find("plan " + planFingerprint(other) + " differs from plan " + planFingerprint(p)), std::string::npos)
      << err;
  // A shard folder of one plan refuses to run another plan.
  FakeRunner r;
  try {
    runSweep(p, r, quiet(dir, 1, 2));
    ADD_FAILURE() << "ran plan p in a shard folder of another plan";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("shard.json"), std::string::npos) << e.what();
  }
  fs::remove_all(dir);

  // Same plan, shards of 2 and of 3 side by side.
  runShards(p, dir, 2);
  runSweep(p, r, quiet(dir, 2, 3));
  err = mergeError(p, dir);
  EXPECT_NE(err.find("N is 3"), std::string::npos) << err;
  EXPECT_NE(err.find(shardDir(dir, {2, 3}) + "/shard.json"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(dir + "/results.json"));
  fs::remove_all(dir);
}

TEST(SweepShard, MergeRefusesADoctoredDuplicateRow) {
  const std::string dir = tempDir("doctored");
  SweepPlan p = plan();
  runShards(p, dir, 2);
  // Shard 1's journal gains a copy of shard 0's first row with another error_rate.
  auto first = nlohmann::json::parse(lines(shardDir(dir, {0, 2}) + "/rows.jsonl").front());
  const std::string key = first.at("row").at("scene").get<std::string>() + " | " +
                          first.at("row").at("config").get<std::string>() + " | " +
                          first.at("row").at("light").get<std::string>();
  first["row"]["metrics"]["error_rate"] = 0.999;
  const std::string journal = shardDir(dir, {1, 2}) + "/rows.jsonl";
  std::ofstream(journal, std::ios::app) << first.dump() << "\n";
  const std::string err = mergeError(p, dir);
  EXPECT_NE(err.find(journal), std::string::npos) << err;
  EXPECT_NE(err.find("row \"" + key + "\" is also in"), std::string::npos) << err;
  EXPECT_NE(err.find("different metrics"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(dir + "/results.json"));
  // The same copy with the same metrics is harmless (e.g. a row re-run by hand).
  auto ls = lines(journal);
  first["row"]["metrics"] =
      nlohmann::json::parse(lines(shardDir(dir, {0, 2}) + "/rows.jsonl").front())["row"]["metrics"];
  ls.back() = first.dump();
  writeLines(journal, ls);
  FakeRunner m;
  EXPECT_NO_THROW(mergeSweepShards(p, m, quiet(dir)));
  fs::remove_all(dir);
}

TEST(SweepShard, MergeWithNoShardsSaysWhatItExpected) {
  const std::string dir = tempDir("none");
  fs::create_directories(dir);
  const std::string err = mergeError(plan(), dir);
  EXPECT_NE(err.find(dir + "/shards"), std::string::npos) << err;
  EXPECT_NE(err.find("--shard I/N"), std::string::npos) << err;
  try {
    loadShardedSpec(dir);
    ADD_FAILURE() << "a spec from no shards";
  } catch (const InputError&) {
  }
  fs::remove_all(dir);
}

}  // namespace sweep_shard_test
