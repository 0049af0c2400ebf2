// Output locations are checked before any work, by every subcommand that writes a folder, and a
// command that fails after claiming its folder leaves nothing behind. One --set syntax (method keys
// and scene:/pointer values) for every subcommand that takes a scene.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "support/cli.h"

namespace robustness_outputs_test {

namespace fs = std::filesystem;
using shadowlab::testing::CliRun;
using shadowlab::testing::runShadowlab;
using shadowlab::testing::slurp;

namespace {

fs::path tempDir(const std::string& name) {
  fs::path dir = fs::temp_directory_path() / ("shadowlab_outputs_test_" + std::to_string(::getpid())) / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

// A small image keeps every trace and render in this file well under a second.
const std::string kSmall = " --set scene:/camera/width=48 --set scene:/camera/height=32";

}  // namespace

// /proc refuses new folders even to root (access() would say yes): each command must find out
// before it traces or renders, and must not leave a reference cache in the working folder.
TEST(OutputFolders, UnusableOutputFolderExitsTwoBeforeAnyWork) {
  const fs::path dir = tempDir("proc");
  const std::string bad = "/proc/shadowlab_no_such_folder/out";
  const std::string cd = "cd '" + dir.string() + "' && ";
  for (const std::string& command : {"reference grazing" + kSmall, "raster grazing" + kSmall, "run grazing" + kSmall,
                                     "stability grazing --path dolly --frames 2 --distance 0.1" + kSmall,
                                     "sweep grazing --grid map.size=64" + kSmall}) {
    SCOPED_TRACE(command);
    CliRun r = runShadowlab(command + " -o " + bad, dir, cd);
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_NE(r.err.find(bad), std::string::npos) << "names the folder: " << r.err;
    EXPECT_NE(r.err.find("output folder"), std::string::npos) << r.err;
    EXPECT_EQ(r.out, "") << "nothing ran: " << r.out;
    EXPECT_FALSE(fs::exists(dir / ".shadowlab-cache")) << "a reference was traced and cached first";
  }
}

TEST(OutputFolders, FolderUnderAFileExitsTwo) {
  const fs::path dir = tempDir("under_file");
  std::ofstream(dir / "file.txt") << "x";
  CliRun r = runShadowlab("reference grazing" + kSmall + " -o '" + (dir / "file.txt" / "out").string() + "'", dir);
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("file.txt/out"), std::string::npos) << r.err;
  EXPECT_EQ(r.out, "");
}

// The folder is created early to prove it can be written; a failure after that removes it again.
TEST(OutputFolders, CommandFailingAfterTheCheckLeavesNoFolder) {
  const fs::path dir = tempDir("cleanup");
  const fs::path out = dir / "new" / "deeper";
  CliRun r = runShadowlab("raster grazing" + kSmall + " --device no_such_vulkan_device -o '" + out.string() + "'", dir);
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("no_such_vulkan_device"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "new")) << "the folders the command created were left behind";
}

TEST(OutputFolders, CompareChecksItsOutputBeforeReadingFrames) {
  const fs::path dir = tempDir("compare");
  CliRun ref = runShadowlab("reference grazing" + kSmall + " -o '" + (dir / "ref").string() + "'", dir);
  ASSERT_EQ(ref.code, 0) << ref.err;
  CliRun ras = runShadowlab("raster grazing" + kSmall + " -o '" + (dir / "ras").string() + "'", dir);
  if (ras.code == 3) GTEST_SKIP() << "no Vulkan device (shadowlab exit 3): " << ras.err;
  ASSERT_EQ(ras.code, 0) << ras.err;
  CliRun bad = runShadowlab(
      "compare '" + (dir / "ref").string() + "' '" + (dir / "ras").string() + "' -o /proc/shadowlab_no_such_folder/cmp",
      dir);
  EXPECT_EQ(bad.code, 2) << bad.err;
  EXPECT_NE(bad.err.find("/proc/shadowlab_no_such_folder/cmp"), std::string::npos) << bad.err;
  CliRun good = runShadowlab(
      "compare '" + (dir / "ref").string() + "' '" + (dir / "ras").string() + "' -o '" + (dir / "cmp").string() + "'",
      dir);
  EXPECT_EQ(good.code, 0) << good.err;
  EXPECT_TRUE(fs::is_regular_file(dir / "cmp" / "metrics.json"));
}

