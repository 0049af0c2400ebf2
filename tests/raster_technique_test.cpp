// Technique files (method key technique, raster/METHODS.md "Your own technique"): compiled at run
// time into the lookup and evidence passes. examples/techniques/pcf.glsl must reproduce the built-in
// filter=pcf bit for bit, every channel and the lookup's bytes, for several sizes, light types and
// biases; a file that does not compile is an InputError naming file:line:column before anything is
// drawn. Quarter-size cameras keep the executable fast on lavapipe.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include "shadowlab/raster/raster.h"
#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/loader.h"
#include "shadowlab/scenes/technique.h"
#include "support/cli.h"
#include "support/raster_device.h"

namespace raster_technique_test {

using namespace shadowlab;

namespace {

using RasterTechnique = shadowlab::testing::ValidatedRasterTest;

const std::string kExamples = std::string(SHADOWLAB_SOURCE_DIR) + "/examples/techniques/";

Scene quarterScene(const std::string& name) {
  Scene s = loadScene(resolveScenePath(name));
  s.camera.width /= 4;
  s.camera.height /= 4;
  return s;
}

// Every channel of two frames bit for bit; "" or the first difference.
std::string firstDifference(const Frame& a, const Frame& b) {
  if (a.names != b.names) return "different channel lists";
  for (size_t c = 0; c < a.names.size(); ++c)
    for (size_t i = 0; i < a.data[c].size(); ++i)
      if (std::memcmp(&a.data[c][i], &b.data[c][i], 4) != 0)
        return a.names[c] + " at pixel " + std::to_string(i) + ": " + std::to_string(a.data[c][i]) + " vs " +
               std::to_string(b.data[c][i]);
  return "";
}

std::string writeFile(const std::filesystem::path& dir, const std::string& name, const std::string& text) {
  const std::filesystem::path p = dir / name;
  std::ofstream(p, std::ios::binary) << text;
  return p.string();
}

}  // namespace

// pcf.glsl with technique.size = N against filter=pcf filter.size = N: the same bits in every
// channel (vis, its evidence, the lookup's bytes), with fractional pixels present (a filter that
// returned 0/1 only could not pass), for two directional lights, with and without the
// receiver-plane bias, and a point light (a cube map: q.layer picks the face).
TEST_F(RasterTechnique, PcfFileIsTheBuiltInPcfBitForBit) {
  REQUIRE_DEVICE();
  Scene point = quarterScene("sphere_on_plane");
  point.name = "sphere_on_plane, a point light";
  point.lights.front().type = LightType::Point;
  point.lights.front().position = glm::vec3(1.5f, 4.0f, 1.0f);
  for (const Scene& s : {quarterScene("sphere_on_plane"), quarterScene("contact"), point}) {
    const char* sceneName = s.name.c_str();
    const bool pointLight = s.lights.front().type == LightType::Point;
    for (int size : {3, 5})
      for (bool receiverPlane : {false, true}) {
        if (pointLight && (size == 3 || receiverPlane)) continue;  // one case: the faces are what is new
        Method builtIn;
        builtIn.filter = Filter::Pcf;
        builtIn.filterSize = size;
        builtIn.mapSize = 512;
        builtIn.biasReceiverPlane = receiverPlane;
        Method file = builtIn;
        file.filter = Filter::None;
        file.technique = kExamples + "pcf.glsl";
        file.techniqueParams["size"] = size;
        validateMethod(file, "test");
        const Frame a = R->render(s, builtIn);
        const std::vector<uint8_t> bytesA = R->lookupVisibility();
        const Frame b = R->render(s, file);
        const std::vector<uint8_t> bytesB = R->lookupVisibility();
        const std::string where =
            std::string(sceneName) + " size " + std::to_string(size) + (receiverPlane ? " receiver plane" : "");
        EXPECT_EQ(firstDifference(a, b), "") << where;
        EXPECT_EQ(bytesA, bytesB) << where;
        size_t fractional = 0;
        for (float v : a.get("light." + s.lights.front().name + ".vis")) fractional += v > 0.0f && v < 1.0f;
        EXPECT_GT(fractional, 100u) << where;
      }
  }
}

// Evidence on demand: the evidence pass (compact) resolves the listed pixels with the technique too.
TEST_F(RasterTechnique, PcfFileOnDemandMatchesTheBuiltIn) {
  REQUIRE_DEVICE();
  const Scene s = quarterScene("sphere_on_plane");
  Method builtIn;
  builtIn.filter = Filter::Pcf;
  builtIn.filterSize = 5;
  builtIn.mapSize = 256;
  Method file = builtIn;
  file.filter = Filter::None;
  file.technique = kExamples + "pcf.glsl";
  file.techniqueParams["size"] = 5;
  // Lists every other pixel for the full evidence (the fractional ones are listed anyway).
  EvidenceSelector select = [](const uint8_t*, int width, int height, EvidenceRequest& request) {
    for (int i = 0; i < width * height; i += 2) request.full.push_back(uint32_t(i));
  };
  // Each frame handed back before the next (its group's planes are lent to it), a copy kept.
  R->recycle(R->render(s, builtIn, "", nullptr, nullptr, &select));  // the group's first frame
  Frame a = R->render(s, builtIn, "", nullptr, nullptr, &select);
  const Frame keptA = a;
  R->recycle(std::move(a));
  Frame b = R->render(s, file, "", nullptr, nullptr, &select);
  ASSERT_EQ(keptA.meta.value("evidence", ""), "partial");
  ASSERT_EQ(b.meta.value("evidence", ""), "partial");
  EXPECT_EQ(firstDifference(keptA, b), "");
  R->recycle(std::move(b));
}

// A declared key reaches the shader: a larger pcf grid gives other (softer) visibilities.
TEST_F(RasterTechnique, DeclaredKeysAreSpecializationConstants) {
  REQUIRE_DEVICE();
  const Scene s = quarterScene("sphere_on_plane");
  Method m;
  m.mapSize = 256;
  m.technique = kExamples + "pcf.glsl";
  m.techniqueParams["size"] = 3;
  const Frame small = R->render(s, m);
  m.techniqueParams["size"] = 9;
  const Frame large = R->render(s, m);
  Method builtIn;
  builtIn.mapSize = 256;
  builtIn.filter = Filter::Pcf;
  builtIn.filterSize = 9;
  EXPECT_NE(firstDifference(small, large), "");
  EXPECT_EQ(firstDifference(large, R->render(s, builtIn)), "");
}

// The other examples compile and render: soft edges (fractional pixels), shadow and light.
TEST_F(RasterTechnique, ExamplesRender) {
  REQUIRE_DEVICE();
  const Scene s = quarterScene("sphere_on_plane");
  for (const char* file : {"poisson_ign.glsl", "pcss.glsl"}) {
    Method m;
    m.mapSize = 512;
    m.technique = kExamples + file;
    validateMethod(m, "test");
    const Frame f = R->render(s, m);
    size_t lit = 0, shadowed = 0, fractional = 0;
    const auto& vis = f.get("light." + s.lights.front().name + ".vis");
    const auto& hit = f.get("hit");
    for (size_t i = 0; i < vis.size(); ++i) {
      if (hit[i] < 0.5f) continue;
      lit += vis[i] == 1.0f, shadowed += vis[i] == 0.0f, fractional += vis[i] > 0.0f && vis[i] < 1.0f;
    }
    EXPECT_GT(lit, 1000u) << file;
    EXPECT_GT(shadowed, 100u) << file;
    EXPECT_GT(fractional, 100u) << file;
  }
}

// A file glslang refuses: an InputError at the user's file:line:column with glslang's message,
// before any pipeline exists.
TEST_F(RasterTechnique, CompileErrorNamesTheUsersLine) {
  REQUIRE_DEVICE();
  const auto dir = shadowlab::testing::freshTempDir("raster_technique_compile");
  const std::string path = writeFile(dir, "broken.glsl",
                                     "// a comment\n"
                                     "float shadowVisibility(ShadowQuery q) {\n"
                                     "  float x = q.depth +;\n"
                                     "  return x;\n"
                                     "}\n");
  Method m;
  m.mapSize = 64;
  m.technique = path;
  const Scene s = quarterScene("sphere_on_plane");
  try {
    R->render(s, m);
    FAIL() << "no error";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.substr(0, what.find('\n')), path + ":3:22: error: syntax error, unexpected SEMICOLON");
  }
  // An undeclared identifier: glslang's words, at its line and column.
  const std::string undeclared = writeFile(dir, "undeclared.glsl",
                                           "float shadowVisibility(ShadowQuery q) {\n"
                                           "  return q.depth * technique_radius;\n"
                                           "}\n");
  m.technique = undeclared;
  try {
    R->render(s, m);
    FAIL() << "no error";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.substr(0, what.find('\n')), undeclared + ":2:20: error: 'technique_radius': undeclared identifier");
  }
}

