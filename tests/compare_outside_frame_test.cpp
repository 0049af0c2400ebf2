// `shadowlab compare SCENE FRAME -o DIR` with frames from another program (scenes/FRAME-CONTRACT.md),
// through the real binary. The frames are written here as a renderer would write them: the truth's
// own visibility (a frame exactly right) as a 16-bit PNG, then transformed into each misalignment
// compare must refuse (flipped rows, a half-pixel shift traced at an offset, a field of view 5 %
// wider or narrower), planted errors, bad values and bad renderer files.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>

#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>
#include <unistd.h>

#include "shadowlab/compare/outside_frame.h"
#include "shadowlab/raster/raster.h"
#include "shadowlab/reference/reference.h"
#include "shadowlab/scenes/frame.h"
#include "shadowlab/scenes/io.h"
#include "shadowlab/scenes/json_reader.h"
#include "shadowlab/scenes/loader.h"
#include "support/cli.h"
#include "support/raster_device.h"

namespace shadowlab::compare_outside_frame_test {
namespace {

namespace fs = std::filesystem;

constexpr int kWidth = 320, kHeight = 180;

class OutsideFrame : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = testing::freshTempDir(std::string("shadowlab-outside-") +
                                 ::testing::UnitTest::GetInstance()->current_test_info()->name());
    // The bundled grazing scene at 320x180 (the block's long shadow on the ground gives hundreds
    // of edge pixels), written beside the frames so the CLI reads the same scene.
    std::string text = readFile(fs::path(SHADOWLAB_SOURCE_DIR) / "scenes/data/grazing.json");
    const std::string from = "\"width\": 960, \"height\": 540";
    const size_t at = text.find(from);
    ASSERT_NE(at, std::string::npos);
    text.replace(at, from.size(), "\"width\": 320, \"height\": 180");
    scenePath_ = path("grazing.json");
    writeFileAtomic(scenePath_, text);
    scene_ = loadScene(scenePath_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  std::string path(const std::string& rel) const { return (dir_ / rel).string(); }
  testing::CliRun shadowlab(const std::string& args) const { return testing::runShadowlab(args, dir_); }
  // The truth's visibility of the sun, traced with `options` (a shifted camera) for `scene`.
  std::vector<float> vis(const Scene& scene, ReferenceOptions options = {}) const {
    options.channels = ReferenceChannels::Compare;
    return renderReference(scene, options).get("light.sun.vis");
  }
  std::vector<float> hit(const Scene& scene) const {
    ReferenceOptions options;
    options.channels = ReferenceChannels::Compare;
    return renderReference(scene, options).get("hit");
  }
  testing::CliRun compare(const std::string& frame, const std::string& out, const std::string& extra = "") const {
    return shadowlab("compare '" + scenePath_ + "' '" + path(frame) + "' -o '" + path(out) + "' " + extra);
  }
  nlohmann::json metrics(const std::string& out) const { return readJsonFile(path(out + "/metrics.json")); }

  fs::path dir_;
  std::string scenePath_;
  Scene scene_;
};

std::vector<float> flipRows(const std::vector<float>& v, int width, int height) {
  std::vector<float> out(v.size());
  for (int y = 0; y < height; ++y)
    std::copy_n(v.begin() + long(size_t(height - 1 - y) * size_t(width)), width,
                out.begin() + long(size_t(y) * size_t(width)));
  return out;
}

TEST_F(OutsideFrame, TheTruthsOwnVisibilityIsAcceptedAndScoresNoError) {
  writeGreyPng16(path("frame.png"), kWidth, kHeight, vis(scene_));
  const auto r = compare("frame.png", "out");
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json m = metrics("out");
  EXPECT_EQ(m["method"]["frame"], "outside");
  EXPECT_EQ(m["method"]["coverage"], "assumed");
  EXPECT_EQ(m["method"]["boundary_band"], "pixels");
  EXPECT_EQ(m["method"]["alignment"]["verdict"], "aligned");
  EXPECT_GE(m["method"]["alignment"]["edge_pixels"].get<int>(), 64);
  EXPECT_EQ(m["config"], "outside");
  EXPECT_EQ(m["scene"], "grazing");
  EXPECT_EQ(m["light"], "sun");
  EXPECT_EQ(m["metrics"]["error_rate"], 0.0);
  EXPECT_EQ(m["metrics"]["geometry_mismatch"], 0);
  EXPECT_GT(m["metrics"]["pixels_compared"].get<int>(), kWidth * kHeight / 2);
  EXPECT_TRUE(fs::is_regular_file(path("out/errors.png")));
  EXPECT_TRUE(fs::is_regular_file(path("out/triptych.png")));
}

// A shadow-mapped frame with its own errors (shadowlab's rasterizer standing in for an outside
// renderer: its vis alone, as a 16-bit PNG) is accepted, and every pixel whose lit decision
// differs from the truth's is counted as an error, whatever its class.
TEST_F(OutsideFrame, AShadowMappedFrameIsAcceptedWithItsErrorsCounted) {
  REQUIRE_DEVICE();
  Method method;
  method.mapSize = 256;  // coarse: aliasing along the block's shadow
  const Frame raster = R->render(scene_, method, "sun");
  writeGreyPng16(path("frame.png"), kWidth, kHeight, raster.get("light.sun.vis"));
  const std::vector<float> decoded = readImagePlane(path("frame.png"), "").values;
  const std::vector<float> truth = vis(scene_), h = hit(scene_);
  uint64_t wrong = 0;
  for (size_t i = 0; i < truth.size(); ++i) wrong += h[i] == 1.0f && (truth[i] >= 0.5f) != (decoded[i] >= 0.5f);
  ASSERT_GT(wrong, 20u) << "the coarse map should alias";
  const auto r = compare("frame.png", "out");
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json m = metrics("out");
  EXPECT_EQ(m["method"]["alignment"]["verdict"], "aligned");
  EXPECT_EQ(m["metrics"]["errors"].get<uint64_t>(), wrong);
  EXPECT_GT(m["metrics"]["aliasing"].get<uint64_t>(), 0u);
  EXPECT_EQ(m["metrics"]["acne"], 0);  // no evidence channel: acne is never proven
}

// Each misalignment is refused with exit 2, its own message, and no output folder.
void expectRefused(const testing::CliRun& r, const std::string& said, const std::string& out) {
  EXPECT_EQ(r.code, 2) << r.out << r.err;
  EXPECT_NE(r.err.find(said), std::string::npos) << "stderr: " << r.err << "\nexpected it to say: " << said;
  EXPECT_NE(r.err.find("frame.png"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out)) << out;
}

TEST_F(OutsideFrame, RowsBottomUpAreRefusedAsUpsideDown) {
  writeGreyPng16(path("frame.png"), kWidth, kHeight, flipRows(vis(scene_), kWidth, kHeight));
  expectRefused(compare("frame.png", "out"), "looks upside down", path("out"));
}

TEST_F(OutsideFrame, AHalfPixelShiftInXIsRefused) {
  ReferenceOptions shifted;
  shifted.pixelOffset = {0.5f, 0.0f};
  writeGreyPng16(path("frame.png"), kWidth, kHeight, vis(scene_, shifted));
  expectRefused(compare("frame.png", "out"), "looks shifted by half a pixel in x:", path("out"));
}

TEST_F(OutsideFrame, AHalfPixelShiftInYIsRefused) {
  ReferenceOptions shifted;
  shifted.pixelOffset = {0.0f, -0.5f};
  writeGreyPng16(path("frame.png"), kWidth, kHeight, vis(scene_, shifted));
  expectRefused(compare("frame.png", "out"), "looks shifted by half a pixel in y:", path("out"));
}

TEST_F(OutsideFrame, AFieldOfView5PercentWiderOrNarrowerIsRefused) {
  Scene wider = scene_, narrower = scene_;
  wider.camera.vfovDeg *= 1.05f;
  narrower.camera.vfovDeg *= 0.95f;
  writeGreyPng16(path("frame.png"), kWidth, kHeight, vis(wider));
  expectRefused(compare("frame.png", "out"), "looks rendered with a wider field of view (+5%", path("out"));
  writeGreyPng16(path("frame.png"), kWidth, kHeight, vis(narrower));
  expectRefused(compare("frame.png", "out"), "looks rendered with a narrower field of view (-5%", path("out"));
}

TEST_F(OutsideFrame, AFlippedCoverageIsRefusedToo) {
  // With coverage the geometry's own edges (the block, the ground's far edge) count as well.
  writeGreyPng16(path("frame.png"), kWidth, kHeight, flipRows(vis(scene_), kWidth, kHeight));
  writeGreyPng16(path("coverage.png"), kWidth, kHeight, flipRows(hit(scene_), kWidth, kHeight));
  expectRefused(compare("frame.png", "out", "--coverage '" + path("coverage.png") + "'"), "looks upside down",
                path("out"));
}

TEST_F(OutsideFrame, AFeaturelessFrameIsScoredAsCannotTell) {
  // Ground and sun, no occluder: no shadow edge, so no transform can be told from another; the
  // frame is scored, and metrics.json says the alignment could not be told.
  writeFileAtomic(path("flat.json"), R"({
    "camera": {"position": [0, 6, 10], "look_at": [0, 0, -2], "vfov_deg": 50, "width": 320, "height": 180},
    "objects": [{"type": "plane", "name": "ground", "size": [60, 60]}],
    "lights": [{"type": "directional", "name": "sun", "elevation_deg": 40, "azimuth_deg": 60}]
  })");
  const Scene flat = loadScene(path("flat.json"));
  writeGreyPng16(path("frame.png"), kWidth, kHeight, flipRows(vis(flat), kWidth, kHeight));
  const auto r = shadowlab("compare '" + path("flat.json") + "' '" + path("frame.png") + "' -o '" + path("out") + "'");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("alignment: cannot tell (0 edge pixels"), std::string::npos) << r.out;
  EXPECT_EQ(metrics("out")["method"]["alignment"]["verdict"], "cannot tell");
}

