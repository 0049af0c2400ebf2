#pragma once
// Shared by the warped fits' tests against the reference (lispsm, psm, tsm): the same method at
// one map size with only the fit changed, scenes written inline, and the frame checks every fit
// must pass.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "shadowlab/scenes/frame.h"
#include "shadowlab/scenes/loader.h"
#include "shadowlab/scenes/method.h"

namespace shadowlab::testing {

// The default method with `fit` at map.size 1024 (the fit tests' common size).
inline Method fitted(Fit fit) {
  Method m;
  m.mapSize = 1024;
  m.fit = fit;
  return m;
}

// A scene from JSON text, loaded through a file as a user's would be.
inline Scene sceneFromText(const std::string& name, const std::string& text) {
  namespace fs = std::filesystem;
  fs::path dir = fs::temp_directory_path() / ("shadowlab_fit_scene_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  fs::path file = dir / (name + ".json");
  std::ofstream(file) << text;
  Scene s = loadScene(file.string());
  fs::remove_all(dir);
  return s;
}

inline void expectAllFinite(const Frame& f, const std::string& what) {
  for (size_t c = 0; c < f.names.size(); ++c)
    for (float v : f.data[c]) ASSERT_TRUE(std::isfinite(v)) << what << ": " << f.names[c];
}

// The camera pass does not depend on the fit: the same surfaces in the same pixels.
inline void expectSameGeometry(const Frame& a, const Frame& b) {
  for (const char* ch : {"hit", "object_id", "prim_id"}) EXPECT_EQ(a.get(ch), b.get(ch)) << ch;
}

// The fall-back tests' scene: a ground, a ball and a crate seen from `position` towards `lookAt`
// (up -z), lit by a sun travelling along `light` (JSON arrays as text).
inline Scene alongTheLightScene(const std::string& name, const std::string& light, const std::string& position,
                                const std::string& lookAt, int width, int height) {
  return sceneFromText(name, R"({
  "camera": {"position": )" + position +
                                 R"(, "look_at": )" + lookAt + R"(, "up": [0, 0, -1], "vfov_deg": 50, "width": )" +
                                 std::to_string(width) + R"(, "height": )" + std::to_string(height) +
                                 R"(, "near": 0.1, "far": 100},
  "objects": [
    {"type": "plane", "name": "ground", "size": [20, 20]},
    {"type": "sphere", "name": "ball", "radius": 1, "transform": {"translate": [0, 2, 0]}},
    {"type": "box", "name": "crate", "size": [1, 1, 1], "transform": {"translate": [3, 0.5, 2], "rotate_deg": [0, 30, 0]}}
  ],
  "lights": [{"type": "directional", "name": "sun", "direction": )" +
                                 light + R"(}]
})");
}

// The fall-back tests' views of alongTheLightScene: exactly along the light (either way, or
// tilted with it: a warped fit must give tight's frame) and one degree off it (the warp is built).
struct AlongTheLightCase {
  const char* name;
  const char* light;     // direction of travel
  const char* position;  // camera
  const char* lookAt;
  bool exact;  // exactly along the light: the same frame as tight
};
inline std::vector<AlongTheLightCase> alongTheLightCases() {
  return {
      {"down_down", "[0, -1, 0]", "[0.5, 12, 0.25]", "[0.5, 0, 0.25]", true},
      {"down_up", "[0, 1, 0]", "[0.5, 12, 0.25]", "[0.5, 0, 0.25]", true},
      {"tilted", "[0.3, -1, 0.2]", "[-3, 10, -2]", "[0, 0, 0]", true},
      {"one_degree", "[0, -1, 0]", "[0.2905, 12, 0.25]", "[0.5, 0, 0.25]", false},
  };
}

// Every channel of `tight` equal in `other`, bit for bit (the fall-back to tight's matrix).
inline void expectSameFrame(const Frame& tight, const Frame& other, const std::string& what) {
  for (size_t k = 0; k < tight.names.size(); ++k)
    EXPECT_EQ(tight.data[k], other.get(tight.names[k])) << what << ": " << tight.names[k];
}

// A pole behind the camera (outside the view frustum) whose shadow falls forward into view: camera
// 3 up looking down -z; the pole at z = +6, 6 tall; the light travels (0.4, -0.3, -1), so the
// shadow runs from (0, 0, 6) to (8, 0, -14), in view from z = -3.4 on.
inline Scene poleBehindScene() {
  return sceneFromText("pole_behind", R"({
  "camera": {"position": [0, 3, 0], "look_at": [0, 0, -10], "vfov_deg": 50, "width": 320, "height": 240, "near": 0.1, "far": 100},
  "objects": [
    {"type": "plane", "name": "ground", "size": [40, 60], "transform": {"translate": [0, 0, -15]}},
    {"type": "cylinder", "name": "pole", "radius": 0.3, "height": 6, "segments": 32, "transform": {"translate": [0, 3, 6]}}
  ],
  "lights": [{"type": "directional", "name": "sun", "direction": [0.4, -0.3, -1]}]
})");
}

}  // namespace shadowlab::testing