// raster takes the scene: overrides that run and sweep take (not refused), and the
// reference takes the scene: ones while refusing method keys, which do not change the truth.
TEST(SetSyntax, RasterAndReferenceTakeSceneOverrides) {
  const fs::path dir = tempDir("set");
  CliRun ras = runShadowlab(
      "raster grazing --set scene:/camera/width=40 --set scene:/camera/height=30 "
      "--set filter=pcf -o '" +
          (dir / "ras").string() + "'",
      dir);
  if (ras.code == 3) GTEST_SKIP() << "no Vulkan device (shadowlab exit 3): " << ras.err;
  ASSERT_EQ(ras.code, 0) << ras.err;
  const std::string rasterJson = slurp(dir / "ras" / "raster.json");
  EXPECT_NE(rasterJson.find("\"width\": 40"), std::string::npos) << rasterJson;
  EXPECT_NE(rasterJson.find("\"height\": 30"), std::string::npos) << rasterJson;
  EXPECT_NE(rasterJson.find("\"filter\": \"pcf\""), std::string::npos) << rasterJson;

  CliRun ref = runShadowlab("reference grazing --set scene:/camera/width=40 --set scene:/camera/height=30 -o '" +
                                (dir / "ref").string() + "'",
                            dir);
  ASSERT_EQ(ref.code, 0) << ref.err;
  const std::string referenceJson = slurp(dir / "ref" / "reference.json");
  EXPECT_NE(referenceJson.find("\"width\": 40"), std::string::npos) << referenceJson;

  CliRun method = runShadowlab("reference grazing --set filter=pcf -o '" + (dir / "ref2").string() + "'", dir);
  EXPECT_EQ(method.code, 2) << method.err;
  EXPECT_NE(method.err.find("filter=pcf"), std::string::npos) << method.err;
  EXPECT_FALSE(fs::exists(dir / "ref2"));

  CliRun badKey =
      runShadowlab("raster grazing --set scene:/camera/no_such_key=3 -o '" + (dir / "ras2").string() + "'", dir);
  EXPECT_EQ(badKey.code, 2) << badKey.err;
  EXPECT_FALSE(fs::exists(dir / "ras2"));
}