TEST_F(OutsideFrame, AnotherSizeOrAspectIsRefused) {
  writeGreyPng16(path("frame.png"), 160, 90, std::vector<float>(160 * 90, 1.0f));
  expectRefused(compare("frame.png", "out"),
                "looks rendered at another size: the frame is 160x90 where the scene's camera is 320x180", path("out"));
  writeGreyPng16(path("frame.png"), 320, 240, std::vector<float>(320 * 240, 1.0f));
  expectRefused(compare("frame.png", "out"), "looks rendered with another aspect", path("out"));
}

TEST_F(OutsideFrame, PlantedErrorsFarFromEdgesAreCountedExactly) {
  // 37 pixels of the lit ground, each more than 2 pixels (the boundary band) from any shadow
  // edge, made dark: 37 wrong pixels, every one "other" (no evidence proves acne), none aliasing.
  std::vector<float> v = vis(scene_);
  const std::vector<float> h = hit(scene_);
  int planted = 0;
  for (int y = 100; y < kHeight - 3 && planted < 37; y += 3) {
    for (int x = 4; x < kWidth - 4 && planted < 37; x += 7) {
      bool far = true;
      for (int dy = -3; dy <= 3 && far; ++dy)
        for (int dx = -3; dx <= 3 && far; ++dx) {
          const size_t n = size_t(y + dy) * kWidth + size_t(x + dx);
          far = h[n] == 1.0f && v[n] == 1.0f;
        }
      if (!far) continue;
      v[size_t(y) * kWidth + size_t(x)] = 0.0f;
      ++planted;
    }
  }
  ASSERT_EQ(planted, 37);
  writeGreyPng16(path("frame.png"), kWidth, kHeight, v);
  const auto r = compare("frame.png", "out");
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json m = metrics("out")["metrics"];
  EXPECT_EQ(m["other"], 37);
  EXPECT_EQ(m["aliasing"], 0);
  EXPECT_EQ(m["acne"], 0);
  EXPECT_EQ(m["leak"], 0);
}

