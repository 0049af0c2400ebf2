// The harness stays well-defined at the extremes: a directional light exactly parallel to
// a receiver (elevation 0 over a plane), a point light inside a closed mesh, and fit-camera paths
// that leave the scene. No NaN in any output channel of either renderer, none in any metric, no
// crash. (near = far and a cascade with nothing in it: tests/raster_cascades_test.cpp.)
//
// In process (the pipeline: renderReference, Rasterizer::render, compareFrames) every channel of
// both frames is checked; through the real binary (`shadowlab stability`), every number of
// stability.json.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>

#include <nlohmann/json.hpp>

#include "shadowlab/compare/compare.h"
#include "shadowlab/raster/raster.h"
#include "shadowlab/reference/reference.h"
#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/loader.h"
#include "shadowlab/scenes/method.h"
#include "support/cli.h"
#include "support/raster_device.h"

namespace robustness_extremes_test {

using namespace shadowlab;
namespace fs = std::filesystem;

namespace {

fs::path tempDir(const std::string& name) {
  fs::path dir = fs::temp_directory_path() / ("shadowlab_robustness_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string writeFile(const fs::path& path, const std::string& text) {
  std::ofstream(path) << text;
  return path.string();
}

// The methods whose arithmetic differs most at the extremes: every fit (the sphere's, the tight
// and cascaded crops, LiSPSM's, PSM's and TSM's warps, stabilized with a blend band) and the biases and filters that divide by
// a slope or a derivative.
std::vector<std::pair<std::string, Method>> extremeMethods() {
  std::vector<std::vector<std::pair<std::string, std::string>>> settings = {
      {},
      {{"fit", "tight"}},
      {{"fit", "lispsm"}},
      {{"fit", "psm"}},
      {{"fit", "tsm"}},
      {{"fit", "cascades"}},
      {{"fit", "cascades"}, {"cascades.stabilize", "true"}, {"cascades.blend", "0.2"}},
      {{"bias.normal", "1.5"}, {"filter", "pcf"}},
      {{"bias.receiver_plane", "true"}, {"filter", "pcf"}, {"filter.size", "5"}},
      {{"filter", "poisson"}},
      {{"filter", "hw2x2"}},
      {{"cull", "back"}},
  };
  std::vector<std::pair<std::string, Method>> out;
  for (const auto& s : settings) {
    Method m;
    std::string name;
    for (const auto& [k, v] : s) {
      applyMethodSetting(m, k, v, "test");
      name += (name.empty() ? "" : ",") + k + "=" + v;
    }
    validateMethod(m, "test");
    out.push_back({name.empty() ? "default" : name, m});
  }
  return out;
}

// Every value of every channel is finite; on failure names the channel, the first bad pixel and value.
void expectFiniteFrame(const Frame& f, const std::string& what) {
  for (size_t c = 0; c < f.names.size(); ++c)
    for (size_t i = 0; i < f.data[c].size(); ++i)
      if (!std::isfinite(f.data[c][i])) {
        ADD_FAILURE() << what << ": channel " << f.names[c] << " is " << f.data[c][i] << " at pixel ("
                      << i % size_t(f.width) << ", " << i / size_t(f.width) << ")";
        break;
      }
}

// Every number in a JSON document is finite (nlohmann keeps a NaN as a number in memory and writes
// it as null: both are caught), on failure naming its JSON pointer. The one null allowed is a
// region's mae and rmse in an object whose count of that region's pixels is 0 (compare/METRICS.md
// "Soft shadows": a binary truth has no penumbra).
void expectFiniteJson(const nlohmann::json& j, const std::string& what, const std::string& pointer = "",
                      const nlohmann::json* parent = nullptr) {
  if (j.is_null() && parent) {
    const std::string key = pointer.substr(pointer.rfind('/') + 1);
    for (const VisRegionInfo& r : kVisRegions)
      if ((key == r.maeMetric || key == r.rmseMetric) && parent->value(r.pixelsMetric, -1) == 0) return;
  }
  if (j.is_null()) ADD_FAILURE() << what << ": " << pointer << " is null (a NaN written as JSON)";
  if (j.is_number_float() && !std::isfinite(j.get<double>()))
    ADD_FAILURE() << what << ": " << pointer << " is " << j.get<double>();
  if (j.is_array())
    for (size_t i = 0; i < j.size(); ++i) expectFiniteJson(j[i], what, pointer + "/" + std::to_string(i));
  if (j.is_object())
    for (auto it = j.begin(); it != j.end(); ++it) expectFiniteJson(it.value(), what, pointer + "/" + it.key(), &j);
}

// Reference and raster of every extreme method, all channels and metrics finite. Returns the
// metrics of each method, by name.
std::vector<std::pair<std::string, Metrics>> checkEveryMethod(const Scene& scene) {
  const Frame reference = renderReference(scene, ReferenceOptions{});
  expectFiniteFrame(reference, scene.name + " reference");
  std::vector<std::pair<std::string, Metrics>> out;
  for (const auto& [name, method] : extremeMethods()) {
    SCOPED_TRACE(scene.name + " " + name);
    Frame raster;
    try {
      raster = shadowlab::testing::rasterizer()->render(scene, method);
    } catch (const std::exception& e) {
      ADD_FAILURE() << scene.name << " " << name << ": render threw: " << e.what();
      continue;
    }
    expectFiniteFrame(raster, scene.name + " raster " + name);
    const Metrics m = compareFrames(reference, raster);
    expectFiniteJson(m.toJson(), scene.name + " metrics " + name);
    out.push_back({name, m});
  }
  return out;
}

// Fails a test after which the Vulkan validation layer reported anything.
class Extremes : public shadowlab::testing::ValidatedRasterTest {};

}  // namespace

// Elevation 0: the sun's rays run exactly along the ground, so the ground's depth-map footprint is
// a line (its slope in light space is infinite) and every lookup on it is the worst grazing case.
// Exact answer from the reference: a receiver parallel to the light is unlit (N . L = 0), and
// every method must produce finite channels and metrics on it.
TEST_F(Extremes, DirectionalLightExactlyParallelToTheReceiver) {
  REQUIRE_DEVICE();
  fs::path dir = tempDir("parallel");
  const std::string path = writeFile(dir / "parallel.json", R"({
    "camera": {"position": [0, 6, 10], "look_at": [0, 0, -2], "vfov_deg": 50, "width": 320, "height": 180},
    "objects": [
      {"type": "plane", "name": "ground", "size": [30, 30]},
      {"type": "box", "name": "block", "size": [1, 1, 1], "transform": {"translate": [0, 0.5, 0]}}
    ],
    "lights": [{"type": "directional", "name": "sun", "elevation_deg": 0, "azimuth_deg": 60}]
  })");
  const Scene scene = loadScene(path);
  ASSERT_EQ(scene.lights[0].direction.y, 0.0f);
  // Exact: N . L = 0 on the ground, which the reference counts as unlit (the light grazes it).
  const Frame reference = renderReference(scene, ReferenceOptions{});
  size_t ground = 0, groundLit = 0;
  for (size_t i = 0; i < reference.pixelCount(); ++i)
    if (reference.get("hit")[i] >= 0.5f && reference.get("object_id")[i] == 1.0f) {
      ++ground;
      groundLit += reference.get("light.sun.vis")[i] >= 0.5f;
    }
  EXPECT_GT(ground, 30000u);
  EXPECT_EQ(groundLit, 0u) << "a light parallel to the ground lit it";
  const auto metrics = checkEveryMethod(scene);
  ASSERT_EQ(metrics.size(), extremeMethods().size());
  for (const auto& [name, m] : metrics) {
    std::printf("  elevation 0, %-58s pixels %6llu error_rate %.5f acne %.5f leak %.5f\n", name.c_str(),
                (unsigned long long)m.pixelsCompared, m.errorRate, m.rate(PixelClass::Acne), m.rate(PixelClass::Leak));
    EXPECT_GT(m.pixelsCompared, 30000u) << name;  // the ground and the block are compared
    EXPECT_LT(m.errorRate, 0.01) << name << ": the rasterizer should agree that the ground is unlit";
  }
  fs::remove_all(dir);
}

// A point light at the center of a closed sphere (two-sided): nothing outside is lit, so the
// reference shadows the whole ground; the cube map's six faces see only the inside of the sphere.
TEST_F(Extremes, PointLightInsideAClosedMesh) {
  REQUIRE_DEVICE();
  fs::path dir = tempDir("inside");
  const std::string path = writeFile(dir / "inside.json", R"({
    "camera": {"position": [0, 4, 8], "look_at": [0, 1, 0], "vfov_deg": 50, "width": 320, "height": 180},
    "objects": [
      {"type": "plane", "name": "ground", "size": [20, 20]},
      {"type": "sphere", "name": "shell", "radius": 1, "segments": 64, "rings": 32, "transform": {"translate": [0, 1.5, 0]}}
    ],
    "lights": [{"type": "point", "name": "bulb", "position": [0, 1.5, 0]}]
  })");
  const Scene scene = loadScene(path);
  const Frame reference = renderReference(scene, ReferenceOptions{});
  // Exact: no ground pixel sees the bulb (object 1 is the ground).
  const auto& hit = reference.get("hit");
  const auto& obj = reference.get("object_id");
  const auto& vis = reference.get("light.bulb.vis");
  size_t ground = 0, groundLit = 0;
  for (size_t i = 0; i < reference.pixelCount(); ++i)
    if (hit[i] >= 0.5f && obj[i] == 1.0f) {
      ++ground;
      groundLit += vis[i] >= 0.5f;
    }
  EXPECT_GT(ground, 20000u);
  EXPECT_EQ(groundLit, 0u) << "a light inside a closed sphere lit the ground";
  const auto metrics = checkEveryMethod(scene);
  ASSERT_EQ(metrics.size(), extremeMethods().size());
  for (const auto& [name, m] : metrics) {
    std::printf("  point light inside a sphere, %-58s error_rate %.5f\n", name.c_str(), m.errorRate);
    // Seen from inside, every triangle of the sphere is a back face: cull=back removes the whole
    // occluder from the cube map and the ground is lit (the method's failure, measured as such);
    // every other method keeps the ground dark.
    if (name == "cull=back") EXPECT_GT(m.errorRate, 0.5) << "culling the back faces must let the light out";
    else EXPECT_LT(m.errorRate, 0.01) << name;
  }
  fs::remove_all(dir);
}

