// `shadowlab reference` through the real binary: bad arguments and missing scenes exit 2 with a
// message naming the culprit and write nothing; a good run writes reference.exr/.png/.json
// whose contents agree with each other and with the library.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "shadowlab/reference/reference.h"
#include "shadowlab/scenes/frame.h"
#include "shadowlab/scenes/loader.h"

namespace reference_cli_test {

namespace {

namespace fs = std::filesystem;

struct RunResult {
  int exitCode = -1;
  std::string output;  // stdout and stderr
};

RunResult runShadowlab(const std::string& args) {
  const fs::path log = fs::temp_directory_path() / ("shadowlab_reference_cli_" + std::to_string(getpid()) + ".log");
  const std::string command = std::string("'") + SHADOWLAB_BINARY + "' " + args + " > '" + log.string() + "' 2>&1";
  const int status = std::system(command.c_str());
  RunResult result;
  result.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream in(log);
  std::stringstream text;
  text << in.rdbuf();
  result.output = text.str();
  fs::remove(log);
  return result;
}

class ReferenceCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("shadowlab_reference_cli_" + std::to_string(getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // A small scene file (procedural geometry only) so the good run takes well under a second.
  std::string writeSmallScene() {
    const fs::path path = dir_ / "small.json";
    std::ofstream(path) << R"({
      // sphere_on_plane, 160 x 90
      "camera": {"position": [0, 5, 9], "look_at": [0, 0.5, -1], "vfov_deg": 45, "width": 160, "height": 90},
      "objects": [
        {"type": "plane", "name": "ground", "size": [40, 40]},
        {"type": "sphere", "name": "ball", "radius": 1, "transform": {"translate": [0, 1, 0]}}
      ],
      "lights": [{"type": "directional", "name": "sun", "elevation_deg": 50, "azimuth_deg": 30}]
    })";
    return path.string();
  }

