// The program's own surface, through the real binary: --version, unknown subcommands, the one
// error-line form, `shadowlab methods` (from the parser's table), -q/-v on the long commands, and a
// job whose images do not fit the device refused before any work (plain message, exit 2) or an
// allocation the device refuses (plain message, exit 3).
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/method.h"
#include "support/cli.h"

namespace app_cli_test {

namespace fs = std::filesystem;
using namespace shadowlab;
using shadowlab::testing::CliRun;
using shadowlab::testing::freshTempDir;
using shadowlab::testing::runShadowlab;

namespace {

const std::string kSmall = " --set scene:/camera/width=48 --set scene:/camera/height=32";

std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) out.push_back(line);
  return out;
}

bool deviceAvailable(const fs::path& dir) {
  static const int code = runShadowlab("raster grazing" + kSmall + " -o '" + (dir / "probe").string() + "'", dir).code;
  return code == 0;
}

}  // namespace

TEST(AppCli, VersionFlagsAndSubcommandAgree) {
  const fs::path dir = freshTempDir("app_cli_version");
  const CliRun longFlag = runShadowlab("--version", dir);
  const CliRun shortFlag = runShadowlab("-V", dir);
  const CliRun sub = runShadowlab("version", dir);
  EXPECT_EQ(longFlag.code, 0) << longFlag.err;
  EXPECT_EQ(shortFlag.code, 0) << shortFlag.err;
  EXPECT_EQ(sub.code, 0) << sub.err;
  EXPECT_EQ(longFlag.out.rfind("shadowlab 0.1.0", 0), 0u) << longFlag.out;
  EXPECT_EQ(longFlag.out, shortFlag.out);
  EXPECT_EQ(longFlag.out, sub.out);
  fs::remove_all(dir);
}

TEST(AppCli, UnknownOrMissingSubcommandNamesTheChoices) {
  const fs::path dir = freshTempDir("app_cli_unknown");
  const CliRun r = runShadowlab("frobnicate --spp 3", dir);
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(r.err.rfind("shadowlab: error: unknown subcommand \"frobnicate\"; expected one of classes, compare, ", 0),
            0u)
      << r.err;
  for (const char* name : {"methods", "raster", "run", "stability", "sweep", "tune", "version"})
    EXPECT_NE(r.err.find(name), std::string::npos) << name << " missing from: " << r.err;
  EXPECT_EQ(r.err.find("A subcommand is required"), std::string::npos) << r.err;
  const CliRun none = runShadowlab("", dir);
  EXPECT_EQ(none.code, 2);
  EXPECT_EQ(none.err.rfind("shadowlab: error: no subcommand given; expected one of classes, ", 0), 0u) << none.err;
  fs::remove_all(dir);
}

// One form for every error line: "shadowlab <subcommand>: error: ..." or "<file or option>: <place>:
// error: ..."; stability's option errors read like every other command's.
TEST(AppCli, ErrorLinesHaveOneForm) {
  const fs::path dir = freshTempDir("app_cli_errors");
  const std::string out = " -o '" + (dir / "out").string() + "'";
  struct Case {
    std::string args, prefix;
  } cases[] = {
      {"raster", "shadowlab raster: error: "},                 // CLI11's own (a missing argument)
      {"run grazing --nope" + out, "shadowlab run: error: "},  // an unknown option
      {"stability long_view --path dolly --frames 1" + out, "--frames: error: got 1; expected 2..1024"},
      {"run grazing --spp 0" + out, "--spp: error: got 0"},
      {"run grazing --set map.size=8" + out, "--set map.size=8: map.size: error: got \"8\""},
      {"reference grazing --spp 0" + out, "--spp: error: got 0"},
  };
  for (const Case& c : cases) {
    const CliRun r = runShadowlab(c.args, dir);
    EXPECT_EQ(r.code, 2) << c.args << "\n" << r.err;
    EXPECT_EQ(r.err.rfind(c.prefix, 0), 0u) << c.args << "\n" << r.err;
    EXPECT_EQ(r.err.find("shadowlab stability: --"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir / "out")) << c.args;
  }
  fs::remove_all(dir);
}