// A file that reads q.planeSlope needs the triangle's normal in the lookup pass too (the surface
// image has none: kSpecTechniqueNormal): the lookup's bytes are the resolve's vis in 8 bits, as for
// the built-in filters (raster_lookup_test.cpp's rule), fractional pixels included.
TEST_F(RasterTechnique, LookupEqualsTheResolveWhenTheFileReadsThePlane) {
  REQUIRE_DEVICE();
  const auto dir = shadowlab::testing::freshTempDir("raster_technique_plane");
  const std::string path =
      writeFile(dir, "plane.glsl",
                "float shadowVisibility(ShadowQuery q) {\n"
                "  ivec2 c = ivec2(floor(q.st));\n"
                "  float sum = 0.0;\n"
                "  for (int y = -1; y <= 1; ++y)\n"
                "    for (int x = -1; x <= 1; ++x) {\n"
                "      ivec2 t = clamp(c + ivec2(x, y), ivec2(0), ivec2(int(q.mapSize) - 1));\n"
                "      float ref = q.depth + dot(q.planeSlope, vec2(c + ivec2(x, y)) + 0.5 - q.st);\n"
                "      sum += texelFetch(mapDepth, ivec3(t, q.layer), 0).r >= ref ? 1.0 : 0.0;\n"
                "    }\n"
                "  return sum / 9.0;\n"
                "}\n");
  const Scene s = quarterScene("grazing");
  Method m;
  m.mapSize = 512;
  m.biasCompare = 0;
  m.technique = path;
  const Frame f = R->render(s, m);
  const std::vector<uint8_t> bytes = R->lookupVisibility();
  const auto& vis = f.get("light." + s.lights.front().name + ".vis");
  ASSERT_EQ(bytes.size(), vis.size());
  size_t mismatches = 0, fractional = 0;
  for (size_t i = 0; i < vis.size(); ++i) {
    const float v = vis[i] >= 1.0f ? 1.0f : (vis[i] > 0.0f ? vis[i] : 0.0f);
    int expected = v == 0.0f ? 0 : v == 1.0f ? 255 : int(std::lround(double(v) * 255.0));
    if (v > 0.0f && v < 1.0f) expected = v >= 0.5f ? std::clamp(expected, 128, 254) : std::clamp(expected, 1, 127);
    mismatches += bytes[i] != expected;
    fractional += v > 0.0f && v < 1.0f;
  }
  EXPECT_EQ(mismatches, 0u);
  EXPECT_GT(fractional, 10u);
}