// A renderer.json with the light's matrix and map size: the blind rule names the classes. On the
// truth's own frame (no error of its own), dark pixels planted on the lit ground far from every
// shadow edge are acne (nothing lies between them and the light, so only the receiver can shadow
// itself), the same whatever filter is declared; with a declared layer that covers only the middle
// of the map, those outside it are coverage. (The too-lit classes by contact and filter:
// compare_metrics_blind_test.cpp; the rule against the full one: compare_blind_agreement_test.cpp.)
TEST_F(OutsideFrame, ADeclaredMapNamesAcneAndCoverageOfPlantedErrors) {
  REQUIRE_DEVICE();
  Method method;
  method.mapSize = 4096;  // the block's shadow on the ground spans many texels: bands narrower than it
  R->render(scene_, method, "sun");
  const std::vector<glm::mat4> layers = R->lastLightClipFromWorld();
  ASSERT_EQ(layers.size(), 1u);
  const std::vector<float> truth = vis(scene_), h = hit(scene_);
  ReferenceOptions ids;
  ids.channels = ReferenceChannels::Compare;
  const std::vector<float> id = renderReference(scene_, ids).get("object_id");
  const float ground = id[size_t(kHeight - 2) * kWidth + kWidth / 2];  // the bottom row sees the ground
  std::vector<float> v = truth;
  // Ground pixels whose 9x9 neighbourhood is all ground of one decision: far from every true edge
  // (and not the block's own faces turned from the sun).
  auto plant = [&](float decision, float to, int count, int step, int reach) {
    int planted = 0;
    for (int y = 6; y < kHeight - 6 && planted < count; y += step)
      for (int x = 6; x < kWidth - 6 && planted < count; x += 2 * step + 1) {
        bool far = true;
        for (int dy = -reach; dy <= reach && far; ++dy)
          for (int dx = -reach; dx <= reach && far; ++dx) {
            const int nx = x + dx, ny = y + dy;
            if (nx < 0 || ny < 0 || nx >= kWidth || ny >= kHeight) {
              far = false;
              break;
            }
            const size_t n = size_t(ny) * kWidth + size_t(nx);
            far = h[n] == 1.0f && id[n] == ground && truth[n] == decision;
          }
        if (!far) continue;
        v[size_t(y) * kWidth + size_t(x)] = to;
        ++planted;
      }
    return planted;
  };
  ASSERT_EQ(plant(1.0f, 0.0f, 40, 3, 4), 40);  // lit ground made dark
  writeGreyPng16(path("frame.png"), kWidth, kHeight, v);
  auto declare = [&](const glm::mat4& layer, const std::string& filter) {
    std::string elements;
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r) elements += (elements.empty() ? "" : ",") + std::to_string(double(layer[c][r]));
    writeFileAtomic(path("renderer.json"), "{\"name\": \"declared\", \"light_clip_from_world\": [[" + elements +
                                               "]], \"map_size\": 4096, \"filter\": \"" + filter + "\"}");
    return "--renderer '" + path("renderer.json") + "'";
  };
  auto r = compare("frame.png", "pcf", declare(layers[0], "PCF"));
  ASSERT_EQ(r.code, 0) << r.err;
  nlohmann::json m = metrics("pcf")["metrics"];
  EXPECT_EQ(m["errors"], 40);
  EXPECT_EQ(m["acne"], 40);
  EXPECT_EQ(m["coverage"], 0);
  r = compare("frame.png", "vsm", declare(layers[0], "VSMShadowMap"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(metrics("vsm")["metrics"]["acne"], 40);
  // Without a declared map the band is in pixels and a texel may span many: never acne.
  r = compare("frame.png", "none");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(metrics("none")["metrics"]["acne"], 0);
  EXPECT_EQ(metrics("none")["metrics"]["other"], 40);
  // A layer twice as fine (x/w and y/w doubled): only the middle half of the old one is inside.
  const glm::mat4 zoom = glm::scale(glm::mat4(1.0f), glm::vec3(2.0f, 2.0f, 1.0f)) * layers[0];
  r = compare("frame.png", "zoom", declare(zoom, "PCF"));
  ASSERT_EQ(r.code, 0) << r.err;
  m = metrics("zoom")["metrics"];
  EXPECT_EQ(m["errors"], 40);
  EXPECT_GT(m["coverage"].get<int>(), 0);
  EXPECT_LT(m["coverage"].get<int>(), 40);
  EXPECT_EQ(m["coverage"].get<int>() + m["acne"].get<int>(), 40);
}

TEST_F(OutsideFrame, CoverageDisagreementIsGeometryMismatchNotScored) {
  const std::vector<float> h = hit(scene_);
  std::vector<float> coverage = h;
  // 50 pixels of surface the renderer says it did not draw: geometry mismatch, not scored.
  int removed = 0;
  for (size_t i = size_t(kWidth) * 150; i < coverage.size() && removed < 50; i += 13) {
    if (coverage[i] == 1.0f) {
      coverage[i] = 0.0f;
      ++removed;
    }
  }
  ASSERT_EQ(removed, 50);
  writeGreyPng16(path("frame.png"), kWidth, kHeight, vis(scene_));
  writeGreyPng16(path("coverage.png"), kWidth, kHeight, coverage);
  const auto r = compare("frame.png", "out", "--coverage '" + path("coverage.png") + "'");
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json m = metrics("out");
  EXPECT_EQ(m["method"]["coverage"], "given");
  EXPECT_EQ(m["metrics"]["geometry_mismatch"], 50);
  EXPECT_EQ(m["metrics"]["error_rate"], 0.0);

  // A depth image: 1 (the far plane) where there is no surface.
  std::vector<float> depth(h.size());
  for (size_t i = 0; i < h.size(); ++i) depth[i] = h[i] == 1.0f ? 0.25f : 1.0f;
  writeGreyPng16(path("depth.png"), kWidth, kHeight, depth);
  const auto d = compare("frame.png", "depth_out", "--coverage '" + path("depth.png") + "' --coverage-far 1");
  ASSERT_EQ(d.code, 0) << d.err;
  EXPECT_EQ(metrics("depth_out")["metrics"]["geometry_mismatch"], 0);
}

TEST_F(OutsideFrame, BadValuesAndChannelsNameTheFileChannelAndPixel) {
  // An EXR with a NaN at (5, 2): exit 2 naming file, channel and the first pixel.
  Frame exr;
  exr.width = kWidth;
  exr.height = kHeight;
  exr.add("vis") = vis(scene_);
  exr.get("vis")[size_t(2) * kWidth + 5] = std::numeric_limits<float>::quiet_NaN();
  writeFrameExr(exr, path("frame.exr"));
  auto r = shadowlab("compare '" + scenePath_ + "' '" + path("frame.exr") + "' -o '" + path("out") + "'");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("frame.exr: channel vis pixel (5, 2): error: got nan; expected a finite number"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(path("out")));
  // Out of range in an EXR.
  exr.get("vis")[size_t(2) * kWidth + 5] = 1.5f;
  writeFrameExr(exr, path("frame.exr"));
  r = shadowlab("compare '" + scenePath_ + "' '" + path("frame.exr") + "' -o '" + path("out") + "'");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("frame.exr: channel vis pixel (5, 2): error: got 1.5; expected a number in [0, 1]"),
            std::string::npos)
      << r.err;
  // A 16-bit grey PNG has no channel R.
  writeGreyPng16(path("frame.png"), kWidth, kHeight, vis(scene_));
  r = compare("frame.png", "out", "--channel R");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("frame.png: channel R: error: a 16-bit grey PNG has no such channel; expected one of Y"),
            std::string::npos)
      << r.err;
  // A colour PNG must name its channel.
  std::vector<uint8_t> rgb(size_t(kWidth) * kHeight * 3, 255);
  rgb[1] = 0;
  writeRgbPng(path("colour.png"), kWidth, kHeight, rgb);
  r = compare("colour.png", "out");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("has colour"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(path("out")));
}

