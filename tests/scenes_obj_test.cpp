// OBJ files: polygon faces cut into the triangles their author meant (polygon.h), every malformed
// line an error at file.obj:LINE (scenes/src/obj_reader.cpp), on synthetic files and on Assimp's
// own test files (assimp-testmodels, tests/support/test_models.h); printable error messages.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <set>
#include <sstream>

#include <nlohmann/json.hpp>

#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/io.h"
#include "shadowlab/scenes/loader.h"
#include "shadowlab/scenes/polygon.h"
#include "support/input_error.h"
#include "support/test_models.h"

namespace scenes_obj_test {

namespace fs = std::filesystem;
using namespace shadowlab;
using shadowlab::testing::inputErrorOf;

namespace {

fs::path tempDir(const std::string& name) {
  fs::path dir = fs::temp_directory_path() / ("shadowlab_scenes_obj_test_" + std::to_string(::getpid())) / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

// A scene holding one OBJ object at `objPath` (absolute, or relative to the scene).
std::string sceneWithObj(const std::string& objPath) {
  return R"({"camera": {"position": [0, 2, 5], "look_at": [0, 0, 0], "vfov_deg": 45, "width": 8, "height": 6},
  "objects": [{"type": "obj", "name": "mesh", "path": )" +
         nlohmann::json(objPath).dump() + R"(}],
  "lights": [{"type": "directional", "elevation_deg": 45}]})";
}

Scene loadObjScene(const std::string& objPath, const fs::path& dir) {
  writeFileAtomic((dir / "s.json").string(), sceneWithObj(objPath));
  return loadScene((dir / "s.json").string());
}

// Writes `text` as x.obj in a fresh folder and returns the loader's error ("" when it loads).
std::string errorOfObjText(const std::string& text, const std::string& name) {
  fs::path dir = tempDir(name);
  writeFileAtomic((dir / "x.obj").string(), text);
  try {
    loadObjScene("x.obj", dir);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

double triangleArea(glm::dvec3 a, glm::dvec3 b, glm::dvec3 c) { return 0.5 * glm::length(glm::cross(b - a, c - a)); }

// Area of a flat polygon (Newell's vector, halved): the area a correct triangulation covers.
double polygonArea(const std::vector<glm::dvec3>& p) {
  glm::dvec3 n(0);
  for (size_t i = 0; i < p.size(); ++i) n += glm::cross(p[i], p[(i + 1) % p.size()]);
  return 0.5 * glm::length(n);
}

// Even-odd point in polygon, in the xz plane.
bool insideXz(const std::vector<glm::dvec3>& p, double x, double z) {
  bool in = false;
  for (size_t i = 0, j = p.size() - 1; i < p.size(); j = i++)
    if ((p[i].z > z) != (p[j].z > z) && x < (p[j].x - p[i].x) * (z - p[i].z) / (p[j].z - p[i].z) + p[i].x) in = !in;
  return in;
}

bool coveredXz(const Object& o, double x, double z) {
  for (const auto& t : o.triangles) {
    glm::dvec2 a(o.positions[t.x].x, o.positions[t.x].z), b(o.positions[t.y].x, o.positions[t.y].z),
        c(o.positions[t.z].x, o.positions[t.z].z), p(x, z);
    auto side = [](glm::dvec2 u, glm::dvec2 v, glm::dvec2 w) {
      return (v.x - u.x) * (w.y - u.y) - (v.y - u.y) * (w.x - u.x);
    };
    double d1 = side(a, b, p), d2 = side(b, c, p), d3 = side(c, a, p);
    if ((d1 >= 0 && d2 >= 0 && d3 >= 0) || (d1 <= 0 && d2 <= 0 && d3 <= 0)) return true;
  }
  return false;
}

// A C in the xz plane at height y: a ring sector of radii 0.5 and 1 around the origin whose gap
// (the notch) opens towards +x, between -45 and +45 degrees. `arc` corners per arc.
std::vector<glm::dvec3> cShape(double y, int arc) {
  std::vector<glm::dvec3> p;
  const double pi = 3.14159265358979323846, from = pi / 4, to = 2 * pi - pi / 4;
  for (int i = 0; i < arc; ++i) {
    double a = from + (to - from) * i / (arc - 1);
    p.push_back({std::cos(a), y, -std::sin(a)});
  }
  for (int i = arc - 1; i >= 0; --i) {
    double a = from + (to - from) * i / (arc - 1);
    p.push_back({0.5 * std::cos(a), y, -0.5 * std::sin(a)});
  }
  return p;
}

std::string objOfPolygon(const std::vector<glm::dvec3>& p) {
  std::ostringstream s;
  s.precision(9);
  for (const auto& v : p) s << "v " << v.x << " " << v.y << " " << v.z << "\n";
  s << "f";
  for (size_t i = 0; i < p.size(); ++i) s << " " << i + 1;
  s << "\n";
  return s.str();
}

// Checks that `t` cuts the polygon `p` into n - 2 triangles of the face's winding that add up to
// its area (so they do not overlap and leave nothing out).
void expectExactCover(const std::vector<glm::dvec3>& exact, const PolygonTriangles& t, const std::string& what) {
  SCOPED_TRACE(what);
  std::vector<glm::dvec3> p;  // the corners as the float positions triangulatePolygon saw
  for (const auto& v : exact) p.push_back(glm::dvec3(glm::vec3(v)));
  ASSERT_EQ(t.error, "");
  EXPECT_EQ(t.triangles.size(), p.size() - 2);
  glm::dvec3 normal(0);
  for (size_t i = 0; i < p.size(); ++i) normal += glm::cross(p[i], p[(i + 1) % p.size()]);
  double sum = 0;
  for (const auto& tri : t.triangles) {
    const glm::dvec3 a = p[tri[0]], b = p[tri[1]], c = p[tri[2]];
    EXPECT_GE(glm::dot(glm::cross(b - a, c - a), normal), 0.0) << "a triangle wound against the face";
    sum += triangleArea(a, b, c);
  }
  EXPECT_NEAR(sum, polygonArea(p), 1e-6 * polygonArea(p));
}

std::vector<glm::vec3> toFloat(const std::vector<glm::dvec3>& p) {
  std::vector<glm::vec3> out;
  for (const auto& v : p) out.push_back(glm::vec3(v));
  return out;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Polygon faces.

TEST(ObjPolygons, AssimpConcavePolygonIsCutIntoExactlyItsArea) {
  SHADOWLAB_REQUIRE_TEST_MODEL(path, "OBJ/concave_polygon.obj");
  // The file's one face, read here independently: 66 corners (two of them, 31 and 32, twice: the
  // bridge between the ring's outer and inner loops).
  std::vector<glm::dvec3> v, face;
  std::ifstream in(path);
  for (std::string line; std::getline(in, line);) {
    std::istringstream s(line);
    std::string key;
    s >> key;
    if (key == "v") {
      glm::dvec3 p;
      s >> p.x >> p.y >> p.z;
      v.push_back(glm::dvec3(glm::vec3(p)));  // as floats, as the loader holds them
    } else if (key == "f") {
      for (std::string corner; s >> corner;) face.push_back(v.at(size_t(std::stoi(corner)) - 1));
    }
  }
  ASSERT_EQ(face.size(), 66u);
  const double area = polygonArea(face);

  fs::path dir = tempDir("concave");
  Scene s = loadObjScene(path, dir);
  const Object& o = s.objects.at(0);
  // A simple polygon of n corners: n - 2 triangles (the old fan gave 44 over most of a disk).
  EXPECT_EQ(o.triangles.size(), 64u);
  double sum = 0;
  glm::dvec3 normal(0);
  for (size_t i = 0; i < face.size(); ++i) normal += glm::cross(face[i], face[(i + 1) % face.size()]);
  for (const auto& t : o.triangles) {
    glm::dvec3 a(o.positions[t.x]), b(o.positions[t.y]), c(o.positions[t.z]);
    EXPECT_GE(glm::dot(glm::cross(b - a, c - a), normal), 0.0) << "every triangle wound like the face";
    sum += triangleArea(a, b, c);
  }
  EXPECT_NEAR(sum, area, 1e-6 * area) << "the triangles cover the ring's area, no more";
  // The ring's hole is empty: its centre (the mean of the inner loop's corners, which lie on a
  // circle) is in no triangle. Project on the face's plane (x = -1.146): use (y, z).
  glm::dvec2 centre(0);
  double lo = 1e9, hi = -1e9;
  for (const auto& p : face) lo = std::min(lo, p.y), hi = std::max(hi, p.y);
  centre = glm::dvec2(0.5 * (lo + hi), 2.348);
  for (const auto& t : o.triangles) {
    glm::dvec2 a(o.positions[t.x].y, o.positions[t.x].z), b(o.positions[t.y].y, o.positions[t.y].z),
        c(o.positions[t.z].y, o.positions[t.z].z);
    auto side = [](glm::dvec2 u, glm::dvec2 w, glm::dvec2 q) {
      return (w.x - u.x) * (q.y - u.y) - (w.y - u.y) * (q.x - u.x);
    };
    double d1 = side(a, b, centre), d2 = side(b, c, centre), d3 = side(c, a, centre);
    EXPECT_FALSE((d1 > 0 && d2 > 0 && d3 > 0) || (d1 < 0 && d2 < 0 && d3 < 0)) << "a triangle covers the hole";
  }
}

TEST(ObjPolygons, CShapedFaceCoversTheCAndNotItsNotch) {
  const auto c = cShape(1.0, 12);
  fs::path dir = tempDir("cshape");
  writeFileAtomic((dir / "c.obj").string(), objOfPolygon(c));
  Scene s = loadObjScene("c.obj", dir);
  const Object& o = s.objects.at(0);
  EXPECT_EQ(o.triangles.size(), c.size() - 2);
  // Under the notch (+x, between the arms), in the hole and outside: nothing. On the arms: covered.
  EXPECT_FALSE(coveredXz(o, 0.75, 0.0)) << "the notch";
  EXPECT_FALSE(coveredXz(o, 0.0, 0.0)) << "the hole";
  EXPECT_FALSE(coveredXz(o, 0.4, 0.1));
  EXPECT_TRUE(coveredXz(o, -0.75, 0.0)) << "the back of the C";
  EXPECT_TRUE(coveredXz(o, 0.0, -0.75)) << "an arm";
  EXPECT_TRUE(coveredXz(o, 0.0, 0.75)) << "the other arm";
  // Everywhere on a grid: covered exactly where the C is (away from its edges).
  int checked = 0;
  for (double x = -1.2; x <= 1.2; x += 0.05)
    for (double z = -1.2; z <= 1.2; z += 0.05) {
      bool near = false;
      for (double dx : {-0.01, 0.0, 0.01})
        for (double dz : {-0.01, 0.0, 0.01}) near |= insideXz(c, x + dx, z + dz) != insideXz(c, x, z);
      if (near) continue;
      ++checked;
      EXPECT_EQ(coveredXz(o, x, z), insideXz(c, x, z)) << "at (" << x << ", " << z << ")";
    }
  EXPECT_GT(checked, 1500);
}

TEST(ObjPolygons, ConvexFacesKeepTheirSplit) {
  // A convex quad is cut along its shorter diagonal (tinyobjloader's rule), either way round.
  auto quad = [](float w) { return std::vector<glm::vec3>{{0, 0, 0}, {w, 0, 0}, {w + 0.5f, 0, 1}, {0.5f, 0, 1}}; };
  using Tris = std::vector<std::array<uint32_t, 3>>;
  // quad(2): 0-2 squared 7.25, 1-3 squared 3.25: cut along 1-3; quad(-0.4): 0-2 squared 1.01,
  // 1-3 squared 1.81: cut along 0-2.
  EXPECT_EQ(triangulatePolygon(quad(2.0f)).triangles, (Tris{{0, 1, 3}, {1, 2, 3}}));
  EXPECT_EQ(triangulatePolygon(quad(-0.4f)).triangles, (Tris{{0, 1, 2}, {0, 2, 3}}));
  const auto q = quad(2.0f);
  const float d02 = glm::dot(q[2] - q[0], q[2] - q[0]), d13 = glm::dot(q[3] - q[1], q[3] - q[1]);
  EXPECT_EQ(triangulatePolygon(q).triangles, d02 < d13 ? (Tris{{0, 1, 2}, {0, 2, 3}}) : (Tris{{0, 1, 3}, {1, 2, 3}}));
  const std::vector<glm::vec3> square = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  EXPECT_EQ(triangulatePolygon(square).triangles, (Tris{{0, 1, 3}, {1, 2, 3}}));  // equal diagonals
  // A convex polygon of 5 or more corners: the fan from the first corner.
  std::vector<glm::vec3> hexagon;
  for (int i = 0; i < 6; ++i) hexagon.push_back({std::cos(i * 1.0471976f), 0, std::sin(i * 1.0471976f)});
  EXPECT_EQ(triangulatePolygon(hexagon).triangles, (Tris{{0, 1, 2}, {0, 2, 3}, {0, 3, 4}, {0, 4, 5}}));
  // Collinear corners on a convex outline are still convex: the fan (with its flat triangle).
  const std::vector<glm::vec3> withMidpoint = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {2, 0, 2}, {0, 0, 2}};
  EXPECT_EQ(triangulatePolygon(withMidpoint).triangles.size(), 3u);
  // A triangle is itself.
  EXPECT_EQ(triangulatePolygon({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}).triangles, (Tris{{0, 1, 2}}));
}

TEST(ObjPolygons, ConcaveFacesAreCutExactly) {
  // An L (6 corners), an arrowhead quad (the shorter diagonal lies outside it), the C, a keyhole
  // square with a square hole (10 corners: the bridge's two ends appear twice), both windings.
  const std::vector<glm::dvec3> l = {{0, 0, 0}, {2, 0, 0}, {2, 1, 0}, {1, 1, 0}, {1, 2, 0}, {0, 2, 0}};
  const std::vector<glm::dvec3> arrow = {{0, 0, 0}, {3, 0.5, 0}, {0, 1, 0}, {0.5, 0.5, 0}};
  const std::vector<glm::dvec3> keyhole = {{0, 0, 0}, {4, 0, 0}, {4, 4, 0}, {0, 4, 0}, {0, 2, 0}, {1, 2, 0},
                                           {1, 3, 0}, {3, 3, 0}, {3, 1, 0}, {1, 1, 0}, {1, 2, 0}, {0, 2, 0}};
  for (const auto& [name, poly] : std::vector<std::pair<std::string, std::vector<glm::dvec3>>>{
           {"L", l}, {"arrow", arrow}, {"C", cShape(0.0, 9)}, {"keyhole", keyhole}}) {
    expectExactCover(poly, triangulatePolygon(toFloat(poly)), name);
    std::vector<glm::dvec3> reversed(poly.rbegin(), poly.rend());
    expectExactCover(reversed, triangulatePolygon(toFloat(reversed)), name + " reversed");
    // Tilted out of every axis plane: the same cut.
    glm::dmat3 tilt = glm::dmat3(glm::dvec3(0.8, 0.36, -0.48), glm::dvec3(-0.6, 0.48, -0.64), glm::dvec3(0, 0.8, 0.6));
    std::vector<glm::dvec3> tilted;
    for (const auto& p : poly) tilted.push_back(glm::dvec3(glm::vec3(tilt * p)));
    expectExactCover(tilted, triangulatePolygon(toFloat(tilted)), name + " tilted");
  }
  // The arrowhead's shorter diagonal (corners 0 and 2, length 1) runs outside it, across its
  // notch: the cut uses corners 1 and 3 (tinyobjloader's quad rule drew a triangle outside it).
  const auto cut = triangulatePolygon(toFloat(arrow)).triangles;
  ASSERT_EQ(cut.size(), 2u);
  for (const auto& t : cut)
    EXPECT_TRUE(std::count(t.begin(), t.end(), 1u) == 1 && std::count(t.begin(), t.end(), 3u) == 1);
}

TEST(ObjPolygons, RandomStarPolygonsAreCutExactly) {
  // Star-shaped polygons (random radius per angle, angles increasing) are simple by construction.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> radius(0.2, 1.0), jitter(0.0, 0.9);
  for (int trial = 0; trial < 300; ++trial) {
    const int n = 4 + trial % 60;
    std::vector<glm::dvec3> p;
    for (int i = 0; i < n; ++i) {
      const double a = 6.283185307179586 * (i + jitter(rng)) / n, r = radius(rng);
      p.push_back(glm::dvec3(glm::vec3(float(r * std::cos(a)), 0.25f, float(r * std::sin(a)))));
    }
    expectExactCover(p, triangulatePolygon(toFloat(p)), "star " + std::to_string(trial));
  }
}

TEST(ObjPolygons, FacesThatCannotBeCutAreRefused) {
  // A bow tie (crossing edges), a pentagram (all turns alike, twice around), a bent L.
  const std::vector<glm::vec3> bowtie = {{0, 0, 0}, {1, 0, 0}, {0, 0, 1}, {1, 0, 1}};
  EXPECT_NE(triangulatePolygon(bowtie).error.find("edges cross"), std::string::npos)
      << triangulatePolygon(bowtie).error;
  std::vector<glm::vec3> star;
  for (int i = 0; i < 5; ++i) star.push_back({std::cos(i * 2.513274f), std::sin(i * 2.513274f), 0});
  EXPECT_NE(triangulatePolygon(star).error.find("edges cross"), std::string::npos) << triangulatePolygon(star).error;
  const std::vector<glm::vec3> bent = {{0, 0, 0}, {2, 0, 0}, {2, 1, 0}, {1, 1, 0.5f}, {1, 2, 0}, {0, 2, 0}};
  EXPECT_NE(triangulatePolygon(bent).error.find("not flat (corner 4 lies"), std::string::npos)
      << triangulatePolygon(bent).error;
  // Slightly bent (within 1% of its size) is cut as if flat.
  std::vector<glm::vec3> nearlyFlat = bent;
  nearlyFlat[3].z = 0.01f;
  EXPECT_EQ(triangulatePolygon(nearlyFlat).error, "");
  EXPECT_EQ(triangulatePolygon(nearlyFlat).triangles.size(), 4u);
}

TEST(ObjPolygons, FaceErrorsNameTheFaceLine) {
  EXPECT_NE(errorOfObjText("# bow tie\nv 0 0 0\nv 1 0 0\nv 0 0 1\nv 1 0 1\nf 1 2 3\nf 1 2 3 4\n", "bowtie")
                .find("x.obj:7: error: a face whose edges cross (corners 2-3 and 4-1); expected a simple polygon"),
            std::string::npos);
}

// ---------------------------------------------------------------------------------------------
// Malformed lines.

TEST(ObjLines, EveryMalformedLineIsAnErrorAtItsLine) {
  const std::string tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n";
  struct Case {
    std::string name, text, expected;
  };
  const std::vector<Case> cases = {
      {"two_corners", tri + "f 1 2 3\nf 2 4\n", "x.obj:6: error: \"f\" line has 2 corners; expected at least 3"},
      {"bare_f", tri + "f\nf 1 2 3\n", "x.obj:5: error: \"f\" line has no corners; expected at least 3"},
      {"two_numbers", "v 0 0 0\nv 1 0\nv 0 1 0\nf 1 2 3\n",
       "x.obj:2: error: \"v\" line has 2 numbers; expected 3 numbers (x y z), 4 (x y z w) or 6 (x y z r g b)"},
      {"five_numbers", "v 0 0 0 1 1\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "x.obj:1: error: \"v\" line has 5 numbers"},
      {"vn_two", tri + "vn 0 1\nf 1//1 2//1 3//1\n", "x.obj:5: error: \"vn\" line has 2 numbers; expected 3 numbers"},
      {"index_zero", tri + "f 0 1 2\n",
       "x.obj:5: error: \"f\" line has vertex index 0; expected 1..4 (OBJ indices start at 1)"},
      {"index_high", tri + "f 1 2 5\n",
       "x.obj:5: error: \"f\" line has vertex index 5; expected 1..4 (the file has 4 \"v\" lines)"},
      {"negative_back", "v 0 0 0\nf -1 -2 -3\nv 1 0 0\nv 0 1 0\n",
       "x.obj:2: error: \"f\" line has vertex index -2; expected -1..-1 (1 \"v\" lines come before it)"},
      {"uv_missing", tri + "f 1/1 2/1 3/1\n",
       "x.obj:5: error: \"f\" line has texture coordinate index 1; expected none: the file has no \"vt\" lines"},
      {"normal_high", tri + "vn 0 0 1\nf 1//1 2//2 3//1\n",
       "x.obj:6: error: \"f\" line has normal index 2; expected 1..1"},
      {"corner_text", tri + "f 1 2 a\n", "x.obj:5: error: \"f\" line has corner \"a\"; expected at least 3 corners"},
      {"corner_float", tri + "f 1 2 3.5\n", "x.obj:5: error: \"f\" line has corner \"3.5\""},
      {"corner_slashes", tri + "f 1 2 3/1/1/1\n", "x.obj:5: error: \"f\" line has corner \"3/1/1/1\""},
      {"line_one", tri + "f 1 2 3\nl 1\n", "x.obj:6: error: \"l\" line has 1 corner; expected at least 2 corners"},
      {"not_a_number", "v 0 0 0\nv 1 0 0\nv 0 1 0x10\nf 1 2 3\n",
       "x.obj:3: error: \"v\" line has \"0x10\"; expected finite numbers"},
      {"float_overflow", tri + "vt 0 1e39\nf 1/1 2/1 3/1\n",
       "x.obj:5: error: \"vt\" line has \"1e39\"; expected finite numbers (magnitude below 3.4e38, the float range)"},
      {"unknown", tri + "vx 1 2 3\nf 1 2 3\n",
       "x.obj:5: error: unknown statement \"vx\"; expected one of v, vt, vn, vp, f"},
      {"freeform", tri + "cstype bezier\nf 1 2 3\n",
       "x.obj:5: error: free-form geometry (\"cstype\") is not supported; expected polygonal faces"},
      {"continuation", tri + "f 1 2 \\\n3\n", "x.obj:5: error: a line continued on the next"},
      {"mtllib_bare", tri + "mtllib\nf 1 2 3\n",
       "x.obj:5: error: \"mtllib\" line has no name; expected MTL file names"},
      {"smooth_word", tri + "s maybe\nf 1 2 3\n",
       "x.obj:5: error: \"s\" line has \"maybe\"; expected off or a smoothing"},
      {"nul", tri + "f 1 2 3\n" + std::string("#\0\n", 3), "x.obj:6: error: a NUL byte"},
      {"empty", "", "x.obj: error: the file has no faces; expected at least one \"f\" line"},
      {"vertices_only", tri, "x.obj: error: the file has no faces"},
      {"points_only", tri + "p 1 2 3\n",
       "x.obj: error: the file has only points and lines (1 \"p\" and 0 \"l\" lines)"},
      {"utf16_no_bom", std::string({'v', '\0', ' ', '\0', '0', '\0', '\n', '\0'}),
       "every other byte of the file is zero"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    const std::string e = errorOfObjText(c.text, c.name);
    EXPECT_NE(e.find(c.expected), std::string::npos) << "got:      " << e << "\nexpected: " << c.expected;
    EXPECT_EQ(e.find('\n'), std::string::npos) << "one line";
  }
}

TEST(ObjLines, WellFormedVariantsLoad) {
  // Trailing comments, CR LF and lone CR line ends, tabs, a UTF-8 byte order mark, negative and
  // forward indices, v with w or colours, vt with 1 to 3 numbers, s off, g without a name, o, a
  // bare usemtl (Meshlab's "no material") and the display statements the renderers have no use for.
  const std::string text =
      "\xEF\xBB\xBF# a comment\r\no thing\r\ng\r\ns off\r\nv 0 0 0 # origin\r\nv 1 0 0 1\rv 0 1 0 0.5 0.5 0.5\n"
      "vt 0\nvt 1 0\nvt 0 1 0\nvn 0 0 1\nlod 1\nusemtl\nf\t1/1/1 2/2/1 3/3/1 # first\nf -3//-1 -2//1 4//1\nv 1 1 0\ns "
      "1\n";
  EXPECT_EQ(errorOfObjText(text, "variants"), "");
  fs::path dir = fs::temp_directory_path() / ("shadowlab_scenes_obj_test_" + std::to_string(::getpid())) / "variants";
  Scene s = loadScene((dir / "s.json").string());
  EXPECT_EQ(s.objects.at(0).triangles.size(), 2u);
}

TEST(ObjLines, AssimpMalformedFilesNameTheBadLine) {
  SHADOWLAB_REQUIRE_TEST_MODEL(malformed, "invalid/malformed.obj");
  fs::path dir = tempDir("assimp_malformed");
  // Line 23 is "f 4 12 2 1" (8 vertices); tinyobjloader itself stopped at line 28 ("f 0 7 8 5").
  std::string e = inputErrorOf([&] { loadObjScene(malformed, dir); });
  EXPECT_EQ(e, malformed + ":23: error: \"f\" line has vertex index 12; expected 1..8 (the file has 8 \"v\" lines)");

  SHADOWLAB_REQUIRE_TEST_MODEL(malformed2, "invalid/malformed2.obj");
  e = inputErrorOf([&] { loadObjScene(malformed2, dir); });
  EXPECT_EQ(e, malformed2 +
                   ":23: error: \"f\" line has no corners; expected at least 3 corners, each v, v/vt, v//vn or "
                   "v/vt/vn");

  SHADOWLAB_REQUIRE_TEST_MODEL(empty, "invalid/empty.obj");
  e = inputErrorOf([&] { loadObjScene(empty, dir); });
  EXPECT_EQ(e, empty + ": error: the file has no faces; expected at least one \"f\" line");
}

TEST(ObjLines, AssimpFilesOfOtherKindsSayWhatTheyAre) {
  SHADOWLAB_REQUIRE_TEST_MODEL(utf16, "OBJ/box_UTF16BE.obj");
  fs::path dir = tempDir("assimp_kinds");
  std::string e = inputErrorOf([&] { loadObjScene(utf16, dir); });
  EXPECT_EQ(e, utf16 +
                   ": error: the file starts with the UTF-16 byte order mark FE FF; UTF-16 is not supported, "
                   "expected ASCII or UTF-8 text");
  SHADOWLAB_REQUIRE_TEST_MODEL(points, "OBJ/testpoints.obj");
  e = inputErrorOf([&] { loadObjScene(points, dir); });
  EXPECT_EQ(e, points +
                   ": error: the file has only points and lines (6 \"p\" and 0 \"l\" lines), which cast no "
                   "shadow; expected faces (\"f\" lines)");
  SHADOWLAB_REQUIRE_TEST_MODEL(lines, "OBJ/testline.obj");
  e = inputErrorOf([&] { loadObjScene(lines, dir); });
  EXPECT_NE(e.find(lines + ": error: the file has only points and lines (0 \"p\" and "), std::string::npos) << e;
  // A folder where the OBJ should be.
  const std::string folder = shadowlab::test::testModelsDir().string() + "/OBJ";
  e = inputErrorOf([&] { loadObjScene(folder, dir); });
  EXPECT_NE(e.find("/objects/0/path: error: OBJ path " + folder + " is a folder; expected a Wavefront .obj file"),
            std::string::npos)
      << e;
}

// Every OBJ file of Assimp's test set: those a real exporter wrote load, with the triangles their
// faces give (a quad 2, a 66-corner ring 64); the others are refused with the reason.
TEST(ObjLines, EveryAssimpObjFileLoadsOrSaysWhy) {
  SHADOWLAB_REQUIRE_TEST_MODEL(box, "OBJ/box.obj");
  fs::path dir = tempDir("assimp_all");
  struct Expect {
    std::string file;
    size_t triangles;   // when it loads
    std::string error;  // else: the message after the file's path
  };
  const std::vector<Expect> expected = {
      {"WusonOBJ.obj", 3732, ""},
      {"box.obj", 12, ""},
      {"box_UTF16BE.obj", 0, ": error: the file starts with the UTF-16 byte order mark FE FF"},
      // Assimp's buffer-overflow test: one square written out 234 times as a single face.
      {"box_longline.obj", 0, ":24: error: a face that runs round 234 times; expected a simple polygon (once round)"},
      {"box_mat_with_spaces.obj", 12, ""},
      {"box_without_lineending.obj", 12, ""},
      {"concave_polygon.obj", 64, ""},
      // Its mtllib names cube_mtllib_after_g.mat; the file beside it is .mtl.
      {"cube_mtllib_after_g.obj", 0, ":2: error: MTL file "},
      {"cube_usemtl.obj", 12, ""},
      {"cube_with_vertexcolors.obj", 12, ""},
      {"cube_with_vertexcolors_uni.obj", 12, ""},
      {"empty_mat.obj", 256, ""},
      {"multiple_spaces.obj", 1, ""},
      // Assimp's number-parser test writes "3.1+e2", which is no number.
      {"number_formats.obj", 0, ":11: error: \"v\" line has \"3.1+e2\"; expected finite numbers"},
      {"point_cloud.obj", 0, ": error: the file has no faces; expected at least one \"f\" line"},
      {"regr01.obj", 2710, ""},
      {"regr_3429812.obj", 4, ""},
      {"space_in_material_name.obj", 64, ""},
      {"spider.obj", 1368, ""},
      {"testline.obj", 0, ": error: the file has only points and lines (0 \"p\" and "},
      {"testmixed.obj", 12, ""},
      {"testpoints.obj", 0, ": error: the file has only points and lines (6 \"p\" and 0 \"l\" lines)"},
  };
  std::set<std::string> listed;
  for (const auto& e : expected) listed.insert(e.file);
  for (const auto& entry : fs::directory_iterator(fs::path(box).parent_path()))
    if (entry.path().extension() == ".obj") {
      EXPECT_TRUE(listed.count(entry.path().filename().string())) << entry.path();
    }
  for (const auto& e : expected) {
    SCOPED_TRACE(e.file);
    const std::string path = SHADOWLAB_TEST_MODEL("OBJ/" + e.file);
    try {
      Scene s = loadObjScene(path, dir);
      EXPECT_EQ(e.error, "") << "loaded";
      EXPECT_EQ(s.triangleCount(), e.triangles);
    } catch (const InputError& err) {
      EXPECT_EQ(std::string(err.what()).rfind(path + e.error, 0), 0u) << err.what();
      EXPECT_NE(e.error, "") << err.what();
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Printable messages.

TEST(ErrorMessages, BytesThatAreNotUtf8AndControlsAreEscaped) {
  EXPECT_EQ(printableText("caf\xE9"), "caf\\xE9");
  EXPECT_EQ(printableText("caf\xC3\xA9 \xE2\x82\xAC \xF0\x9F\x98\x80"), "caf\xC3\xA9 \xE2\x82\xAC \xF0\x9F\x98\x80");
  EXPECT_EQ(printableText("a\x1B[31mb\rc\td\x7F"), "a\\x1B[31mb\\x0Dc\\x09d\\x7F");
  EXPECT_EQ(printableText("one\ntwo"), "one\ntwo");  // several errors, one per line
  EXPECT_EQ(printableText(std::string("nul\0x", 5)), "nul\\x00x");
  EXPECT_EQ(printableText("\xC2\x9B"), "\\xC2\\x9B");                               // C1 control (CSI)
  EXPECT_EQ(printableText("\xC0\xAF \xED\xA0\x80"), "\\xC0\\xAF \\xED\\xA0\\x80");  // overlong, surrogate
  EXPECT_EQ(printableText("\xE2\x82"), "\\xE2\\x82");                               // cut short
  EXPECT_EQ(printableText(printableText("caf\xE9\x1B")), printableText("caf\xE9\x1B"));
  EXPECT_EQ(std::string(InputError("x.obj:1: error: \"caf\xE9\"").what()), "x.obj:1: error: \"caf\\xE9\"");
  EXPECT_EQ(std::string(DriverError("raw \x1B").what()), "raw \\x1B");
}

TEST(ErrorMessages, Latin1ByteInAnObjTokenIsEscaped) {
  const std::string e = errorOfObjText("v 0 0 0\nv 1 0 0\nv 0 1 caf\xE9\nf 1 2 3\n", "latin1");
  EXPECT_NE(e.find("x.obj:3: error: \"v\" line has \"caf\\xE9\"; expected finite numbers"), std::string::npos) << e;
  EXPECT_EQ(e.find('\xE9'), std::string::npos) << "no raw byte";
  const std::string u = errorOfObjText("v 0 0 0\nv 1 0 0\n\xE9t\xE9 1 2\nf 1 2 3\n", "latin1_keyword");
  EXPECT_NE(u.find("x.obj:3: error: unknown statement \"\\xE9t\\xE9\""), std::string::npos) << u;
}

}  // namespace scenes_obj_test