// vsm.glsl (a moments line: the harness renders and blurs the vsm moments for it) against the
// built-in filter=vsm: the same bits in every channel, the moments' evidence included, for two blur
// radii, a bleed cut and a point light (a cube map's faces), full and on demand; with fractional
// pixels present, and a blur that changes the result (the keys reach the moments pass).
TEST_F(RasterTechnique, VsmFileIsTheBuiltInVsmBitForBit) {
  REQUIRE_DEVICE();
  Scene point = quarterScene("sphere_on_plane");
  point.name = "sphere_on_plane, a point light";
  point.lights.front().type = LightType::Point;
  point.lights.front().position = glm::vec3(1.5f, 4.0f, 1.0f);
  std::vector<float> firstVis;
  for (const Scene& s : {quarterScene("sphere_on_plane"), quarterScene("stacked_occluders"), point})
    for (int blur : {0, 3})
      for (float cut : {0.0f, 0.3f}) {
        const bool pointLight = s.lights.front().type == LightType::Point;
        if (pointLight && (blur == 0 || cut > 0)) continue;
        Method builtIn;
        builtIn.filter = Filter::Vsm;
        builtIn.mapSize = 512;
        builtIn.filterBlur = blur;
        builtIn.vsmBleedReduction = cut;
        builtIn.biasSlope = 0;
        Method file = builtIn;
        file.filter = Filter::None;
        file.technique = kExamples + "vsm.glsl";
        validateMethod(file, "test");
        const std::string where = s.name + " blur " + std::to_string(blur) + " cut " + std::to_string(cut);
        const Frame a = R->render(s, builtIn);
        const std::vector<uint8_t> bytesA = R->lookupVisibility();
        const Frame b = R->render(s, file);
        const std::vector<uint8_t> bytesB = R->lookupVisibility();
        EXPECT_EQ(firstDifference(a, b), "") << where;
        EXPECT_EQ(bytesA, bytesB) << where;
        const std::string L = "light." + s.lights.front().name + ".";
        ASSERT_TRUE(b.has(L + "moment_bound")) << where;
        size_t fractional = 0;
        for (float v : a.get(L + "vis")) fractional += v > 0.0f && v < 1.0f;
        EXPECT_GT(fractional, 50u) << where;
        EXPECT_EQ(b.meta.at("method").at("technique"), file.technique) << where;
        EXPECT_EQ(b.meta.at("method").at("filter"), "none") << where;
        if (s.name == "sphere_on_plane" && cut == 0.0f) {
          if (blur == 0) firstVis = b.get(L + "vis");
          else EXPECT_NE(firstVis, b.get(L + "vis")) << "filter.blur does not reach the file's moments";
        }
      }
}