TEST_F(OutsideFrame, TheRendererJsonIsValidatedAndNamesTheConfiguration) {
  writeGreyPng16(path("frame.png"), kWidth, kHeight, vis(scene_));
  writeFileAtomic(path("bad.json"), "{\"name\": \"mine\", \"map_size\": 0}");
  auto r = compare("frame.png", "out", "--renderer '" + path("bad.json") + "'");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("bad.json: /map_size: error: got 0; expected an integer 1..65536"), std::string::npos) << r.err;
  writeFileAtomic(path("typo.json"), "{\"name\": \"mine\",\n \"filtr\": \"PCF\"}");
  r = compare("frame.png", "out", "--renderer '" + path("typo.json") + "'");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("typo.json: /filtr: error: unknown key"), std::string::npos) << r.err;
  writeFileAtomic(path("syntax.json"), "{\"name\": \"mine\",\n \"filter\" \"PCF\"}");
  r = compare("frame.png", "out", "--renderer '" + path("syntax.json") + "'");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("syntax.json:2:"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(path("out")));

  writeFileAtomic(path("renderer.json"), R"({
    // three.js-style settings
    "name": "mine 1.0",
    "light_clip_from_world": [[1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]],
    "map_size": 2048, "depth_bias": -0.0005, "normal_bias_world": 0.02, "filter": "PCFSoft", "frame_ms": 4.5,
    "settings": {"mapSize": 2048, "bias": -0.0005, "type": "PCFSoft"}
  })");
  r = compare("frame.png", "out", "--renderer '" + path("renderer.json") + "'");
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json m = metrics("out");
  EXPECT_EQ(m["config"], "renderer=mine 1.0,bias=-0.0005,mapSize=2048,type=PCFSoft");
  EXPECT_EQ(m["method"]["renderer"], "mine 1.0");
  EXPECT_EQ(m["method"]["map_size"], 2048);
  EXPECT_EQ(m["method"]["frame_ms"], 4.5);
  EXPECT_EQ(m["timings"]["renderer_frame_ms"], 4.5);
}

