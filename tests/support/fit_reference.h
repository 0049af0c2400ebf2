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

}  // namespace shadowlab::testing