// A file that reads the moments without a moments line: an InputError at the read's file:line:column,
// before anything is compiled; a bad moments line names its token.
TEST(TechniqueFile, MomentsWithoutAskingNameTheLine) {
  const auto dir = shadowlab::testing::freshTempDir("raster_technique_moments");
  struct Case {
    const char* name;
    std::string text;
    std::string expect;
  };
  const std::vector<Case> cases = {
      {"field.glsl", "// no moments line\nfloat shadowVisibility(ShadowQuery q) {\n  return q.moments.x;\n}\n",
       ":3:12: error: reads moments without asking for moments; expected a header line // shadowlab: moments"},
      {"image.glsl",
       "float shadowVisibility(ShadowQuery q) {\n  float d = q.depth;\n  return textureLod(mapMoments, vec3(q.uv, "
       "q.layer), 0.0).x;\n}\n",
       ":3:21: error: reads mapMoments without asking"},
      {"kind.glsl", "// shadowlab: moments pcf\nfloat shadowVisibility(ShadowQuery q) {\n  return 1.0;\n}\n",
       ":1:23: error: moments \"pcf\"; expected one of vsm, evsm2, evsm4, msm"},
      {"twice.glsl",
       "// shadowlab: moments vsm\n// shadowlab: moments msm\nfloat shadowVisibility(ShadowQuery q) {\n  return "
       "1.0;\n}\n",
       ":2:15: error: a second moments line (the first on line 1)"},
  };
  for (const Case& c : cases) {
    const std::string path = writeFile(dir, c.name, c.text);
    try {
      loadTechniqueFile(path);
      ADD_FAILURE() << c.name << ": no error";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(path + c.expect), std::string::npos) << c.name << ": " << e.what();
    }
  }
  // Asked for: the kind is the file's, and the method's effective filter is it.
  const std::string ok = writeFile(dir, "ok.glsl",
                                   "  //  shadowlab:  moments   evsm4\nfloat shadowVisibility(ShadowQuery q) {\n  "
                                   "return q.moments.x;\n}\n");
  EXPECT_EQ(loadTechniqueFile(ok).moments, "evsm4");
  EXPECT_EQ(loadTechniqueFile(ok).momentsLine, 1);
  Method m;
  m.technique = ok;
  EXPECT_EQ(effectiveFilter(m), Filter::Evsm4);
  m.technique = kExamples + "pcf.glsl";
  EXPECT_EQ(effectiveFilter(m), Filter::None);
}

}  // namespace raster_technique_test
