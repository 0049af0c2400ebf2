// A clone is the whole project: the main job's sweep (scripts/main.sh runs
// `shadowlab sweep --sweep compare/report/default_sweep.json`) succeeds over every bundled scene with
// SHADOWLAB_SHARED_DIR pointing at a folder that does not exist, so no bundled scene reads a shared
// asset. The negative control shows the check can fail: the bunny scene naming its mesh as
// ${SHARED}/bunny.obj exits 2 under the same environment.
// The grid is cut to one configuration per scene (--grid replaces the file's axes) to keep the test
// cheap; the scenes, the sweep file and the report are the main job's.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <map>

#include <nlohmann/json.hpp>

#include "shadowlab/scenes/io.h"
#include "shadowlab/scenes/loader.h"
#include "support/cli.h"

namespace sweep_runs_anywhere_test {

namespace fs = std::filesystem;
using namespace shadowlab;

namespace {

fs::path freshDir(const std::string& name) {
  fs::path d = fs::temp_directory_path() / ("shadowlab_runs_anywhere_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

// The environment of a machine without the shared folder.
std::string noSharedPrefix(const fs::path& dir) {
  return "SHADOWLAB_SHARED_DIR='" + (dir / "no_such_shared_folder").string() + "' ";
}

// fit=sphere: the default sweep's second grid (the fits) collapses onto the first one's row.
const char* kSmallGrid = "--grid map.size=512 --grid bias.slope=1 --grid filter=pcf --grid fit=sphere";

}  // namespace

TEST(RunsAnywhere, MainSweepNeedsNoSharedFolder) {
  const fs::path dir = freshDir("main");
  ASSERT_FALSE(fs::exists(dir / "no_such_shared_folder"));
  const std::string sweepFile = std::string(SHADOWLAB_SOURCE_DIR) + "/compare/report/default_sweep.json";
  const auto r =
      shadowlab::testing::runShadowlab("sweep --sweep '" + sweepFile + "' " + kSmallGrid + " -o '" +
                                           (dir / "out").string() + "' --cache '" + (dir / "cache").string() + "'",
                                       dir, noSharedPrefix(dir));
  ASSERT_EQ(r.code, 0) << "stdout:\n" << r.out << "\nstderr:\n" << r.err;
  const nlohmann::json results = nlohmann::json::parse(readFile((dir / "out" / "results.json").string()));
  std::map<std::string, int> rowsPerScene;
  for (const auto& row : results.at("rows")) rowsPerScene[row.at("scene").get<std::string>()] += 1;
  const std::vector<std::string> bundled = bundledSceneNames();
  ASSERT_GE(bundled.size(), 8u) << "the bundled scenes went missing from " << bundledScenesDir();
  ASSERT_NE(std::find(bundled.begin(), bundled.end(), "bunny"), bundled.end());
  for (const auto& scene : bundled) EXPECT_GE(rowsPerScene[scene], 1) << scene << " has no row in results.json";
  EXPECT_TRUE(fs::is_regular_file(dir / "out" / "report.html")) << r.err;
  fs::remove_all(dir);
}

TEST(RunsAnywhere, ASceneNamingASharedAssetFailsWithoutTheSharedFolder) {
  const fs::path dir = freshDir("control");
  // bunny.json with its mesh moved to the shared folder; everything else as bundled.
  std::string text = readFile(bundledScenesDir() + "/bunny.json");
  const std::string from = "\"path\": \"assets/bunny.obj\"";
  const size_t at = text.find(from);
  ASSERT_NE(at, std::string::npos) << "bunny.json no longer names assets/bunny.obj; update this control";
  text.replace(at, from.size(), "\"path\": \"${SHARED}/bunny.obj\"");
  { std::ofstream(dir / "bunny_shared.json") << text; }
  const auto r =
      shadowlab::testing::runShadowlab("sweep '" + (dir / "bunny_shared.json").string() + "' " + kSmallGrid + " -o '" +
                                           (dir / "out").string() + "' --cache '" + (dir / "cache").string() + "'",
                                       dir, noSharedPrefix(dir));
  EXPECT_EQ(r.code, 2) << "stdout:\n" << r.out << "\nstderr:\n" << r.err;
  EXPECT_NE(r.err.find("bunny.obj"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "out" / "results.json"));
  fs::remove_all(dir);
}

}  // namespace sweep_runs_anywhere_test