TEST_F(OutsideFrame, GatePassesTheSameRendererAndFailsAWorseFrame) {
  writeFileAtomic(path("renderer.json"), R"({"name": "mine", "settings": {"mapSize": 1024}})");
  const std::string renderer = "--renderer '" + path("renderer.json") + "'";
  std::vector<float> v = vis(scene_);
  writeGreyPng16(path("frame.png"), kWidth, kHeight, v);
  ASSERT_EQ(compare("frame.png", "base", renderer).code, 0);
  ASSERT_EQ(compare("frame.png", "run", renderer).code, 0);
  auto g = shadowlab("gate '" + path("run/metrics.json") + "' --baseline '" + path("base/metrics.json") + "'");
  EXPECT_EQ(g.code, 0) << g.out << g.err;
  // A worse frame: every 5th lit pixel of the lower half shadowed.
  for (size_t i = size_t(kWidth) * (kHeight / 2); i < v.size(); i += 5) v[i] = 0.0f;
  writeGreyPng16(path("frame.png"), kWidth, kHeight, v);
  const auto worse = compare("frame.png", "worse", renderer);
  ASSERT_EQ(worse.code, 0) << worse.err;
  g = shadowlab("gate '" + path("worse/metrics.json") + "' --baseline '" + path("base/metrics.json") + "'");
  EXPECT_EQ(g.code, 1) << g.out << g.err;
  EXPECT_NE(g.err.find("error_rate"), std::string::npos) << g.err;
}