// `shadowlab methods --json` is the parser's table: every key the parser accepts, nothing else;
// the defaults are Method{}'s (a method file made of them loads as the default method); the
// ranges are what the parser enforces (each integer range's ends accepted, one past refused).
TEST(AppCli, MethodsListsTheParsersKeysDefaultsAndRanges) {
  const fs::path dir = freshTempDir("app_cli_methods");
  const CliRun r = runShadowlab("methods --json", dir);
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json doc = nlohmann::json::parse(r.out);
  EXPECT_EQ(doc["schema"], "shadowlab.methods/1");
  std::set<std::string> listed;
  nlohmann::json file = nlohmann::json::object();
  for (const auto& row : doc["keys"]) {
    const std::string key = row["key"];
    EXPECT_TRUE(listed.insert(key).second) << key << " listed twice";
    EXPECT_FALSE(row["help"].get<std::string>().empty()) << key;
    EXPECT_FALSE(row["range"].get<std::string>().empty()) << key;
    if (!row["default"].is_null()) file[key] = row["default"];  // null: unset by default (technique)
    // The listed type is the default's.
    const std::string type = row["type"];
    if (type == "integer") {
      EXPECT_TRUE(row["default"].is_number_integer()) << key;
    } else if (type == "number") {
      EXPECT_TRUE(row["default"].is_number()) << key;
    } else if (type == "boolean") {
      EXPECT_TRUE(row["default"].is_boolean()) << key;
    }
    if (type == "choice") {
      EXPECT_EQ(row["range"].get<std::string>().rfind("one of ", 0), 0u) << key;
      EXPECT_NE(row["range"].get<std::string>().find(row["default"].get<std::string>()), std::string::npos) << key;
    }
    // An integer range "an integer LO..HI": both ends parse, one past either end does not.
    long long lo = 0, hi = 0;
    if (std::sscanf(row["range"].get<std::string>().c_str(), "an integer %lld..%lld", &lo, &hi) == 2) {
      for (long long v : {lo, hi}) {
        Method m;
        if (key == "filter.size" && v % 2 == 0) continue;
        EXPECT_NO_THROW(applyMethodSetting(m, key, std::to_string(v), "--set")) << key << "=" << v;
      }
      for (long long v : {lo - 1, hi + 1}) {
        Method m;
        EXPECT_THROW(applyMethodSetting(m, key, std::to_string(v), "--set"), InputError) << key << "=" << v;
      }
    }
  }
  std::set<std::string> accepted(methodKeys().begin(), methodKeys().end());
  accepted.insert("name");
  EXPECT_EQ(listed, accepted);
  // Every listed key is one the parser takes, with its listed default.
  const fs::path methodFile = dir / "defaults.json";
  std::ofstream(methodFile) << file.dump(2);
  const Method loaded = loadMethodFile(methodFile.string());
  EXPECT_EQ(methodToJson(loaded), methodToJson(Method{}));
  // The text listing names every key too, with its default.
  const CliRun text = runShadowlab("methods", dir);
  ASSERT_EQ(text.code, 0) << text.err;
  for (const std::string& key : accepted) EXPECT_NE(text.out.find(key + " "), std::string::npos) << key;
  EXPECT_NE(text.out.find("map.size"), std::string::npos);
  EXPECT_NE(text.out.find("integer, default 2048:"), std::string::npos) << text.out;
  EXPECT_NE(text.out.find("bias.compare"), std::string::npos);
  EXPECT_NE(text.out.find("number, default 0.0005:"), std::string::npos) << text.out;
  fs::remove_all(dir);
}

