// Camera paths declared in scene files ("paths", scenes/FORMAT.md) and the keyframe interpolation
// (scenes/camera_path.h): long_view's paths parse to what the file says, keyframe frames land
// exactly on their keyframes and halfway between them, and bad paths (unknown kind, frames < 2,
// NaN, degenerate keyframes) are InputErrors naming the file and the JSON pointer. The files in
// tests/bad_input/scene_path_*.json check the same through the binary.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "shadowlab/scenes/camera_path.h"
#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/loader.h"
#include "support/input_error.h"

namespace scenes_paths_test {

using namespace shadowlab;
using shadowlab::testing::inputErrorOf;
namespace fs = std::filesystem;

namespace {

Camera keyCamera(glm::vec3 position, glm::vec3 lookAt) {
  Camera c;
  c.position = position;
  c.lookAt = lookAt;
  c.width = 320;
  c.height = 180;
  return c;
}

}  // namespace

TEST(ScenePaths, LongViewDeclaresAWalkAndATurn) {
  const Scene s = loadScene(resolveScenePath("long_view"));
  ASSERT_EQ(s.paths.size(), 2u);
  const CameraPath* walk = s.findPath("walk");
  ASSERT_NE(walk, nullptr);
  EXPECT_EQ(walk->kind, CameraPathKind::Dolly);
  EXPECT_EQ(walk->frames, 32);
  EXPECT_FLOAT_EQ(walk->distanceWorld, 4.0f);
  // The walk is exactly the generated dolly of the same length (the shimmer test's path).
  const std::vector<Camera> cams = expandCameraPath(s.camera, *walk);
  const std::vector<Camera> dolly = dollyPath(s.camera, 4.0f, 32);
  ASSERT_EQ(cams.size(), 32u);
  for (size_t k = 0; k < cams.size(); ++k) EXPECT_EQ(cams[k].hash(), dolly[k].hash()) << k;
  // --frames replaces the count: the same 4 units in 3 frames.
  const std::vector<Camera> three = expandCameraPath(s.camera, *walk, 3);
  ASSERT_EQ(three.size(), 3u);
  EXPECT_NEAR(glm::length(three[2].position - s.camera.position), 4.0f, 1e-4f);

  const CameraPath* turn = s.findPath("turn");
  ASSERT_NE(turn, nullptr);
  EXPECT_EQ(turn->kind, CameraPathKind::Keyframes);
  EXPECT_EQ(turn->frames, 17);
  ASSERT_EQ(turn->keyframes.size(), 3u);
  // Other camera fields are the scene camera's.
  EXPECT_EQ(turn->keyframes[1].vfovDeg, s.camera.vfovDeg);
  EXPECT_EQ(turn->keyframes[1].width, s.camera.width);
  const std::vector<Camera> t = expandCameraPath(s.camera, *turn);
  ASSERT_EQ(t.size(), 17u);
  // 16 steps over 2 intervals: frames 0, 8 and 16 are the keyframes, exactly.
  EXPECT_EQ(t[0].position, glm::vec3(0, 1.7f, 8));
  EXPECT_EQ(t[8].position, glm::vec3(0, 1.7f, 4));
  EXPECT_EQ(t[8].lookAt, glm::vec3(-20, 1.2f, -100));
  EXPECT_EQ(t[16].position, glm::vec3(0, 1.7f, 0));
  EXPECT_EQ(s.findPath("dolly"), nullptr);
}

TEST(ScenePaths, KeyframeInterpolationIsPiecewiseLinearAtEqualSteps) {
  const std::vector<Camera> keys = {keyCamera({0, 0, 0}, {0, 0, -1}), keyCamera({4, 0, 0}, {4, 0, -1}),
                                    keyCamera({4, 8, 0}, {4, 8, -1})};
  // 2 intervals in 5 frames: t = 0, 0.5, 1, 1.5, 2 keyframe intervals.
  const std::vector<Camera> p = keyframePath(keys, 5);
  ASSERT_EQ(p.size(), 5u);
  EXPECT_EQ(p[0].position, glm::vec3(0, 0, 0));
  EXPECT_EQ(p[1].position, glm::vec3(2, 0, 0));
  EXPECT_EQ(p[2].position, glm::vec3(4, 0, 0));
  EXPECT_EQ(p[3].position, glm::vec3(4, 4, 0));
  EXPECT_EQ(p[4].position, glm::vec3(4, 8, 0));
  EXPECT_EQ(p[3].lookAt, glm::vec3(4, 4, -1));
  EXPECT_EQ(p[3].width, 320);
  // 2 keys in 4 frames: thirds.
  const std::vector<Camera> q = keyframePath({keys[0], keys[1]}, 4);
  EXPECT_NEAR(q[1].position.x, 4.0f / 3.0f, 1e-6f);
  EXPECT_NEAR(q[2].position.x, 8.0f / 3.0f, 1e-6f);
  EXPECT_EQ(q[3].position, glm::vec3(4, 0, 0));
  EXPECT_THROW(keyframePath(keys, 1), InputError);
  EXPECT_THROW(keyframePath({keys[0]}, 4), InputError);
  // Two keyframes swapping position and look_at: the halfway camera has no view direction.
  const std::string e = inputErrorOf([] {
    keyframePath({keyCamera({0, 0, 1}, {0, 0, -1}), keyCamera({0, 0, -1}, {0, 0, 1})}, 3);
  });
  EXPECT_NE(e.find("frame 1 (between keyframes 0 and 1) is degenerate: its look_at is its position"), std::string::npos)
      << e;
}

TEST(ScenePaths, BadPathsNameTheFileAndThePointer) {
  const std::string lv = resolveScenePath("long_view");
  struct Case {
    std::vector<SceneOverride> overrides;
    std::string message;
  } cases[] = {
      {{{"/paths/walk/kind", "spiral"}},
       "/paths/walk/kind: error: got \"spiral\"; expected one of dolly, orbit, keyframes"},
      {{{"/paths/walk/frames", 1}}, "/paths/walk/frames: error: got 1; expected an integer 2..1024"},
      {{{"/paths/walk/frames", 0}}, "/paths/walk/frames: error: got 0; expected an integer 2..1024"},
      {{{"/paths/walk/frames", 2.5}}, "/paths/walk/frames: error: got 2.5; expected an integer 2..1024"},
      {{{"/paths/walk/frames", 1025}}, "/paths/walk/frames: error: got 1025; expected an integer 2..1024"},
      // JSON cannot hold NaN, but an override (and nlohmann in memory) can: still refused.
      {{{"/paths/walk/distance", std::nan("")}}, "/paths/walk/distance: error: got "},
      {{{"/paths/walk/distance", "far"}}, "/paths/walk/distance: error: got \"far\"; expected a number"},
      {{{"/paths/turn/cameras/1/look_at", nlohmann::json::array({0, 1.7, 4})}},
       "/paths/turn/cameras/1: error: keyframe 1 is degenerate: its look_at is its position"},
      {{{"/paths/turn/cameras/1/up", nlohmann::json::array({-20, -0.5, -104})}},
       "/paths/turn/cameras/1: error: keyframe 1 is degenerate: its up is parallel to the view direction"},
      {{{"/paths/turn/cameras", nlohmann::json::array()}},
       "/paths/turn/cameras: error: got an array of 0 values; expected an array of at least 2 cameras"},
      {{{"/paths/walk/speed", 2}},
       "/paths/walk/speed: error: unknown key \"speed\"; expected one of kind, frames, distance"},
      {{{"/paths/walk", 3}}, "/paths/walk: error: got 3; expected a camera path object with \"kind\""},
      {{{"/paths", nlohmann::json::object()}},
       "/paths: error: got an object; expected a non-empty object of named camera paths"},
  };
  for (const Case& c : cases) {
    const std::string e = inputErrorOf([&] { loadScene(lv, c.overrides); });
    EXPECT_EQ(e.rfind(lv + ": ", 0), 0u) << e;
    EXPECT_NE(e.find(c.message), std::string::npos) << "got:      " << e << "\nexpected: " << c.message;
  }
  // A path name must be usable as --path NAME.
  fs::path dir = fs::temp_directory_path() / ("shadowlab_scene_paths_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string file = (dir / "p.json").string();
  std::ofstream(file) << R"({"camera": {"position": [0, 2, 5], "look_at": [0, 0, 0], "vfov_deg": 45, "width": 64,
    "height": 48}, "objects": [{"type": "plane", "size": [10, 10]}], "lights": [{"type": "directional",
    "elevation_deg": 45}], "paths": {"a walk": {"kind": "dolly", "distance": 1, "frames": 2}}})";
  EXPECT_NE(inputErrorOf([&] {
              loadScene(file);
            }).find(file + ": /paths/a walk: error: path name \"a walk\" has a character other than letters"),
            std::string::npos);
  fs::remove_all(dir);
}

}  // namespace scenes_paths_test