// Fit-camera paths that leave the scene: long_view's camera dollied 400 units forward (past the
// ground's far end at z = -205, looking into nothing), 2000 units backwards, and orbited 180 degrees
// about its look_at (ending beyond the far end, looking back). The tight and cascaded crops of a
// frustum that holds no geometry must stay finite: every number in stability.json is.
TEST_F(Extremes, CameraPathsThatLeaveTheScene) {
  REQUIRE_DEVICE();
  (void)R;
  fs::path dir = tempDir("leave");
  const std::string common =
      "stability long_view --set scene:/camera/width=320 --set scene:/camera/height=180 --cache " +
      (dir / "cache").string();
  const std::vector<std::string> paths = {"--path dolly --frames 3 --distance 400",
                                          "--path dolly --frames 3 --distance -2000",
                                          "--path orbit --frames 3 --angle-deg 180"};
  const std::vector<std::string> fits = {"--set fit=tight", "--set fit=cascades",
                                         "--set fit=cascades --set cascades.stabilize=true"};
  int n = 0;
  for (const auto& path : paths)
    for (const auto& fit : fits) {
      const fs::path out = dir / ("out" + std::to_string(n++));
      shadowlab::testing::CliRun r =
          shadowlab::testing::runShadowlab(common + " " + fit + " " + path + " -o " + out.string(), dir);
      ASSERT_EQ(r.code, 0) << path << " " << fit << ":\n" << r.err;
      std::ifstream in(out / "stability.json");
      const nlohmann::json j = nlohmann::json::parse(in);
      expectFiniteJson(j, path + " " + fit);
      std::printf("  long_view %-40s %-50s shimmer %.5f error_rate max %.5f\n", path.c_str(), fit.c_str(),
                  j["shimmer_rate"].get<double>(), j["error_rate_max"].get<double>());
    }
  fs::remove_all(dir);
}

}  // namespace robustness_extremes_test