// -q: errors only (a successful run prints nothing, a failing one its error line); -v: the memory
// estimate and the device's images, which a plain run of this size does not print.
TEST(AppCli, QuietAndVerboseOnTheLongCommands) {
  const fs::path dir = freshTempDir("app_cli_verbosity");
  if (!deviceAvailable(dir)) GTEST_SKIP() << "no Vulkan device: test NOT run";
  const std::string cache = " --cache '" + (dir / "cache").string() + "'";
  const CliRun plain = runShadowlab("run grazing" + kSmall + cache + " -o '" + (dir / "plain").string() + "'", dir);
  ASSERT_EQ(plain.code, 0) << plain.err;
  EXPECT_FALSE(plain.out.empty());
  EXPECT_EQ(plain.err.find("device images"), std::string::npos) << plain.err;
  const CliRun quiet = runShadowlab("run grazing -q" + kSmall + cache + " -o '" + (dir / "quiet").string() + "'", dir);
  EXPECT_EQ(quiet.code, 0) << quiet.err;
  EXPECT_EQ(quiet.out, "");
  EXPECT_EQ(quiet.err, "");
  EXPECT_TRUE(fs::exists(dir / "quiet" / "metrics.json"));
  const CliRun quietFail = runShadowlab("run grazing --quiet --spp 0 -o '" + (dir / "fail").string() + "'", dir);
  EXPECT_EQ(quietFail.code, 2);
  EXPECT_EQ(quietFail.err, "--spp: error: got 0; expected an integer 1..1024 (reference samples per pixel)\n");
  const CliRun verbose =
      runShadowlab("run grazing -v" + kSmall + cache + " -o '" + (dir / "verbose").string() + "'", dir);
  EXPECT_EQ(verbose.code, 0) << verbose.err;
  EXPECT_NE(verbose.err.find("run: about "), std::string::npos) << verbose.err;
  EXPECT_NE(verbose.err.find("run: device images "), std::string::npos) << verbose.err;
  EXPECT_NE(verbose.err.find("shadow map depth 2048^2 x 1 layer x "), std::string::npos) << verbose.err;
  const CliRun both = runShadowlab("run grazing -q -v -o '" + (dir / "both").string() + "'", dir);
  EXPECT_EQ(both.code, 2) << both.err;
  EXPECT_EQ(both.err.rfind("shadowlab run: error: ", 0), 0u) << both.err;
  for (const char* command : {"run", "stability", "sweep", "tune"}) {
    const CliRun help = runShadowlab(std::string(command) + " --help", dir);
    EXPECT_NE(help.out.find("-q,--quiet"), std::string::npos) << command;
    EXPECT_NE(help.out.find("-v,--verbose"), std::string::npos) << command;
  }
  fs::remove_all(dir);
}

// The tracker's case: 3 cascades of 16384^2 passed the memory estimate and then died with a raw
// VK_ERROR_OUT_OF_DEVICE_MEMORY and a source path. Now refused before any work, exit 2, naming the
// image; --max-memory 1000 keeps the RAM estimate out of the way on any machine.
TEST(AppCli, ImagesAboveTheDeviceLimitAreRefusedBeforeWork) {
  const fs::path dir = freshTempDir("app_cli_device_memory");
  if (!deviceAvailable(dir)) GTEST_SKIP() << "no Vulkan device: test NOT run";
  for (const char* command : {"raster", "run", "stability"}) {
    SCOPED_TRACE(command);
    const fs::path out = dir / (std::string("out_") + command);
    const std::string name = command;
    const std::string extra = (name == "stability" ? " --path dolly --frames 2" : "") +
                              (name == "raster" ? "" : " --cache '" + (dir / "cache").string() + "'");
    const CliRun r = runShadowlab(std::string(command) +
                                      " long_view --set fit=cascades --set cascades.count=3 --set map.size=16384"
                                      " --max-memory 1000" +
                                      extra + " -o '" + out.string() + "'",
                                  dir);
    EXPECT_EQ(r.code, 2) << r.err;
    // The last line (a job this large prints its RAM estimate first).
    const std::vector<std::string> errLines = lines(r.err);
    ASSERT_FALSE(errLines.empty());
    EXPECT_EQ(errLines.back().rfind("method: map.size: error: shadow map depth 16384^2 x 3 layers x 4 B = 3.00 GiB is "
                                    "above the largest allocation device llvmpipe",
                                    0),
              0u)
        << r.err;
    EXPECT_NE(r.err.find("(maxMemoryAllocationSize); expected a map.size of at most 13376 at 3 layers"),
              std::string::npos)
        << r.err;
    EXPECT_EQ(r.err.find(".cpp"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out)) << "a refused job wrote its folder";
  }
  size_t cached = 0;
  if (fs::exists(dir / "cache"))
    for (const auto& entry : fs::recursive_directory_iterator(dir / "cache")) cached += entry.is_regular_file();
  EXPECT_EQ(cached, 0u) << "a refused job traced a reference";
  fs::remove_all(dir);
}