// A job whose estimated memory exceeds --max-memory is refused before it starts, naming the
// estimate and the limit; one under it runs.
TEST(JobLimits, MaxMemoryRefusesJobsThatCannotFitBeforeAnyWork) {
  const fs::path dir = tempDir("memory");
  const std::string big = " --set scene:/camera/width=8000 --set scene:/camera/height=8000 --max-memory 1";
  for (const char* command : {"reference grazing", "raster grazing", "run grazing"}) {
    SCOPED_TRACE(command);
    CliRun r = runShadowlab(std::string(command) + big + " -o '" + (dir / "out").string() + "'", dir);
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_NE(r.err.find("this job needs about"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("expected at most 1.00 GiB (--max-memory)"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir / "out")) << "the refused job wrote its folder";
  }
  // the map alone: 16384^2 texels x 8 bytes = 2 GiB
  CliRun map = runShadowlab(
      "raster grazing" + kSmall + " --set map.size=16384 --max-memory 1 -o '" + (dir / "out").string() + "'", dir);
  EXPECT_EQ(map.code, 2) << map.err;
  EXPECT_NE(map.err.find("map 16384^2 x 1 layer(s) 2.00 GiB"), std::string::npos) << map.err;
  // a filterable map's moments: two RGBA32F images for msm, 8192^2 x 16 bytes x 2 = 2 GiB
  CliRun moments =
      runShadowlab("raster grazing" + kSmall + " --set map.size=8192 --set filter=msm --max-memory 1 -o '" +
                       (dir / "out").string() + "'",
                   dir);
  EXPECT_EQ(moments.code, 2) << moments.err;
  EXPECT_NE(moments.err.find("moments 8192^2 x 1 layer(s) x 2 2.00 GiB"), std::string::npos) << moments.err;

  CliRun small = runShadowlab("reference grazing" + kSmall + " --max-memory 1 -o '" + (dir / "ok").string() + "'", dir);
  EXPECT_EQ(small.code, 0) << small.err;
}

// The trace's progress line shows on a terminal only: `script` gives the command a pseudo-terminal.
TEST(JobLimits, ProgressOnATerminalOnly) {
  const fs::path dir = tempDir("progress");
  if (std::system("command -v script >/dev/null 2>&1") != 0)
    GTEST_SKIP() << "no `script` (util-linux) to make a terminal";
  const std::string args = "reference grazing" + kSmall + " -o '" + (dir / "ref").string() + "'";
  const fs::path log = dir / "tty.txt";
  const std::string cmd =
      "script -qec \"" + std::string(SHADOWLAB_BINARY) + " " + args + "\" /dev/null >'" + log.string() + "' 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << slurp(log);
  EXPECT_NE(slurp(log).find("reference: tracing 100%"), std::string::npos) << slurp(log);
  CliRun piped = runShadowlab(args, dir);
  EXPECT_EQ(piped.code, 0) << piped.err;
  EXPECT_EQ(piped.err.find('%'), std::string::npos) << "no progress line into a pipe: " << piped.err;
}

// A scene with projectors and no light is valid (scenes/FORMAT.md) and `reference` traces it; `run`
// and `compare` compare what it has: the projector's metrics, no light ("light_compared": false).
TEST(ProjectorOnly, RunAndCompareCompareTheProjector) {
  const fs::path dir = tempDir("projector_only");
  const std::string image = std::string(SHADOWLAB_SOURCE_DIR) + "/scenes/data/projector_image.png";
  std::ofstream(dir / "slide.json") << R"({
  "camera": {"position": [6, 4, 6], "look_at": [0, 1, -2], "vfov_deg": 50, "width": 96, "height": 64},
  "objects": [{"type": "plane", "size": [20, 20]},
              {"type": "quad", "size": [8, 5], "transform": {"translate": [0, 2.5, -4]}}],
  "projectors": [{"name": "slide", "position": [0, 2.5, 3], "look_at": [0, 2.5, -5], "fov_deg": 40,
                  "image": ")" + image + R"("}]
})";
  const std::string scene = "'" + (dir / "slide.json").string() + "'";
  CliRun run = runShadowlab(
      "run " + scene + " --cache '" + (dir / "cache").string() + "' -o '" + (dir / "run").string() + "'", dir);
  if (run.code == 3) GTEST_SKIP() << "no Vulkan device (shadowlab exit 3): " << run.err;
  ASSERT_EQ(run.code, 0) << run.err;
  EXPECT_NE(run.out.find("no light (projector-only scene); projector: coverage_iou"), std::string::npos) << run.out;
  const std::string metrics = slurp(dir / "run" / "metrics.json");
  EXPECT_NE(metrics.find("\"light_compared\": false"), std::string::npos) << metrics;
  EXPECT_NE(metrics.find("\"projector_coverage_iou\""), std::string::npos) << metrics;

  ASSERT_EQ(runShadowlab("reference " + scene + " -o '" + (dir / "ref").string() + "'", dir).code, 0);
  ASSERT_EQ(runShadowlab("raster " + scene + " -o '" + (dir / "ras").string() + "'", dir).code, 0);
  CliRun cmp = runShadowlab(
      "compare '" + (dir / "ref").string() + "' '" + (dir / "ras").string() + "' -o '" + (dir / "cmp").string() + "'",
      dir);
  EXPECT_EQ(cmp.code, 0) << cmp.err;
  EXPECT_NE(cmp.out.find("no light (projector-only scene)"), std::string::npos) << cmp.out;
}

// A failing or lost device call (simulated with the test-only SHADOWLAB_VK_FAIL switch, vk/check.h)
// ends as exit 3 naming the call and the result, never a hang or a crash, and leaves no output.
TEST(DeviceFailure, FailingVulkanCallExitsThreeNamingIt) {
  const fs::path dir = tempDir("device_failure");
  CliRun healthy = runShadowlab("raster grazing" + kSmall + " -o '" + (dir / "ok").string() + "'", dir);
  if (healthy.code == 3) GTEST_SKIP() << "no Vulkan device (shadowlab exit 3): " << healthy.err;
  ASSERT_EQ(healthy.code, 0) << healthy.err;
  for (const char* call : {"vkCreateDevice", "vkAllocateMemory", "vkQueueSubmit", "vkWaitForFences", "vkMapMemory"}) {
    SCOPED_TRACE(call);
    const fs::path out = dir / (std::string("out_") + call);
    CliRun r = runShadowlab("raster grazing" + kSmall + " -o '" + out.string() + "'", dir,
                            std::string("SHADOWLAB_VK_FAIL=") + call + " timeout 120 ");
    EXPECT_EQ(r.code, 3) << r.err;
    EXPECT_NE(r.err.find(call), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("VK_ERROR_DEVICE_LOST"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out)) << "a failed render left its folder";
  }
}

}  // namespace robustness_outputs_test