TEST_F(OutsideFrame, ASoftShadowFrameOfTheTruthIsAcceptedWithoutError) {
  // A sized light: the truth's fractional visibility, 16-bit (quantization error <= 1/131070,
  // far below the soft tolerance), is right; compare scores it in soft mode.
  std::string text = readFile(fs::path(SHADOWLAB_SOURCE_DIR) / "scenes/data/soft_post.json");
  const std::string from = "\"width\": 640, \"height\": 360";
  const size_t at = text.find(from);
  ASSERT_NE(at, std::string::npos);
  text.replace(at, from.size(), "\"width\": 160, \"height\": 90");
  writeFileAtomic(path("soft.json"), text);
  const Scene soft = loadScene(path("soft.json"));
  ReferenceOptions options;
  options.channels = ReferenceChannels::Compare;
  const Frame truth = renderReference(soft, options);
  const std::string light = soft.lightOrDefault("");
  const std::vector<float>& v = truth.get("light." + light + ".vis");
  ASSERT_TRUE(std::any_of(v.begin(), v.end(), [](float x) { return x > 0.05f && x < 0.95f; })) << "no penumbra";
  writeGreyPng16(path("frame.png"), 160, 90, v);
  const auto r = shadowlab("compare '" + path("soft.json") + "' '" + path("frame.png") + "' -o '" + path("out") + "'");
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json m = metrics("out")["metrics"];
  EXPECT_EQ(m["error_rate"], 0.0);
  EXPECT_GT(m["penumbra_pixels"].get<int>(), 0);
  EXPECT_LT(m["penumbra_mae"].get<double>(), 1e-5);
}

TEST_F(OutsideFrame, AReferenceFolderInPlaceOfTheSceneIsRefused) {
  writeGreyPng16(path("frame.png"), kWidth, kHeight, vis(scene_));
  fs::create_directories(path("ref"));
  const auto r = shadowlab("compare '" + path("ref") + "' '" + path("frame.png") + "' -o '" + path("out") + "'");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("ref: error: is a folder; a frame from another program"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(path("out")));
}

TEST_F(OutsideFrame, OutsideOptionsOnShadowlabsOwnFramesAreRefused) {
  Frame f;
  f.width = 4;
  f.height = 4;
  f.meta["kind"] = "reference";
  f.add("hit", 1.0f);
  writeFrameExr(f, path("reference.exr"));
  writeFrameExr(f, path("raster.exr"));
  const auto r = shadowlab("compare '" + path("reference.exr") + "' '" + path("raster.exr") + "' -o '" + path("out") +
                           "' --channel R");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("apply to a frame from another program"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace shadowlab::compare_outside_frame_test