// An allocation the device refuses (simulated: SHADOWLAB_VK_FAIL=call=VK_ERROR_OUT_OF_DEVICE_MEMORY)
// is a plain line naming what was allocated, its size, the result and the call: exit 3, no source
// path, no output.
TEST(AppCli, AllocationFailureIsAPlainMessage) {
  const fs::path dir = freshTempDir("app_cli_alloc_failure");
  if (!deviceAvailable(dir)) GTEST_SKIP() << "no Vulkan device: test NOT run";
  for (const char* call : {"vkBindImageMemory", "vkAllocateMemory"}) {
    SCOPED_TRACE(call);
    const fs::path out = dir / (std::string("out_") + call);
    const CliRun r =
        runShadowlab("raster grazing" + kSmall + " -o '" + out.string() + "'", dir,
                     std::string("SHADOWLAB_VK_FAIL=") + call + "=VK_ERROR_OUT_OF_DEVICE_MEMORY timeout 120 ");
    EXPECT_EQ(r.code, 3) << r.err;
    const std::vector<std::string> errLines = lines(r.err);
    ASSERT_EQ(errLines.size(), 1u) << r.err;
    EXPECT_EQ(errLines[0].rfind("shadowlab raster: error: device llvmpipe", 0), 0u) << r.err;
    EXPECT_NE(r.err.find(" could not allocate "), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(std::string("(VK_ERROR_OUT_OF_DEVICE_MEMORY at ") + call + ")"), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find(".cpp"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out));
  }
  fs::remove_all(dir);
}

// A count that is no integer names the range, as an integer out of it does ("Could not convert"
// said neither), on every command that takes it.
TEST(AppCli, SampleCountsThatAreNoIntegerNameTheRange) {
  const fs::path dir = freshTempDir("app_cli_counts");
  for (const std::string& command : {std::string("reference grazing"), std::string("run grazing"),
                                     std::string("sweep grazing"), std::string("tune grazing --max-error 0.1")}) {
    for (const char* value : {"1e9", "abc", "99999999999"}) {
      const CliRun r =
          runShadowlab(command + " --light-samples " + value + " -o out", dir, "cd '" + dir.string() + "' && ");
      EXPECT_EQ(r.code, 2) << command << " " << value << "\n" << r.err;
      EXPECT_NE(r.err.find(std::string("--light-samples: got ") + value + "; expected an integer 1..4096"),
                std::string::npos)
          << command << "\n"
          << r.err;
      EXPECT_EQ(r.err.find("Could not convert"), std::string::npos) << r.err;
    }
    const CliRun spp = runShadowlab(command + " --spp 2.5 -o out", dir, "cd '" + dir.string() + "' && ");
    EXPECT_EQ(spp.code, 2) << spp.err;
    EXPECT_NE(spp.err.find("--spp: got 2.5; expected an integer 1..1024"), std::string::npos) << spp.err;
    EXPECT_FALSE(fs::exists(dir / "out"));
  }
  fs::remove_all(dir);
}

// A sweep file that names a scene that does not exist: the message names the sweep file and the
// JSON pointer of the name, where it named only the resolved path.
TEST(AppCli, SweepFileNamingAMissingSceneNamesFileAndPointer) {
  const fs::path dir = freshTempDir("app_cli_sweep_scene");
  std::ofstream(dir / "s.sweep.json") << R"({"scenes": ["grazing", "nope"], "grid": {"map.size": [256]}})";
  const CliRun r = runShadowlab("sweep --sweep s.sweep.json -o out", dir, "cd '" + dir.string() + "' && ");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_EQ(r.err.rfind("s.sweep.json: /scenes/1: error: scene \"nope\" not found (", 0), 0u) << r.err;
  EXPECT_NE(r.err.find("expected a scene file or a bundled scene name: sphere_on_plane, grazing"), std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(dir / "out"));
  fs::remove_all(dir);
}

}  // namespace app_cli_test