  fs::path dir_;
};

TEST_F(ReferenceCli, BadSppExitsTwoAndWritesNothing) {
  const std::string scene = writeSmallScene();
  for (const char* spp : {"0", "1025", "-3", "abc"}) {
    SCOPED_TRACE(spp);
    const fs::path out = dir_ / "out";
    const RunResult result = runShadowlab("reference '" + scene + "' -o '" + out.string() + "' --spp " + spp);
    EXPECT_EQ(result.exitCode, 2) << result.output;
    EXPECT_NE(result.output.find("spp"), std::string::npos) << result.output;
    EXPECT_FALSE(fs::exists(out)) << "a rejected run created " << out;
  }
}

TEST_F(ReferenceCli, BadThreadsExitsTwoAndWritesNothing) {
  const std::string scene = writeSmallScene();
  const fs::path out = dir_ / "out";
  const RunResult result = runShadowlab("reference '" + scene + "' -o '" + out.string() + "' --threads -1");
  EXPECT_EQ(result.exitCode, 2) << result.output;
  EXPECT_NE(result.output.find("--threads"), std::string::npos) << result.output;
  EXPECT_FALSE(fs::exists(out));
}

TEST_F(ReferenceCli, OutputThatIsAFileExitsTwoBeforeTracing) {
  const std::string scene = writeSmallScene();
  const fs::path out = dir_ / "taken";
  std::ofstream(out) << "a file";
  const RunResult result = runShadowlab("reference '" + scene + "' -o '" + out.string() + "'");
  EXPECT_EQ(result.exitCode, 2) << result.output;
  EXPECT_NE(result.output.find("taken"), std::string::npos) << result.output;
  EXPECT_TRUE(fs::is_regular_file(out));
}

TEST_F(ReferenceCli, MissingSceneExitsTwoNamingItAndWritesNothing) {
  for (const std::string& scene : {std::string("no_such_scene"), (dir_ / "missing.json").string()}) {
    SCOPED_TRACE(scene);
    const fs::path out = dir_ / "out";
    const RunResult result = runShadowlab("reference '" + scene + "' -o '" + out.string() + "'");
    EXPECT_EQ(result.exitCode, 2) << result.output;
    EXPECT_NE(result.output.find(fs::path(scene).stem().string()), std::string::npos) << result.output;
    EXPECT_NE(result.output.find("error"), std::string::npos) << result.output;
    EXPECT_FALSE(fs::exists(out));
  }
}

TEST_F(ReferenceCli, MalformedSceneExitsTwoAndLeavesExistingOutputsAlone) {
  const fs::path scene = dir_ / "broken.json";
  std::ofstream(scene) << "{ \"camera\": { \"width\": 16, }\n";
  const fs::path out = dir_ / "out";
  fs::create_directories(out);
  std::ofstream(out / "reference.json") << "old";
  const RunResult result = runShadowlab("reference '" + scene.string() + "' -o '" + out.string() + "'");
  EXPECT_EQ(result.exitCode, 2) << result.output;
  EXPECT_NE(result.output.find("broken.json"), std::string::npos) << result.output;
  std::ifstream in(out / "reference.json");
  std::string content((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(content, "old");
  EXPECT_FALSE(fs::exists(out / "reference.exr"));
  EXPECT_FALSE(fs::exists(out / "reference.png"));
}

// A sphere light whose sphere cuts or encloses geometry has no truth to give (soft_post at radius
// 5: a bright disc on the ground, the post's shadow gone; at 1e9 every pixel lit): refused at load,
// naming the light's radius and the first object the growing sphere reaches, and nothing written.
TEST_F(ReferenceCli, SphereLightThatReachesGeometryExitsTwoNamingTheObject) {
  const fs::path out = dir_ / "out";
  for (const char* radius : {"5", "1e9"}) {
    SCOPED_TRACE(radius);
    const RunResult r = runShadowlab("reference soft_post --set scene:/lights/0/radius=" + std::string(radius) +
                                     " -o '" + out.string() + "'");
    EXPECT_EQ(r.exitCode, 2) << r.output;
    // The post's top corner (0.075, 2.5, 0.075) is 2.6098 from the light's centre (2, 4, 1).
    EXPECT_NE(r.output.find("/lights/0/radius"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("; expected a radius below 2.6098"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("its sphere reaches object \"post\" at distance 2.6098"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(out));
  }
  // A light 3 above a ground plane: the ground at exactly 3; 2.99 passes.
  const fs::path scene = dir_ / "bulb.json";
  std::ofstream(scene) << R"({
    "camera": {"position": [0, 5, 9], "look_at": [0, 0, 0], "vfov_deg": 45, "width": 32, "height": 18},
    "objects": [{"type": "plane", "name": "ground", "size": [40, 40]}],
    "lights": [{"type": "point", "name": "bulb", "position": [0, 3, 0], "radius": 3}]
  })";
  const RunResult ground = runShadowlab("reference '" + scene.string() + "' -o '" + out.string() + "'");
  EXPECT_EQ(ground.exitCode, 2) << ground.output;
  EXPECT_NE(ground.output.find(scene.string() +
                               ": /lights/0/radius: error: got 3; expected a radius below 3: its sphere reaches "
                               "object \"ground\" at distance 3 from the centre (a sphere light must lie outside "
                               "every object; radius 0..1e30)"),
            std::string::npos)
      << ground.output;
  const RunResult clear =
      runShadowlab("reference '" + scene.string() + "' --set scene:/lights/0/radius=2.99 -o '" + out.string() + "'");
  EXPECT_EQ(clear.exitCode, 0) << clear.output;
  // Beyond the float range the message states the upper limit.
  const RunResult huge = runShadowlab("reference '" + scene.string() + "' --set scene:/lights/0/radius=1e37 -o '" +
                                      (dir_ / "o2").string() + "'");
  EXPECT_EQ(huge.exitCode, 2) << huge.output;
  EXPECT_NE(huge.output.find("expected a radius 0..1e30"), std::string::npos) << huge.output;
}

TEST_F(ReferenceCli, GoodRunWritesConsistentOutputs) {
  const std::string scenePath = writeSmallScene();
  const fs::path out = dir_ / "nested" / "out";
  const RunResult result = runShadowlab("reference '" + scenePath + "' -o '" + out.string() + "' --spp 4 --threads 2");
  ASSERT_EQ(result.exitCode, 0) << result.output;
  ASSERT_TRUE(fs::exists(out / "reference.exr"));
  ASSERT_TRUE(fs::exists(out / "reference.png"));
  ASSERT_TRUE(fs::exists(out / "reference.json"));
  // No temporary files left behind by the atomic writers.
  size_t entries = 0;
  for (const auto& entry : fs::directory_iterator(out)) {
    (void)entry;
    ++entries;
  }
  EXPECT_EQ(entries, 3u);

  std::ifstream in(out / "reference.json");
  const nlohmann::json report = nlohmann::json::parse(in);
  const shadowlab::Scene scene = shadowlab::loadScene(scenePath);
  EXPECT_EQ(report.at("width"), 160);
  EXPECT_EQ(report.at("height"), 90);
  EXPECT_EQ(report.at("spp"), 4);
  EXPECT_EQ(report.at("scene_hash"), scene.hash);
  shadowlab::ReferenceOptions options;
  options.spp = 4;
  EXPECT_EQ(report.at("reference_hash"), shadowlab::referenceHash(scene, options));
  EXPECT_EQ(report.at("rays").get<uint64_t>(),
            report.at("primary_rays").get<uint64_t>() + report.at("shadow_rays").get<uint64_t>());
  EXPECT_GT(report.at("shadow_rays").get<uint64_t>(), 0u);
  EXPECT_GT(report.at("trace_seconds").get<double>(), 0.0);
  EXPECT_NEAR(report.at("mrays_per_s").get<double>(),
              report.at("rays").get<double>() / report.at("trace_seconds").get<double>() * 1e-6, 1e-6);

  // The EXR holds exactly what the library renders (any thread count gives the same bits): by
  // default the Compare channel set, the one the reference cache holds.
  EXPECT_EQ(report.at("channels"), "compare");
  const shadowlab::Frame written = shadowlab::readFrameExr((out / "reference.exr").string());
  options.channels = shadowlab::ReferenceChannels::Compare;
  const shadowlab::Frame expected = shadowlab::renderReference(scene, options);
  EXPECT_EQ(written.names, (std::vector<std::string>{"hit", "object_id", "light.sun.vis", "light.sun.occluder_dist"}));
  EXPECT_EQ(written.meta.at("channels"), "compare");
  // spp 4: a center ray per pixel, plus 4 samples where the center hit something (a pixel whose
  // center sees the sky reports no hit, whatever its samples would see).
  size_t hits = 0;
  for (float h : written.get("hit")) hits += h == 1.0f;
  EXPECT_GT(hits, 1000u);
  EXPECT_LT(hits, 160u * 90u);
  EXPECT_EQ(report.at("primary_rays").get<uint64_t>(), 160u * 90u + 4u * hits);
  EXPECT_EQ(written.meta.at("kind"), "reference");
  EXPECT_EQ(written.meta.at("scene_hash"), scene.hash);
  ASSERT_EQ(written.names, expected.names);
  for (size_t c = 0; c < expected.names.size(); ++c)
    EXPECT_EQ(written.data[c], expected.data[c]) << "channel " << expected.names[c];
}

// --all-channels adds prim_id, P, N (and a projector's u, v) to the same values; the picture, drawn
// from every channel in both cases, is the same file.
TEST_F(ReferenceCli, AllChannelsAddsTheChannelsForPeople) {
  const std::string scenePath = writeSmallScene();
  const fs::path compareOut = dir_ / "compare", allOut = dir_ / "all";
  const RunResult plain = runShadowlab("reference '" + scenePath + "' -o '" + compareOut.string() + "'");
  ASSERT_EQ(plain.exitCode, 0) << plain.output;
  const RunResult all =
      runShadowlab("reference '" + scenePath + "' -o '" + allOut.string() + "' --all-channels --threads 1");
  ASSERT_EQ(all.exitCode, 0) << all.output;

  const shadowlab::Scene scene = shadowlab::loadScene(scenePath);
  shadowlab::ReferenceOptions options;
  options.channels = shadowlab::ReferenceChannels::All;
  const shadowlab::Frame expected = shadowlab::renderReference(scene, options);
  const shadowlab::Frame written = shadowlab::readFrameExr((allOut / "reference.exr").string());
  EXPECT_EQ(written.names, (std::vector<std::string>{"hit", "object_id", "prim_id", "P.x", "P.y", "P.z", "N.x", "N.y",
                                                     "N.z", "light.sun.vis", "light.sun.occluder_dist"}));
  EXPECT_EQ(written.meta.at("channels"), "all");
  ASSERT_EQ(written.names, expected.names);
  for (size_t c = 0; c < expected.names.size(); ++c)
    EXPECT_EQ(written.data[c], expected.data[c]) << "channel " << expected.names[c];
  std::ifstream in(allOut / "reference.json");
  EXPECT_EQ(nlohmann::json::parse(in).at("channels"), "all");

  // The default run's channels are the same planes, bit for bit.
  const shadowlab::Frame compareSet = shadowlab::readFrameExr((compareOut / "reference.exr").string());
  ASSERT_EQ(compareSet.names.size(), 4u);
  for (size_t c = 0; c < compareSet.names.size(); ++c)
    EXPECT_EQ(compareSet.data[c], written.get(compareSet.names[c])) << "channel " << compareSet.names[c];
  auto bytes = [](const fs::path& path) {
    std::ifstream file(path, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  };
  EXPECT_EQ(bytes(compareOut / "reference.png"), bytes(allOut / "reference.png"));
}

}  // namespace

}  // namespace reference_cli_test
