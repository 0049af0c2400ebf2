// Scene files -> resolved Scene. Everything is validated before anything is returned, and every
// error names the file and the JSON pointer of the offending value (line:col for syntax errors).
#include "shadowlab/scenes/loader.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <sstream>

#include <glm/gtc/matrix_transform.hpp>
#include <tiny_obj_loader.h>

#include "gltf_loader.h"
#include "image_io.h"
#include "json_util.h"
#include "obj_reader.h"
#include "shadowlab/scenes/json_reader.h"
#include "shadowlab/scenes/camera_path.h"
#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/io.h"
#include "shadowlab/scenes/number_text.h"
#include "shadowlab/scenes/polygon.h"

#ifndef SHADOWLAB_SOURCE_DIR
#error "SHADOWLAB_SOURCE_DIR must be defined by the build"
#endif
#ifndef SHADOWLAB_SHARED_DIR
#define SHADOWLAB_SHARED_DIR ""
#endif

namespace shadowlab {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr int kMaxResolution = 16384;
constexpr const char* kResolutionWhy = "the largest image every Vulkan device must support";
// Object ids travel through float channels: exact only below 2^24.
constexpr long long kMaxObjectId = (1ll << 24) - 1;
// Triangle (primitive) ids too, and the rasterizer's global triangle id + 1 read back through a
// float: a scene holds at most 2^24 - 1 triangles in all (also about 3 GB of BVH and vertex
// buffers, within this 24 GB machine).
constexpr uint64_t kMaxSceneTriangles = (1ull << 24) - 1;

// A value in the document together with its JSON pointer, for error messages.
struct Node {
  const json* j = nullptr;
  std::string ptr;
  explicit operator bool() const { return j != nullptr; }
};

class Reader {
 public:
  explicit Reader(std::string file) : file_(std::move(file)) {}
  const std::string& file() const { return file_; }

  [[noreturn]] void fail(const std::string& ptr, const std::string& what) const {
    // A value an override put there is the override's fault: name where it came from first.
    for (const SceneOverride& o : blamed_)
      if (ptr == o.pointer || ptr.rfind(o.pointer + "/", 0) == 0)
        throw InputError(formatError(o.origin, "", what + " (" + file_ + ": " + ptr + ")"));
    throw InputError(formatError(file_, ptr, what));
  }
  // Overrides that carry an origin, blamed for errors at or below their pointer.
  void blame(const std::vector<SceneOverride>& overrides) {
    for (const SceneOverride& o : overrides)
      if (!o.origin.empty()) blamed_.push_back(o);
  }
  [[noreturn]] void expected(const Node& n, const std::string& what) const {
    fail(n.ptr, "got " + detail::describe(*n.j) + "; expected " + what);
  }

  // Checks that `n` is an object whose keys all appear in `allowed`.
  void keys(const Node& n, const std::vector<std::string>& allowed, const std::string& what = "an object") const {
    if (!n.j->is_object()) expected(n, what);
    for (const auto& item : n.j->items()) {
      if (std::find(allowed.begin(), allowed.end(), item.key()) != allowed.end()) continue;
      std::string list;
      for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
      fail(
          detail::childPointer(n.ptr, item.key()),
          "unknown key \"" + item.key() + "\"" + detail::didYouMean(item.key(), allowed) + "; expected one of " + list);
    }
  }

  Node child(const Node& n, const std::string& key) const {
    auto it = n.j->find(key);
    if (it == n.j->end()) return Node{nullptr, detail::childPointer(n.ptr, key)};
    return Node{&*it, detail::childPointer(n.ptr, key)};
  }
  Node require(const Node& n, const std::string& key, const std::string& what) const {
    Node c = child(n, key);
    if (!c) fail(n.ptr, "missing key \"" + key + "\"; expected " + what);
    return c;
  }
  Node at(const Node& n, size_t i) const { return Node{&(*n.j)[i], detail::childPointer(n.ptr, i)}; }

  double number(const Node& n) const {
    if (!n.j->is_number()) expected(n, "a number");
    double d = n.j->get<double>();
    // Values become floats: 1e39 is a finite double but an infinite float.
    if (!std::isfinite(d) || std::fabs(d) > double(std::numeric_limits<float>::max()))
      expected(n, "a finite number (magnitude below 3.4e38, the float range)");
    return d;
  }
  // lo < x < hi or lo <= x <= hi by the flags; `what` is the whole "expected" text.
  double range(const Node& n, double lo, bool loOpen, double hi, bool hiOpen, const std::string& what) const {
    if (!n.j->is_number()) expected(n, what);
    double d = n.j->get<double>();
    if (!std::isfinite(d) || d < lo || d > hi || (loOpen && d == lo) || (hiOpen && d == hi)) expected(n, what);
    return d;
  }
  double positive(const Node& n, const std::string& unit = "") const {
    return range(n, 0, true, 1e30, false, "a positive number" + unit);
  }
  long long integer(const Node& n, long long lo, long long hi, const char* why = nullptr) const {
    std::string what = "an integer " + std::to_string(lo) + ".." + std::to_string(hi) +
                       (why ? std::string(" (") + why + ")" : std::string());
    if (n.j->is_number_integer()) {
      long long v =
          n.j->is_number_unsigned() && n.j->get<unsigned long long>() > (1ull << 62) ? hi + 1 : n.j->get<long long>();
      if (v < lo || v > hi) expected(n, what);
      return v;
    }
    expected(n, what);
  }
  bool boolean(const Node& n) const {
    if (!n.j->is_boolean()) expected(n, "true or false");
    return n.j->get<bool>();
  }
  std::string string(const Node& n, const std::string& what = "a string") const {
    if (!n.j->is_string() || n.j->get<std::string>().empty()) expected(n, what);
    return n.j->get<std::string>();
  }
  std::vector<double> numbers(const Node& n, size_t count, const std::string& labels) const {
    std::string what = std::to_string(count) + " (" + labels + ")";
    if (!n.j->is_array()) expected(n, "an array of " + what + " numbers");
    if (n.j->size() != count)
      fail(n.ptr,
           "got " + std::to_string(n.j->size()) + (n.j->size() == 1 ? " number" : " numbers") + "; expected " + what);
    std::vector<double> out;
    for (size_t i = 0; i < count; ++i) out.push_back(number(at(n, i)));
    return out;
  }
  glm::vec3 vec3(const Node& n) const {
    auto v = numbers(n, 3, "x, y, z");
    return glm::vec3(float(v[0]), float(v[1]), float(v[2]));
  }
  glm::vec2 vec2(const Node& n, const std::string& labels) const {
    auto v = numbers(n, 2, labels);
    return glm::vec2(float(v[0]), float(v[1]));
  }
  // A vec2 of positive numbers (sizes), or one number for both when `allowScalar`.
  glm::vec2 positive2(const Node& n, const std::string& labels, bool allowScalar) const {
    if (allowScalar && n.j->is_number()) {
      float s = float(positive(n));
      return glm::vec2(s);
    }
    if (!n.j->is_array())
      expected(n, std::string(allowScalar ? "a positive number or " : "") + "an array of 2 positive numbers (" +
                      labels + ")");
    glm::vec2 v = vec2(n, labels);
    for (int i = 0; i < 2; ++i)
      if (!(v[i] > 0))
        fail(detail::childPointer(n.ptr, size_t(i)),
             "got " + detail::describe((*n.j)[i]) + "; expected a positive number");
    return v;
  }
  glm::vec3 positive3(const Node& n, const std::string& labels, bool allowScalar) const {
    if (allowScalar && n.j->is_number()) return glm::vec3(float(positive(n)));
    if (!n.j->is_array())
      expected(n, std::string(allowScalar ? "a positive number or " : "") + "an array of 3 positive numbers (" +
                      labels + ")");
    auto v = numbers(n, 3, labels);
    for (size_t i = 0; i < 3; ++i)
      if (!(v[i] > 0))
        fail(detail::childPointer(n.ptr, i), "got " + detail::describe((*n.j)[i]) + "; expected a positive number");
    return glm::vec3(float(v[0]), float(v[1]), float(v[2]));
  }

 private:
  std::string file_;
  std::vector<SceneOverride> blamed_;
};

std::string vecText(glm::vec3 v) {
  std::ostringstream s;
  s << "[" << v.x << ", " << v.y << ", " << v.z << "]";
  return s.str();
}

bool finite(glm::vec3 v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

// Names become channel names ("light.NAME.vis"): a dot or a space would make them ambiguous.
void checkName(const Reader& r, const Node& n, const std::string& name) {
  for (char c : name)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-'))
      r.expected(n, "a name of letters, digits, '_' and '-'");
}

// "${SHARED}/x" -> shared assets folder; relative -> beside the scene (or MTL) file.
std::string resolvePath(const std::string& p, const fs::path& baseDir) {
  const std::string token = "${SHARED}";
  if (p.rfind(token, 0) == 0) {
    std::string rest = p.substr(token.size());
    while (!rest.empty() && rest[0] == '/') rest.erase(0, 1);
    return (fs::path(sharedAssetsDir()) / rest).lexically_normal().string();
  }
  fs::path path(p);
  if (path.is_absolute()) return path.lexically_normal().string();
  return (baseDir / path).lexically_normal().string();
}

// Reads an image as floats; throws InputError at `ptr` in `file` naming the image path.
Image readImage(const Reader& r, const std::string& ptr, const std::string& path, const std::string& role) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) r.fail(ptr, role + " " + path + " not found; expected an image file");
  image_io::FloatImage read;
  const std::string err = image_io::readTexture(path, read, kMaxResolution);
  if (!err.empty()) r.fail(ptr, "cannot read " + role + " " + path + ": " + err + "; expected an image file");
  if (read.width <= 0 || read.height <= 0 || read.width > kMaxResolution || read.height > kMaxResolution)
    r.fail(ptr, role + " " + path + " is " + std::to_string(read.width) + "x" + std::to_string(read.height) +
                    "; expected 1..16384 texels per side");
  Image img;
  img.width = read.width;
  img.height = read.height;
  img.channels = int(read.channels.size());
  img.pixels = std::move(read.pixels);
  for (float v : img.pixels)
    if (!std::isfinite(v)) r.fail(ptr, role + " " + path + " holds a non-finite value; expected finite texels");
  return img;
}

// Alpha from an image: its alpha channel when it has one (RGBA, gray+alpha), the single channel
// of a grayscale image (MTL map_d convention), else the mean of R, G and B.
Image alphaOf(const Image& img) {
  Image a;
  a.width = img.width;
  a.height = img.height;
  a.channels = 1;
  a.pixels.resize(size_t(img.width) * img.height);
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      float v;
      if (img.channels == 1) v = img.at(x, y, 0);
      else if (img.channels == 2 || img.channels >= 4) v = img.at(x, y, img.channels == 2 ? 1 : 3);
      else v = (img.at(x, y, 0) + img.at(x, y, 1) + img.at(x, y, 2)) / 3.0f;
      a.pixels[size_t(y) * img.width + x] = v;
    }
  return a;
}

// RGB from an image: gray replicated, alpha dropped. Values stay as stored (no sRGB decode):
// the projected color is compared, never lit.
Image rgbOf(const Image& img) {
  Image c;
  c.width = img.width;
  c.height = img.height;
  c.channels = 3;
  c.pixels.resize(size_t(img.width) * img.height * 3);
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x)
      for (int k = 0; k < 3; ++k)
        c.pixels[(size_t(y) * img.width + x) * 3 + k] = img.at(x, y, img.channels >= 3 ? k : 0);
  return c;
}

// ---------------------------------------------------------------------------------------------
// Procedural primitives, in object space. Each is a closed or open triangle mesh with
// counter-clockwise (outward-facing) winding.

struct Mesh {
  std::vector<glm::vec3> positions;
  std::vector<glm::vec2> uvs;
  std::vector<glm::uvec3> triangles;
  std::vector<uint32_t> triangleMaterial;  // filled for OBJ meshes only
};

void addQuad(Mesh& m, glm::vec3 a, glm::vec3 b, glm::vec3 c, glm::vec3 d, bool withUv) {
  uint32_t base = uint32_t(m.positions.size());
  m.positions.insert(m.positions.end(), {a, b, c, d});
  if (withUv) m.uvs.insert(m.uvs.end(), {glm::vec2(0, 1), glm::vec2(1, 1), glm::vec2(1, 0), glm::vec2(0, 0)});
  m.triangles.push_back({base, base + 1, base + 2});
  m.triangles.push_back({base, base + 2, base + 3});
}

// Rectangle in xz at y = 0 facing +y; uv (0, 0) at the (-x, -z) corner, u along +x, v along +z
// (seen from above with -z at the top, a texture reads upright).
Mesh makePlane(glm::vec2 size, glm::vec2 uvScale) {
  Mesh m;
  float hx = size.x * 0.5f, hz = size.y * 0.5f;
  m.positions = {{-hx, 0, -hz}, {-hx, 0, hz}, {hx, 0, hz}, {hx, 0, -hz}};
  m.uvs = {{0, 0}, {0, uvScale.y}, {uvScale.x, uvScale.y}, {uvScale.x, 0}};
  m.triangles = {{0, 1, 2}, {0, 2, 3}};
  return m;
}

// Rectangle in xy at z = 0 facing +z; u = 0 at -x, v = 0 at +y (the image's top row on top).
Mesh makeQuad(glm::vec2 size, glm::vec2 uvScale) {
  Mesh m;
  float hx = size.x * 0.5f, hy = size.y * 0.5f;
  m.positions = {{-hx, -hy, 0}, {hx, -hy, 0}, {hx, hy, 0}, {-hx, hy, 0}};
  m.uvs = {{0, uvScale.y}, {uvScale.x, uvScale.y}, {uvScale.x, 0}, {0, 0}};
  m.triangles = {{0, 1, 2}, {0, 2, 3}};
  return m;
}

// Axis-aligned box centered at the origin; each face has its own 4 vertices and uv 0..1.
Mesh makeBox(glm::vec3 size) {
  Mesh m;
  glm::vec3 h = size * 0.5f;
  auto face = [&](glm::vec3 c, glm::vec3 u, glm::vec3 v) {
    addQuad(m, c - u - v, c + u - v, c + u + v, c - u + v, true);
  };
  face({h.x, 0, 0}, {0, 0, -h.z}, {0, h.y, 0});
  face({-h.x, 0, 0}, {0, 0, h.z}, {0, h.y, 0});
  face({0, h.y, 0}, {h.x, 0, 0}, {0, 0, -h.z});
  face({0, -h.y, 0}, {h.x, 0, 0}, {0, 0, h.z});
  face({0, 0, h.z}, {h.x, 0, 0}, {0, h.y, 0});
  face({0, 0, -h.z}, {-h.x, 0, 0}, {0, h.y, 0});
  return m;
}

// Flips any triangle whose normal points against `outward(centroid)`.
template <class Fn>
void orientOutward(Mesh& m, Fn outward) {
  for (auto& t : m.triangles) {
    glm::dvec3 a = m.positions[t.x], b = m.positions[t.y], c = m.positions[t.z];
    glm::dvec3 n = glm::cross(b - a, c - a);
    glm::dvec3 centroid = (a + b + c) / 3.0;
    if (glm::dot(n, outward(centroid)) < 0) std::swap(t.y, t.z);
  }
}

// UV sphere centered at the origin: `segments` around y, `rings` from pole to pole.
// Flat triangles lie inside the sphere between their vertices; to keep the mesh within the
// smallest shell around the true sphere, the vertices sit at radius k*r with
// k = 2 / (1 + minNorm), where minNorm is the smallest |p| / r over the widest (equator)
// triangles: the surface then deviates by at most (1 - minNorm) / (1 + minNorm) * r in either
// direction (7.5e-5 r for 256 x 128).
Mesh makeSphere(double radius, int segments, int rings) {
  auto unit = [&](int ring, int seg) {
    double theta = kPi * ring / rings;
    double phi = 2.0 * kPi * (seg % segments) / segments;
    return glm::dvec3(std::sin(theta) * std::cos(phi), std::cos(theta), std::sin(theta) * std::sin(phi));
  };
  // The widest cell touches the equator; sample both of its triangles densely.
  double minNorm = 1.0;
  int eq = rings / 2;
  for (int ring : {eq - 1, eq}) {
    if (ring < 0 || ring + 1 > rings) continue;
    glm::dvec3 p00 = unit(ring, 0), p01 = unit(ring, 1), p10 = unit(ring + 1, 0), p11 = unit(ring + 1, 1);
    for (const auto& tri : {std::array<glm::dvec3, 3>{p00, p10, p11}, std::array<glm::dvec3, 3>{p00, p11, p01}})
      for (int i = 0; i <= 64; ++i)
        for (int j = 0; i + j <= 64; ++j) {
          double a = i / 64.0, b = j / 64.0;
          minNorm = std::min(minNorm, glm::length(tri[0] + a * (tri[1] - tri[0]) + b * (tri[2] - tri[0])));
        }
  }
  double k = 2.0 / (1.0 + minNorm);
  Mesh m;
  m.positions.push_back(glm::vec3(0, float(radius * k), 0));
  for (int ring = 1; ring < rings; ++ring)
    for (int seg = 0; seg < segments; ++seg) m.positions.push_back(glm::vec3(unit(ring, seg) * (radius * k)));
  m.positions.push_back(glm::vec3(0, float(-radius * k), 0));
  uint32_t south = uint32_t(m.positions.size() - 1);
  auto idx = [&](int ring, int seg) { return uint32_t(1 + (ring - 1) * segments + (seg % segments)); };
  for (int seg = 0; seg < segments; ++seg) m.triangles.push_back({0, idx(1, seg + 1), idx(1, seg)});
  for (int ring = 1; ring + 1 < rings; ++ring)
    for (int seg = 0; seg < segments; ++seg) {
      m.triangles.push_back({idx(ring, seg), idx(ring, seg + 1), idx(ring + 1, seg + 1)});
      m.triangles.push_back({idx(ring, seg), idx(ring + 1, seg + 1), idx(ring + 1, seg)});
    }
  for (int seg = 0; seg < segments; ++seg) m.triangles.push_back({south, idx(rings - 1, seg), idx(rings - 1, seg + 1)});
  orientOutward(m, [](glm::dvec3 c) { return c; });
  return m;
}

// Closed cylinder around the y axis, centered at the origin (y from -height/2 to +height/2).
Mesh makeCylinder(double radius, double height, int segments) {
  Mesh m;
  float h = float(height * 0.5);
  for (int s = 0; s < segments; ++s) {
    double phi = 2.0 * kPi * s / segments;
    float x = float(radius * std::cos(phi)), z = float(radius * std::sin(phi));
    m.positions.push_back({x, -h, z});
    m.positions.push_back({x, h, z});
  }
  uint32_t bottomCenter = uint32_t(m.positions.size());
  m.positions.push_back({0, -h, 0});
  uint32_t topCenter = bottomCenter + 1;
  m.positions.push_back({0, h, 0});
  for (int s = 0; s < segments; ++s) {
    uint32_t b0 = 2 * s, t0 = 2 * s + 1, b1 = 2 * ((s + 1) % segments), t1 = b1 + 1;
    m.triangles.push_back({b0, t1, b1});
    m.triangles.push_back({b0, t0, t1});
    m.triangles.push_back({bottomCenter, b0, b1});
    m.triangles.push_back({topCenter, t1, t0});
  }
  // Side triangles point away from the axis, cap triangles away from the middle.
  const size_t n = m.triangles.size();
  for (size_t i = 0; i < n; ++i) {
    auto& t = m.triangles[i];
    glm::dvec3 a = m.positions[t.x], b = m.positions[t.y], c = m.positions[t.z];
    glm::dvec3 centroid = (a + b + c) / 3.0;
    bool cap = (i % 4) >= 2;
    glm::dvec3 out = cap ? glm::dvec3(0, centroid.y, 0) : glm::dvec3(centroid.x, 0, centroid.z);
    if (glm::dot(glm::cross(b - a, c - a), out) < 0) std::swap(t.y, t.z);
  }
  return m;
}

// tinyobjloader's MTL files, each named relative to the OBJ file's folder (its own reader splits
// the folder at ':' as a search path).
class MtlBesideObj : public tinyobj::MaterialReader {
 public:
  explicit MtlBesideObj(fs::path dir) : dir_(std::move(dir)) {}
  bool operator()(const std::string& name, std::vector<tinyobj::material_t>* materials,
                  std::map<std::string, int>* matMap, std::string* warn, std::string* err) override {
    std::error_code ec;
    if (name.empty() || !fs::is_regular_file(dir_ / name, ec)) return false;  // obj::scanObj has named it
    std::ifstream in(dir_ / name);
    if (!in) return false;
    tinyobj::LoadMtl(matMap, materials, &in, warn, err);
    return true;
  }

 private:
  fs::path dir_;
};

// Loads an OBJ (and its MTL files): obj::scanObj checks every line, tinyobjloader reads what it
// passed (numbers as tinyobjloader always read them), triangulatePolygon cuts the faces.
// MTL materials are appended to `materials` as "<object name>/<mtl name>"; faces without one get
// `fallbackMaterial`.
Mesh loadObj(const Reader& r, const std::string& ptr, const std::string& objPath, const std::string& objectName,
             std::vector<Material>& materials, uint32_t fallbackMaterial, bool overrideMaterial) {
  std::error_code ec;
  if (fs::is_directory(objPath, ec))
    r.fail(ptr, "OBJ path " + objPath + " is a folder; expected a Wavefront .obj file");
  if (!fs::exists(objPath, ec)) r.fail(ptr, "OBJ file " + objPath + " not found; expected a Wavefront .obj file");
  if (!fs::is_regular_file(objPath, ec))
    r.fail(ptr, "OBJ path " + objPath + " is not a regular file; expected a Wavefront .obj file");
  fs::path objDir = fs::path(objPath).parent_path();
  const obj::ObjText text = obj::scanObj(objPath);
  tinyobj::attrib_t attrib;
  std::vector<tinyobj::shape_t> shapes;
  std::vector<tinyobj::material_t> mtls;
  {
    std::string warn, err;
    std::istringstream in(text.text);
    MtlBesideObj mtlReader(objDir);
    if (!tinyobj::LoadObj(&attrib, &shapes, &mtls, &warn, &err, &in, &mtlReader, /*triangulate=*/false,
                          /*default_vcols_fallback=*/false)) {
      while (!err.empty() && (err.back() == '\n' || err.back() == '\r')) err.pop_back();
      r.fail(ptr, "cannot read OBJ file " + objPath + ": " + err);
    }
  }

  std::vector<uint32_t> materialIndex(mtls.size(), fallbackMaterial);
  if (!overrideMaterial) {
    for (size_t i = 0; i < mtls.size(); ++i) {
      Material mat;
      mat.name = objectName + "/" + mtls[i].name;
      mat.albedo = glm::vec3(mtls[i].diffuse[0], mtls[i].diffuse[1], mtls[i].diffuse[2]);
      if (!finite(mat.albedo)) mat.albedo = glm::vec3(0.8f);
      if (!mtls[i].alpha_texname.empty()) {
        std::string tex = resolvePath(mtls[i].alpha_texname, objDir);
        mat.alphaTexture =
            alphaOf(readImage(r, ptr, tex, "alpha texture (map_d of material \"" + mtls[i].name + "\")"));
        mat.hasAlpha = true;
      }
      materialIndex[i] = uint32_t(materials.size());
      materials.push_back(std::move(mat));
    }
  }

  Mesh m;
  bool anyUv = false;
  for (const auto& s : shapes)
    for (const auto& idx : s.mesh.indices)
      if (idx.texcoord_index >= 0) anyUv = true;
  // Corners sharing a position and a uv share a vertex; without uvs the OBJ's own vertex list is used.
  std::map<std::pair<int, int>, uint32_t> vertexOf;
  auto vertex = [&](const tinyobj::index_t& idx) -> uint32_t {
    int vi = idx.vertex_index;
    int ti = anyUv ? idx.texcoord_index : -1;
    if (vi < 0 || size_t(vi) * 3 + 2 >= attrib.vertices.size() + 0 ||
        (ti >= 0 && size_t(ti) * 2 + 1 >= attrib.texcoords.size()))
      r.fail(ptr, "OBJ file " + objPath + " has a face index out of range");
    auto key = std::make_pair(vi, ti);
    auto it = vertexOf.find(key);
    if (it != vertexOf.end()) return it->second;
    uint32_t id = uint32_t(m.positions.size());
    m.positions.emplace_back(attrib.vertices[3 * vi], attrib.vertices[3 * vi + 1], attrib.vertices[3 * vi + 2]);
    // OBJ's v = 0 is the image's bottom row; ours is the top row.
    if (anyUv)
      m.uvs.push_back(ti >= 0 ? glm::vec2(attrib.texcoords[2 * ti], 1.0f - attrib.texcoords[2 * ti + 1])
                              : glm::vec2(0));
    vertexOf.emplace(key, id);
    return id;
  };
  // Faces in file order, as obj::scanObj listed them (so an error can name the face's line).
  size_t face = 0;
  for (const auto& s : shapes) {
    size_t offset = 0;
    for (size_t f = 0; f < s.mesh.num_face_vertices.size(); ++f, ++face) {
      // tinyobjloader counts a face's corners in a byte (num_face_vertices holds unsigned char):
      // the line check's count is the true one, and must agree with it modulo 256.
      if (face >= text.faceCorners.size() || uint8_t(text.faceCorners[face]) != s.mesh.num_face_vertices[f] ||
          offset + text.faceCorners[face] > s.mesh.indices.size())
        throw DriverError("OBJ file " + objPath + ": tinyobjloader's face " + std::to_string(face + 1) +
                          " differs from the line check's; expected the same faces");
      const size_t n = text.faceCorners[face];
      const int line = text.faceLine[face];
      std::vector<glm::vec3> corners(n);
      for (size_t k = 0; k < n; ++k) {
        const int vi = s.mesh.indices[offset + k].vertex_index;
        if (vi < 0 || size_t(vi) * 3 + 2 >= attrib.vertices.size())
          obj::objError(objPath, line, "a vertex index out of range; expected an index of a \"v\" line");
        corners[k] = glm::vec3(attrib.vertices[3 * vi], attrib.vertices[3 * vi + 1], attrib.vertices[3 * vi + 2]);
      }
      const PolygonTriangles cut = triangulatePolygon(corners);
      if (!cut.error.empty()) obj::objError(objPath, line, cut.error);
      const int mid = f < s.mesh.material_ids.size() ? s.mesh.material_ids[f] : -1;
      const uint32_t material =
          mid >= 0 && size_t(mid) < materialIndex.size() ? materialIndex[size_t(mid)] : fallbackMaterial;
      for (const auto& c : cut.triangles) {
        glm::uvec3 t(vertex(s.mesh.indices[offset + c[0]]), vertex(s.mesh.indices[offset + c[1]]),
                     vertex(s.mesh.indices[offset + c[2]]));
        m.triangles.push_back(t);
        m.triangleMaterial.push_back(material);
      }
      offset += n;
    }
  }
  if (face != text.faceCorners.size())
    throw DriverError("OBJ file " + objPath + ": tinyobjloader read " + std::to_string(face) +
                      " faces, the line check " + std::to_string(text.faceCorners.size()) +
                      "; expected the same faces");
  if (m.triangles.empty()) r.fail(ptr, "OBJ file " + objPath + " has no triangles; expected at least one face");
  for (const auto& p : m.positions)
    if (!finite(p)) r.fail(ptr, "OBJ file " + objPath + " has a non-finite vertex; expected finite coordinates");
  return m;
}

// ---------------------------------------------------------------------------------------------

glm::mat4 readTransform(const Reader& r, const Node& obj) {
  Node t = r.child(obj, "transform");
  if (!t) return glm::mat4(1.0f);
  r.keys(t, {"translate", "rotate_deg", "scale"});
  glm::vec3 translate(0), rotateDeg(0), scale(1);
  if (Node n = r.child(t, "translate")) translate = r.vec3(n);
  if (Node n = r.child(t, "rotate_deg")) rotateDeg = r.vec3(n);
  if (Node n = r.child(t, "scale")) scale = r.positive3(n, "x, y, z", true);
  // XYZ Euler: X first, then Y, then Z (column vectors: Rz * Ry * Rx).
  glm::mat4 m = glm::translate(glm::mat4(1.0f), translate);
  m = glm::rotate(m, glm::radians(rotateDeg.z), glm::vec3(0, 0, 1));
  m = glm::rotate(m, glm::radians(rotateDeg.y), glm::vec3(0, 1, 0));
  m = glm::rotate(m, glm::radians(rotateDeg.x), glm::vec3(1, 0, 0));
  m = glm::scale(m, scale);
  return m;
}

// Unit vector from `n`; zero length is an error.
glm::vec3 direction(const Reader& r, const Node& n) {
  glm::vec3 d = r.vec3(n);
  float len = glm::length(d);
  if (!(len > 1e-12f) || !std::isfinite(len))
    r.fail(n.ptr, "got " + vecText(d) + " (zero length); expected a non-zero direction");
  return d / len;
}

void readCamera(const Reader& r, const Node& root, Camera& cam) {
  Node c = r.require(root, "camera", "an object with position, look_at, vfov_deg, width, height");
  r.keys(c, {"position", "look_at", "up", "projection", "vfov_deg", "ortho_height", "width", "height", "near", "far"});
  cam.position = r.vec3(r.require(c, "position", "3 numbers (x, y, z)"));
  Node lookAt = r.require(c, "look_at", "3 numbers (x, y, z)");
  cam.lookAt = r.vec3(lookAt);
  if (Node n = r.child(c, "up")) cam.up = direction(r, n);
  if (Node n = r.child(c, "projection")) {
    const std::string p = r.string(n, "perspective or orthographic");
    if (p == "orthographic") cam.projection = Projection::Orthographic;
    else if (p != "perspective") r.fail(n.ptr, "got \"" + p + "\"; expected perspective or orthographic");
  }
  if (cam.orthographic()) {
    // The view's height in world units; vfov_deg would be a second, contradicting size.
    if (Node n = r.child(c, "vfov_deg"))
      r.fail(n.ptr, "given with \"projection\": \"orthographic\"; expected ortho_height (the view's height, world "
                    "units) instead");
    cam.orthoHeight = float(r.positive(r.require(c, "ortho_height", "the view's height in world units, > 0")));
  } else {
    if (Node n = r.child(c, "ortho_height"))
      r.fail(n.ptr, "given with a perspective camera; expected \"projection\": \"orthographic\" beside it");
    cam.vfovDeg = float(r.range(r.require(c, "vfov_deg", "a number in (0, 180)"), 0, true, 180, true,
                                "a field of view in degrees, 0 < vfov_deg < 180"));
  }
  // 16384: the largest 2D image every Vulkan device must support (maxImageDimension2D, lavapipe's
  // limit); memory is checked per command (--max-memory).
  cam.width = int(r.integer(r.require(c, "width", "an integer 1..16384"), 1, kMaxResolution, kResolutionWhy));
  cam.height = int(r.integer(r.require(c, "height", "an integer 1..16384"), 1, kMaxResolution, kResolutionWhy));
  if (Node n = r.child(c, "near")) cam.nearPlane = float(r.positive(n));
  if (Node n = r.child(c, "far")) cam.farPlane = float(r.positive(n));
  glm::vec3 view = cam.lookAt - cam.position;
  if (!(glm::length(view) > 1e-6f))
    r.fail(lookAt.ptr, "got " + vecText(cam.lookAt) + ", the camera position; expected a point away from the camera");
  if (glm::length(glm::cross(glm::normalize(view), cam.up)) < 1e-4f)
    r.fail(r.child(c, "up").ptr, "got " + vecText(cam.up) + ", parallel to the view direction " +
                                     vecText(glm::normalize(view)) + "; expected an up vector not parallel to it");
  if (!(cam.nearPlane < cam.farPlane))
    r.fail(r.child(c, "near").ptr,
           "got near " + numberText(cam.nearPlane) + " >= far " + numberText(cam.farPlane) + "; expected near < far");
}

void readMaterials(const Reader& r, const Node& root, const fs::path& dir, std::vector<Material>& materials) {
  Material def;
  def.name = "default";
  materials.push_back(def);
  Node ms = r.child(root, "materials");
  if (!ms) return;
  if (!ms.j->is_object()) r.expected(ms, "an object of named materials");
  for (const auto& item : ms.j->items()) {
    Node m{&item.value(), detail::childPointer(ms.ptr, item.key())};
    r.keys(m, {"two_sided", "alpha_texture", "alpha_cutoff", "albedo"}, "a material object");
    Material mat;
    mat.name = item.key();
    if (Node n = r.child(m, "two_sided")) mat.twoSided = r.boolean(n);
    if (Node n = r.child(m, "alpha_cutoff")) mat.alphaCutoff = float(r.range(n, 0, false, 1, false, "a number 0..1"));
    if (Node n = r.child(m, "albedo")) {
      if (n.j->is_number())
        mat.albedo = glm::vec3(float(r.range(n, 0, false, 1, false, "a number 0..1 or 3 numbers (r, g, b)")));
      else {
        mat.albedo = r.vec3(n);
        for (int k = 0; k < 3; ++k)
          if (mat.albedo[k] < 0 || mat.albedo[k] > 1)
            r.fail(detail::childPointer(n.ptr, size_t(k)),
                   "got " + detail::describe((*n.j)[k]) + "; expected a number 0..1");
      }
    }
    if (Node n = r.child(m, "alpha_texture")) {
      std::string path = resolvePath(r.string(n, "a path to an image"), dir);
      mat.alphaTexture = alphaOf(readImage(r, n.ptr, path, "alpha texture"));
      mat.hasAlpha = true;
    }
    if (mat.name == "default") materials[0] = std::move(mat);
    else materials.push_back(std::move(mat));
  }
}

const std::vector<std::string> kObjectCommon = {"type", "name", "id", "material", "casts_shadow", "transform"};

// What the scene's glTF objects bring besides triangles (gltf_loader.h), gathered while reading
// objects and applied once they are all read (finishGltf).
struct GltfState {
  std::vector<SceneOverride> overrides;  // a .gltf/.glb path as the scene: overrides address the glTF
  bool any = false;
  bool hasCamera = false, explicitCamera = false, infiniteFar = false;
  Camera camera;
  std::string cameraFile;  // the glTF file the camera came from, and its index in "cameras"
  int cameraIndex = -1;
  std::vector<Light> lights;
  std::vector<std::string> lightFile, lightRadiusPtr;  // per light: its glTF file and the pointer of its radius
  bool scene = false;                                  // the glTF file is the scene: its marked nodes become objects
  std::vector<gltf::Part> parts;                       // the marked nodes of that file (gltf_loader.h)
  uint64_t hash = 0;
};

// A {"type": "gltf"} object: its file flattened into one mesh (in the glTF scene's world space; the
// object's transform is applied by the caller), its lights and camera moved by that transform.
Mesh readGltfObject(const Reader& r, const Node& o, const fs::path& dir, const std::string& name, Scene& scene,
                    uint32_t material, uint64_t budget, GltfState& st) {
  Node p = r.require(o, "path", "a path to a .gltf or .glb file");
  gltf::Request q;
  q.path = resolvePath(r.string(p, "a path to a .gltf or .glb file"), dir);
  const std::string problem = gltf::notARegularFile(q.path);
  if (!problem.empty()) r.fail(p.ptr, "glTF file " + q.path + ": " + problem + "; expected a .gltf or .glb file");
  q.objectName = name;
  q.fallbackMaterial = material;
  q.overrides = st.overrides;
  q.triangleBudget = budget;
  q.budgetWhy = "(triangle ids travel through float channels, exact below 2^24)";
  q.requestFile = r.file();
  q.requestPtr = o.ptr;
  if (Node n = r.child(o, "scene")) q.sceneIndex = int(r.integer(n, 0, std::numeric_limits<int>::max()));
  Node cam = r.child(o, "camera");
  if (cam) {
    if (cam.j->is_string()) q.cameraName = r.string(cam, "a camera name or index");
    else q.cameraIndex = int(r.integer(cam, 0, std::numeric_limits<int>::max()));
    if (st.explicitCamera) r.fail(cam.ptr, "a second glTF object chooses the camera; expected one at most");
  }
  gltf::Content c = gltf::load(q, scene.materials);
  for (const auto& w : c.warnings) std::fprintf(stderr, "%s\n", w.c_str());
  const glm::mat4 xf = readTransform(r, o);
  const glm::mat3 xf3(xf);
  auto point = [&](glm::vec3 v) { return glm::vec3(xf * glm::vec4(v, 1.0f)); };
  // Exact values from a file's shadowlab extras stay bit for bit where no transform moves them.
  const bool moved = bool(r.child(o, "transform"));
  for (size_t i = 0; i < c.lights.size(); ++i) {
    Light l = c.lights[i];
    if (moved || !c.lightExact[i]) {
      l.position = point(l.position);
      l.direction = glm::normalize(xf3 * l.direction);
    }
    st.lights.push_back(l);
    st.lightFile.push_back(q.path);
    st.lightRadiusPtr.push_back(c.lightRadiusPtr[i]);
  }
  if (st.scene) st.parts = std::move(c.parts);
  if (c.hasCamera && (cam || !st.hasCamera)) {
    Camera k = c.camera;
    if (moved || !c.cameraExact) {
      const glm::vec3 forward = glm::normalize(xf3 * (c.camera.lookAt - c.camera.position));
      k.position = point(c.camera.position);
      k.lookAt = k.position + forward;
      k.up = glm::normalize(xf3 * c.camera.up);
    }
    st.camera = k;
    st.infiniteFar = c.infiniteFar;
    st.hasCamera = true;
    st.explicitCamera = bool(cam);
    st.cameraFile = q.path;
    st.cameraIndex = c.cameraIndex;
  }
  st.any = true;
  st.hash = fnv1a64(&c.hash, sizeof c.hash, st.hash ^ 0x9e3779b97f4a7c15ull);
  Mesh m;
  m.positions = std::move(c.positions);
  m.uvs = std::move(c.uvs);
  m.triangles = std::move(c.triangles);
  m.triangleMaterial = std::move(c.triangleMaterial);
  return m;
}

// A glTF path as the scene whose mesh nodes say which shadowlab object they are (exportGlb): one
// object per node, in node order, with its name, id and casts_shadow (ids and names were checked
// unique by gltf_loader.cpp). The node's vertices are contiguous in the flattened mesh.
void splitParts(const Object& all, const std::vector<gltf::Part>& parts, Scene& scene) {
  for (const gltf::Part& p : parts) {
    if (p.triangleCount == 0) continue;  // a node of POINTS or LINES only
    Object obj;
    obj.name = p.name;
    obj.id = p.id;
    obj.castsShadow = p.castsShadow && all.castsShadow;
    obj.positions.assign(all.positions.begin() + ptrdiff_t(p.firstVertex),
                         all.positions.begin() + ptrdiff_t(p.firstVertex + p.vertexCount));
    if (!all.uvs.empty())
      obj.uvs.assign(all.uvs.begin() + ptrdiff_t(p.firstVertex),
                     all.uvs.begin() + ptrdiff_t(p.firstVertex + p.vertexCount));
    obj.triangles.reserve(p.triangleCount);
    for (size_t t = p.firstTriangle; t < p.firstTriangle + p.triangleCount; ++t)
      obj.triangles.push_back(all.triangles[t] - glm::uvec3(uint32_t(p.firstVertex)));
    obj.triangleMaterial.assign(all.triangleMaterial.begin() + ptrdiff_t(p.firstTriangle),
                                all.triangleMaterial.begin() + ptrdiff_t(p.firstTriangle + p.triangleCount));
    scene.objects.push_back(std::move(obj));
  }
}

void readObjects(const Reader& r, const Node& root, const fs::path& dir, Scene& scene, GltfState& gltfState) {
  Node os = r.require(root, "objects", "an array of objects");
  if (!os.j->is_array() || os.j->empty()) r.expected(os, "a non-empty array of objects");
  std::map<uint32_t, std::string> idOwner;
  std::set<std::string> names;
  uint64_t sceneTriangles = 0;
  // The scene's triangle budget, checked before a procedural mesh is built (its count is known from
  // its parameters: two maximal spheres would otherwise be built first) and after every object.
  auto checkTriangles = [&](const Node& o, uint64_t total) {
    if (total > kMaxSceneTriangles)
      r.fail(o.ptr, "the scene reaches " + std::to_string(total) + " triangles with this object; expected at most " +
                        std::to_string(kMaxSceneTriangles) +
                        " (triangle ids travel through float channels, exact below 2^24)");
  };
  for (size_t i = 0; i < os.j->size(); ++i) {
    Node o = r.at(os, i);
    if (!o.j->is_object()) r.expected(o, "an object");
    Node typeNode = r.require(o, "type", "one of plane, quad, box, sphere, cylinder, obj, gltf");
    std::string type = typeNode.j->is_string() ? typeNode.j->get<std::string>() : "";
    std::vector<std::string> extra;
    if (type == "plane" || type == "quad") extra = {"size", "uv_scale"};
    else if (type == "box") extra = {"size"};
    else if (type == "sphere") extra = {"radius", "segments", "rings"};
    else if (type == "cylinder") extra = {"radius", "height", "segments"};
    else if (type == "obj") extra = {"path"};
    else if (type == "gltf") extra = {"path", "scene", "camera"};
    else r.expected(typeNode, "one of plane, quad, box, sphere, cylinder, obj, gltf");
    std::vector<std::string> allowed = kObjectCommon;
    allowed.insert(allowed.end(), extra.begin(), extra.end());
    r.keys(o, allowed);

    Object obj;
    obj.name = type + std::to_string(i + 1);
    if (Node n = r.child(o, "name")) {
      obj.name = r.string(n, "a non-empty name");
      checkName(r, n, obj.name);
    }
    if (!names.insert(obj.name).second)
      r.fail(r.child(o, "name").ptr, "duplicate object name \"" + obj.name + "\"; expected a unique name");
    obj.id = uint32_t(i + 1);
    Node idNode = r.child(o, "id");
    if (idNode) obj.id = uint32_t(r.integer(idNode, 1, kMaxObjectId));
    if (idOwner.count(obj.id))
      r.fail(idNode ? idNode.ptr : o.ptr, "object id " + std::to_string(obj.id) + " is already used by " +
                                              idOwner[obj.id] +
                                              "; expected unique ids (the default id is the 1-based index)");
    idOwner[obj.id] = "\"" + obj.name + "\" (" + o.ptr + ")";
    if (Node n = r.child(o, "casts_shadow")) obj.castsShadow = r.boolean(n);

    uint32_t material = 0;
    Node matNode = r.child(o, "material");
    if (matNode) {
      std::string name = r.string(matNode, "a material name");
      bool found = false;
      for (size_t k = 0; k < scene.materials.size(); ++k)
        if (scene.materials[k].name == name) {
          material = uint32_t(k);
          found = true;
        }
      if (!found) {
        std::string list;
        for (const auto& m : scene.materials) list += (list.empty() ? "" : ", ") + m.name;
        r.fail(matNode.ptr, "unknown material \"" + name + "\"; expected one of " + list);
      }
    }

    auto uvScaleOf = [&]() {
      Node n = r.child(o, "uv_scale");
      return n ? r.positive2(n, "u, v", true) : glm::vec2(1.0f);
    };
    Mesh mesh;
    if (type == "plane")
      mesh = makePlane(r.positive2(r.require(o, "size", "2 positive numbers (sx, sz)"), "sx, sz", false), uvScaleOf());
    else if (type == "quad")
      mesh = makeQuad(r.positive2(r.require(o, "size", "2 positive numbers (sx, sy)"), "sx, sy", false), uvScaleOf());
    else if (type == "box")
      mesh = makeBox(r.positive3(r.require(o, "size", "3 positive numbers (x, y, z)"), "x, y, z", false));
    else if (type == "sphere") {
      double radius = r.positive(r.require(o, "radius", "a positive number"));
      int segments = 256, rings = 128;
      if (Node n = r.child(o, "segments")) segments = int(r.integer(n, 3, 4096));
      if (Node n = r.child(o, "rings")) rings = int(r.integer(n, 2, 2048));
      checkTriangles(o, sceneTriangles + 2ull * uint64_t(segments) * uint64_t(rings - 1));  // makeSphere's count
      mesh = makeSphere(radius, segments, rings);
    } else if (type == "cylinder") {
      double radius = r.positive(r.require(o, "radius", "a positive number"));
      double height = r.positive(r.require(o, "height", "a positive number"));
      int segments = 256;
      if (Node n = r.child(o, "segments")) segments = int(r.integer(n, 3, 4096));
      mesh = makeCylinder(radius, height, segments);
    } else if (type == "gltf") {
      mesh = readGltfObject(r, o, dir, obj.name, scene, material, kMaxSceneTriangles - sceneTriangles, gltfState);
    } else {
      Node p = r.require(o, "path", "a path to an .obj file");
      std::string path = resolvePath(r.string(p, "a path to an .obj file"), dir);
      mesh = loadObj(r, p.ptr, path, obj.name, scene.materials, material, bool(matNode));
    }

    glm::mat4 xf = readTransform(r, o);
    obj.positions.reserve(mesh.positions.size());
    for (const auto& p : mesh.positions) {
      glm::vec3 w = glm::vec3(xf * glm::vec4(p, 1.0f));
      if (!finite(w))
        r.fail(o.ptr,
               "the transformed geometry has a non-finite coordinate; expected finite positions (check the transform "
               "and sizes)");
      obj.positions.push_back(w);
    }
    obj.uvs = std::move(mesh.uvs);
    obj.triangles = std::move(mesh.triangles);
    obj.triangleMaterial = mesh.triangleMaterial.empty() ? std::vector<uint32_t>(obj.triangles.size(), material)
                                                         : std::move(mesh.triangleMaterial);
    for (size_t t = 0; t < obj.triangles.size(); ++t)
      if (scene.materials[obj.triangleMaterial[t]].hasAlpha && obj.uvs.empty())
        r.fail(matNode ? matNode.ptr : o.ptr,
               "material \"" + scene.materials[obj.triangleMaterial[t]].name + "\" has an alpha texture but a " + type +
                   " has no uv coordinates; expected a plane, quad, box or an OBJ with vt");
    sceneTriangles += obj.triangles.size();
    checkTriangles(o, sceneTriangles);
    if (type == "gltf" && !gltfState.parts.empty()) splitParts(obj, gltfState.parts, scene);
    else scene.objects.push_back(std::move(obj));
  }
}

// The closest point of triangle (a, b, c) to p (Ericson, Real-Time Collision Detection, 5.1.5),
// in double: the distance decides whether a sphere light touches geometry.
glm::dvec3 closestPointOnTriangle(const glm::dvec3& p, const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c) {
  const glm::dvec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const glm::dvec3 bp = p - b;
  const double d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + ab * (d1 / (d1 - d3));
  const glm::dvec3 cp = p - c;
  const double d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + ac * (d2 / (d2 - d6));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  const double denom = 1.0 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

// A sphere light is a light source outside the scene: one whose sphere cuts or encloses geometry
// has surface points inside the light, whose truth the reference cannot give (its samples on the
// sphere lie behind or inside that geometry: a bright disc where the sphere cuts the ground, every
// pixel lit once it encloses everything). Refused: the radius must stay below the distance from
// the light's centre to the nearest triangle of any object (every object: one that casts no
// shadow is still lit by it).
void checkSphereLightClear(const Reader& r, const Node& radiusNode, const Light& light, const Scene& scene) {
  const glm::dvec3 centre(light.position);
  double nearest = std::numeric_limits<double>::infinity();
  const Object* reached = nullptr;
  for (const Object& o : scene.objects)
    for (const glm::uvec3& t : o.triangles) {
      const glm::dvec3 q = closestPointOnTriangle(centre, glm::dvec3(o.positions[t.x]), glm::dvec3(o.positions[t.y]),
                                                  glm::dvec3(o.positions[t.z]));
      const double d = glm::length(q - centre);
      if (d < nearest) nearest = d, reached = &o;
    }
  if (!reached || double(light.radius) < nearest) return;
  const std::string what = nearest == 0.0 ? "its centre lies on object \"" + reached->name + "\""
                                          : "its sphere reaches object \"" + reached->name + "\" at distance " +
                                                numberText(nearest) + " from the centre";
  r.expected(radiusNode, "a radius below " + numberText(nearest) + ": " + what +
                             " (a sphere light must lie outside every object; radius 0..1e30)");
}

void readLights(const Reader& r, const Node& root, Scene& scene) {
  Node ls = r.child(root, "lights");
  if (!ls) return;
  if (!ls.j->is_array()) r.expected(ls, "an array of lights");
  std::set<std::string> names;
  for (size_t i = 0; i < ls.j->size(); ++i) {
    Node l = r.at(ls, i);
    if (!l.j->is_object()) r.expected(l, "a light object");
    Node typeNode = r.require(l, "type", "one of " + kindKeys(lightTypeKinds()));
    std::string type = typeNode.j->is_string() ? typeNode.j->get<std::string>() : "";
    const KindInfo<LightType>* kind = findKind(lightTypeKinds(), type);
    if (!kind) r.expected(typeNode, "one of " + kindKeys(lightTypeKinds()));
    Light light;
    light.type = kind->kind;
    switch (light.type) {  // the keys each type takes
      case LightType::Directional:
        r.keys(l, {"type", "name", "direction", "elevation_deg", "azimuth_deg", "angular_diameter_deg"});
        break;
      case LightType::Spot:
        r.keys(l, {"type", "name", "position", "direction", "look_at", "cone_deg", "near", "radius"});
        break;
      case LightType::Point: r.keys(l, {"type", "name", "position", "near", "radius"}); break;
    }
    light.name = type == "directional" ? "sun" : type;
    if (ls.j->size() > 1) light.name += std::to_string(i + 1);
    if (Node n = r.child(l, "name")) {
      light.name = r.string(n, "a non-empty name");
      checkName(r, n, light.name);
    }
    if (!names.insert(light.name).second)
      r.fail(r.child(l, "name").ptr,
             "duplicate light name \"" + light.name + "\"; expected a unique name (it names output channels)");

    if (light.type == LightType::Directional) {
      Node d = r.child(l, "direction"), e = r.child(l, "elevation_deg"), a = r.child(l, "azimuth_deg");
      if (d && (e || a)) r.fail(d.ptr, "both direction and elevation_deg/azimuth_deg given; expected one of them");
      if (d) {
        light.direction = direction(r, d);
      } else {
        if (!e)
          r.fail(
              l.ptr,
              "missing key \"direction\" (or \"elevation_deg\" and \"azimuth_deg\"); expected the light's direction");
        double elev = r.range(e, -90, false, 90, false, "an elevation in degrees -90..90");
        double azim = a ? r.number(a) : 0.0;
        double er = elev * kPi / 180.0, ar = azim * kPi / 180.0;
        // Direction TO the light; the light travels the opposite way.
        glm::dvec3 toLight(std::cos(er) * std::sin(ar), std::sin(er), std::cos(er) * std::cos(ar));
        light.direction = glm::vec3(-toLight);
      }
      if (Node n = r.child(l, "angular_diameter_deg"))
        light.angularDiameterDeg =
            float(r.range(n, 0, false, kMaxAngularDiameterDeg, false,
                          "an angle in degrees 0.." + std::to_string(int(kMaxAngularDiameterDeg)) +
                              " (the light's angular diameter; 0: a hard light)"));
    } else {
      light.position = r.vec3(r.require(l, "position", "3 numbers (x, y, z)"));
      if (Node n = r.child(l, "near")) light.nearPlane = float(r.positive(n));
      if (Node n = r.child(l, "radius")) {
        light.radius = float(r.range(n, 0, false, 1e30, false, "a radius 0..1e30 (a sphere light; 0: a hard light)"));
        if (light.radius > 0.0f) checkSphereLightClear(r, n, light, scene);
      }
      if (light.type == LightType::Spot) {
        Node d = r.child(l, "direction"), at = r.child(l, "look_at");
        if (d && at) r.fail(d.ptr, "both direction and look_at given; expected one of them");
        if (d) light.direction = direction(r, d);
        else if (at) {
          glm::vec3 v = r.vec3(at) - light.position;
          if (!(glm::length(v) > 1e-6f)) r.fail(at.ptr, "got the light's own position; expected a point away from it");
          light.direction = glm::normalize(v);
        } else {
          r.fail(l.ptr, "missing key \"direction\" (or \"look_at\"); expected where the spot light points");
        }
        Node cone = r.require(l, "cone_deg", "the full apex angle in degrees");
        light.coneDeg = float(r.range(cone, 0, true, 180, true, "a cone angle in degrees, 0 < cone_deg < 180"));
      }
    }
    scene.lights.push_back(light);
  }
}

void readProjectors(const Reader& r, const Node& root, const fs::path& dir, Scene& scene) {
  Node ps = r.child(root, "projectors");
  if (!ps) return;
  if (!ps.j->is_array()) r.expected(ps, "an array of projectors");
  std::set<std::string> names;
  for (size_t i = 0; i < ps.j->size(); ++i) {
    Node p = r.at(ps, i);
    r.keys(p, {"name", "position", "direction", "look_at", "up", "fov_deg", "aspect", "near", "far", "image"},
           "a projector object");
    Projector proj;
    proj.name = ps.j->size() > 1 ? "projector" + std::to_string(i + 1) : "projector";
    if (Node n = r.child(p, "name")) {
      proj.name = r.string(n, "a non-empty name");
      checkName(r, n, proj.name);
    }
    if (!names.insert(proj.name).second)
      r.fail(r.child(p, "name").ptr,
             "duplicate projector name \"" + proj.name + "\"; expected a unique name (it names output channels)");
    proj.position = r.vec3(r.require(p, "position", "3 numbers (x, y, z)"));
    Node d = r.child(p, "direction"), at = r.child(p, "look_at");
    if (d && at) r.fail(d.ptr, "both direction and look_at given; expected one of them");
    Node dirNode = d ? d : at;
    if (d) proj.direction = direction(r, d);
    else if (at) {
      glm::vec3 v = r.vec3(at) - proj.position;
      if (!(glm::length(v) > 1e-6f)) r.fail(at.ptr, "got the projector's own position; expected a point away from it");
      proj.direction = glm::normalize(v);
    } else {
      r.fail(p.ptr, "missing key \"direction\" (or \"look_at\"); expected where the projector points");
    }
    Node upNode = r.child(p, "up");
    if (upNode) proj.up = direction(r, upNode);
    if (glm::length(glm::cross(proj.direction, proj.up)) < 1e-4f)
      r.fail(upNode ? upNode.ptr : dirNode.ptr, "up " + vecText(proj.up) + " is parallel to the direction " +
                                                    vecText(proj.direction) +
                                                    "; expected an up vector not parallel to it");
    proj.fovDeg = float(r.range(r.require(p, "fov_deg", "a vertical field of view in degrees"), 0, true, 180, true,
                                "a field of view in degrees, 0 < fov_deg < 180"));
    if (Node n = r.child(p, "near")) proj.nearPlane = float(r.positive(n));
    if (Node n = r.child(p, "far")) proj.farPlane = float(r.positive(n));
    if (!(proj.nearPlane < proj.farPlane))
      r.fail(r.child(p, "near").ptr, "got near " + numberText(proj.nearPlane) + " >= far " + numberText(proj.farPlane) +
                                         "; expected near < far");
    Node img = r.require(p, "image", "a path to an image");
    proj.image = rgbOf(readImage(r, img.ptr, resolvePath(r.string(img, "a path to an image"), dir), "projector image"));
    proj.aspect = float(proj.image.width) / float(proj.image.height);
    if (Node n = r.child(p, "aspect"))
      proj.aspect = float(r.range(n, 0, true, 1e4, false, "a positive aspect ratio (width / height)"));
    scene.projectors.push_back(std::move(proj));
  }
}

void readFailure(const Reader& r, const Node& root, Scene& scene) {
  Node f = r.child(root, "failure");
  if (!f) return;
  r.keys(f, {"pointer", "values", "description"});
  Node p = r.require(f, "pointer", "a JSON pointer into this scene file");
  scene.failurePointer = r.string(p, "a JSON pointer into this scene file");
  try {
    json::json_pointer ptr(scene.failurePointer);
    if (!root.j->contains(ptr))
      r.fail(p.ptr,
             "got \"" + scene.failurePointer + "\", which is not in this scene; expected a pointer to a value in it");
    if (!(*root.j)[ptr].is_number())
      r.fail(p.ptr, "got \"" + scene.failurePointer + "\", which points at " + detail::describe((*root.j)[ptr]) +
                        "; expected a pointer to a number");
  } catch (const json::exception& e) {
    r.fail(p.ptr, "got \"" + scene.failurePointer + "\"; expected a JSON pointer like /lights/0/elevation_deg");
  }
  Node v = r.require(f, "values", "an array of numbers");
  if (!v.j->is_array() || v.j->empty()) r.expected(v, "a non-empty array of numbers");
  for (size_t i = 0; i < v.j->size(); ++i) scene.failureValues.push_back(r.number(r.at(v, i)));
  if (Node d = r.child(f, "description")) r.string(d);
}

// "paths": named camera paths for `shadowlab stability --path NAME` (scenes/FORMAT.md, "paths").
// Each path is expanded here once, so a degenerate keyframe interpolation is an error at load time.
void readPaths(const Reader& r, const Node& root, Scene& scene) {
  Node ps = r.child(root, "paths");
  if (!ps) return;
  if (!ps.j->is_object() || ps.j->empty()) r.expected(ps, "a non-empty object of named camera paths");
  const std::string frameRange = "an integer 2.." + std::to_string(kMaxPathFrames);
  for (const auto& item : ps.j->items()) {
    Node p{&item.value(), detail::childPointer(ps.ptr, item.key())};
    CameraPath path;
    path.name = item.key();
    // The name is given on the command line (--path NAME): the same characters as light names.
    for (char c : path.name)
      if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-'))
        r.fail(p.ptr, "path name \"" + path.name +
                          "\" has a character other than letters, digits, '_' and '-'; "
                          "expected a name usable as --path NAME");
    // dolly and orbit are the generated paths' names: a scene path of that name would hide them.
    if (path.name == "dolly" || path.name == "orbit")
      r.fail(p.ptr, "path name \"" + path.name + "\" is reserved for the generated paths; expected another name");
    if (!p.j->is_object()) r.expected(p, "a camera path object with \"kind\"");
    Node kind = r.require(p, "kind", "one of dolly, orbit, keyframes");
    const std::string k = kind.j->is_string() ? kind.j->get<std::string>() : "";
    if (k == "dolly") {
      r.keys(p, {"kind", "frames", "distance"});
      path.kind = CameraPathKind::Dolly;
      path.distanceWorld = float(r.number(r.require(p, "distance", "the total travel in world units")));
    } else if (k == "orbit") {
      r.keys(p, {"kind", "frames", "angle_deg"});
      path.kind = CameraPathKind::Orbit;
      path.angleDeg = float(r.range(r.require(p, "angle_deg", "the total rotation in degrees"), -360, false, 360, false,
                                    "an angle in degrees -360..360"));
    } else if (k == "keyframes") {
      r.keys(p, {"kind", "frames", "cameras"});
      path.kind = CameraPathKind::Keyframes;
      Node cams = r.require(p, "cameras", "an array of at least 2 cameras {position, look_at, up?}");
      if (!cams.j->is_array() || cams.j->size() < 2)
        r.expected(cams, "an array of at least 2 cameras {position, look_at, up?}");
      for (size_t i = 0; i < cams.j->size(); ++i) {
        Node c = r.at(cams, i);
        r.keys(c, {"position", "look_at", "up"}, "a camera object {position, look_at, up?}");
        Camera cam = scene.camera;  // field of view, size and depth range stay the scene camera's
        cam.position = r.vec3(r.require(c, "position", "3 numbers (x, y, z)"));
        cam.lookAt = r.vec3(r.require(c, "look_at", "3 numbers (x, y, z)"));
        cam.up = glm::vec3(0, 1, 0);
        if (Node u = r.child(c, "up")) cam.up = direction(r, u);
        const std::string problem = pathCameraProblem(cam);
        if (!problem.empty())
          r.fail(c.ptr, "keyframe " + std::to_string(i) + " is degenerate: " + problem +
                            "; expected a camera that looks somewhere");
        path.keyframes.push_back(cam);
      }
      path.frames = int(path.keyframes.size());
    } else {
      r.expected(kind, "one of dolly, orbit, keyframes");
    }
    if (Node f = r.child(p, "frames")) path.frames = int(r.integer(f, 2, kMaxPathFrames));
    else if (path.kind != CameraPathKind::Keyframes) r.fail(p.ptr, "missing key \"frames\"; expected " + frameRange);
    if (path.frames > kMaxPathFrames)
      r.fail(p.ptr,
             "got " + std::to_string(path.frames) + " keyframes; expected at most " + std::to_string(kMaxPathFrames));
    try {
      (void)expandCameraPath(scene.camera, path);
    } catch (const InputError& e) {
      // The generators word their errors for the command line ("keyframes: error: ..."): keep the
      // part after "error: " and put it at this path's pointer.
      std::string what = e.what();
      const auto at = what.find("error: ");
      r.fail(p.ptr, at == std::string::npos ? what : what.substr(at + 7));
    }
    scene.paths.push_back(std::move(path));
  }
}

// Every number as a double, so 50 in the file and 50.0 from an override hash alike.
json canonicalNumbers(const json& j) {
  if (j.is_number()) return json(j.get<double>());
  if (j.is_array()) {
    json out = json::array();
    for (const auto& v : j) out.push_back(canonicalNumbers(v));
    return out;
  }
  if (j.is_object()) {
    json out = json::object();
    for (const auto& item : j.items()) out[item.key()] = canonicalNumbers(item.value());
    return out;
  }
  return j;
}

// FNV-1a over the canonical document (sorted keys, no comments or whitespace, numbers as
// doubles) and everything resolved from files.
std::string sceneHash(const json& doc, const Scene& s) {
  std::string canonical = canonicalNumbers(doc).dump(-1, ' ', false, json::error_handler_t::replace);
  uint64_t h = fnv1a64(canonical.data(), canonical.size());
  auto mix = [&h](const void* p, size_t n) { h = fnv1a64(p, n, h); };
  for (const auto& o : s.objects) {
    mix(o.positions.data(), o.positions.size() * sizeof(glm::vec3));
    mix(o.uvs.data(), o.uvs.size() * sizeof(glm::vec2));
    mix(o.triangles.data(), o.triangles.size() * sizeof(glm::uvec3));
    mix(o.triangleMaterial.data(), o.triangleMaterial.size() * sizeof(uint32_t));
  }
  for (const auto& m : s.materials) mix(m.alphaTexture.pixels.data(), m.alphaTexture.pixels.size() * sizeof(float));
  for (const auto& p : s.projectors) mix(p.image.pixels.data(), p.image.pixels.size() * sizeof(float));
  return hashHex(h);
}

void applyOverrides(const Reader& r, json& doc, const std::vector<SceneOverride>& overrides) {
  for (const auto& o : overrides) {
    // Named by its origin when it has one (the scene file then follows the message).
    auto formatError = [&](const std::string& file, const std::string& place, const std::string& what) {
      return o.origin.empty() ? shadowlab::formatError(file, place, what)
                              : shadowlab::formatError(o.origin, "", what + " (" + file + ")");
    };
    std::string place = "override " + o.pointer;
    json::json_pointer ptr;
    try {
      ptr = json::json_pointer(o.pointer);
    } catch (const json::exception&) {
      throw InputError(formatError(r.file(), place,
                                   "got \"" + o.pointer + "\"; expected a JSON pointer like /lights/0/elevation_deg"));
    }
    if (ptr.empty())
      throw InputError(
          formatError(r.file(), place, "cannot replace the whole document; expected a pointer to a value"));
    // The value must exist, or be a new key of an existing object (validated like any key).
    bool exists = false;
    try {
      exists = doc.contains(ptr);
    } catch (const json::exception&) {
      exists = false;
    }
    bool parentIsObject = false;
    try {
      json::json_pointer parent = ptr.parent_pointer();
      parentIsObject = doc.contains(parent) && doc[parent].is_object();
    } catch (const json::exception&) {
      parentIsObject = false;
    }
    if (!exists && !parentIsObject)
      throw InputError(
          formatError(r.file(), place, "no such value in the scene; expected a pointer to an existing value"));
    doc[ptr] = o.value;
  }
}

bool finiteMatrix(const glm::mat4& m) {
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r)
      if (!std::isfinite(m[c][r])) return false;
  return true;
}

// Inputs are finite one by one, yet their combination can overflow float (a camera 1e38 away
// from its target): check what the renderers will compute before handing the scene over.
// `cameraFrom`: where the camera came from when the scene has no JSON "camera" (a glTF file's
// camera, or the framing camera), for the message.
void checkComputed(const Reader& r, const Scene& s, const GltfState* cameraFrom) {
  const Camera& c = s.camera;
  bool ok = finiteMatrix(c.viewFromWorld()) && finiteMatrix(c.clipFromView());
  for (glm::vec2 px : {glm::vec2(0), glm::vec2(float(c.width), float(c.height)), glm::vec2(0, float(c.height))})
    ok = ok && finite(c.rayDirection(px.x, px.y));
  const std::string what = "the camera's matrices or rays are not finite; expected a camera with moderate coordinates";
  if (!ok && cameraFrom && cameraFrom->hasCamera)
    throw InputError(formatError(cameraFrom->cameraFile, "/cameras/" + std::to_string(cameraFrom->cameraIndex),
                                 what + " (the glTF camera, placed by its node)"));
  if (!ok && cameraFrom)
    throw InputError(formatError(r.file(), "", what + " (the framing camera, from the scene's bounds)"));
  if (!ok) r.fail("/camera", what);
  for (size_t i = 0; i < s.lights.size(); ++i)
    if (!finite(s.lights[i].direction) || !finite(s.lights[i].position))
      r.fail("/lights/" + std::to_string(i), "the light's direction or position is not finite; expected finite values");
  for (size_t i = 0; i < s.projectors.size(); ++i)
    if (!finiteMatrix(s.projectors[i].texFromWorld()))
      r.fail("/projectors/" + std::to_string(i),
             "the projective texture matrix is not finite; expected moderate coordinates");
}

bool hasGltfObject(const json& doc) {
  auto it = doc.find("objects");
  if (it == doc.end() || !it->is_array()) return false;
  for (const auto& o : *it)
    if (o.is_object() && o.contains("type") && o["type"] == "gltf") return true;
  return false;
}

// The glTF objects' lights join the scene's (after the JSON lights; a clashing name gets "_2",
// "_3", ...), and the scene camera is the JSON "camera", else the glTF camera (its far plane past
// the scene's bounds when the glTF camera has no zfar), else one framing the bounds. A glTF path
// without lights gets a default sun, with a warning.
void finishGltf(const Reader& r, const Node& root, Scene& scene, const GltfState& st, bool gltfScene) {
  // A sphere light from a file's extras must lie outside every object, as a JSON scene's must.
  for (size_t i = 0; i < st.lights.size(); ++i)
    if (!st.lightRadiusPtr[i].empty()) {
      const json radius = double(st.lights[i].radius);
      checkSphereLightClear(Reader(st.lightFile[i]), Node{&radius, st.lightRadiusPtr[i]}, st.lights[i], scene);
    }
  std::set<std::string> names;
  for (const auto& l : scene.lights) names.insert(l.name);
  for (Light l : st.lights) {
    const std::string base = l.name;
    for (int k = 2; names.count(l.name); ++k) l.name = base + "_" + std::to_string(k);
    names.insert(l.name);
    scene.lights.push_back(l);
  }
  const Node camera = r.child(root, "camera");
  if (camera && st.explicitCamera)
    r.fail(camera.ptr, "both a JSON camera and a glTF object's \"camera\" are given; expected one of them");
  if (!camera) {
    const glm::vec3 lo = scene.boundsMin(), hi = scene.boundsMax();
    if (st.hasCamera) {
      scene.camera = st.camera;
      if (st.infiniteFar) {
        // No zfar means an infinite far plane: past the farthest corner of the scene's bounds.
        float farthest = 0;
        for (int k = 0; k < 8; ++k) {
          const glm::vec3 corner((k & 1) ? hi.x : lo.x, (k & 2) ? hi.y : lo.y, (k & 4) ? hi.z : lo.z);
          farthest = std::max(farthest, glm::length(corner - scene.camera.position));
        }
        scene.camera.farPlane = std::max(2.0f * farthest, 10.0f * scene.camera.nearPlane);
      }
    } else {
      scene.camera = gltf::framingCamera(lo, hi);
    }
  }
  if (gltfScene && scene.lights.empty()) {
    Light sun;
    sun.name = "sun";
    const double er = 50 * kPi / 180.0, ar = 30 * kPi / 180.0;
    sun.direction = -glm::vec3(glm::dvec3(std::cos(er) * std::sin(ar), std::sin(er), std::cos(er) * std::cos(ar)));
    scene.lights.push_back(sun);
    std::fprintf(stderr,
                 "%s: warning: no KHR_lights_punctual light; added a directional light \"sun\" (elevation 50, "
                 "azimuth 30 degrees)\n",
                 r.file().c_str());
  }
}

std::string envOr(const char* name, const std::string& fallback) {
  const char* v = std::getenv(name);
  return v && *v ? std::string(v) : fallback;
}

// The image size is a harness setting on any scene: when the camera comes from a glTF object (a
// glTF path, or a JSON scene without "camera"), /camera/width and /camera/height, which address
// no value in either document, set the size of the camera the scene ends up with.
bool isImageSizePointer(const std::string& pointer) {
  return pointer == "/camera/width" || pointer == "/camera/height";
}

void applyImageSize(const Reader& r, const std::vector<SceneOverride>& sizes, Camera& cam) {
  for (const SceneOverride& o : sizes) {
    const json& v = o.value;
    const bool ok = v.is_number_integer() &&
                    !(v.is_number_unsigned() && v.get<uint64_t>() > uint64_t(kMaxResolution)) &&
                    v.get<int64_t>() >= 1 && v.get<int64_t>() <= kMaxResolution;
    if (!ok) {
      const std::string what = "got " + detail::describe(v) + "; expected an integer 1.." +
                               std::to_string(kMaxResolution) + " (" + kResolutionWhy + ")";
      // The pointer names a value in neither the scene file nor the glTF file: cite the setting.
      if (!o.origin.empty())
        throw InputError(formatError(o.origin, "", what + " (the image size of " + r.file() + ")"));
      throw InputError(formatError(r.file(), "override " + o.pointer, what));
    }
    (o.pointer == "/camera/width" ? cam.width : cam.height) = int(v.get<int64_t>());
  }
}

}  // namespace

Scene loadScene(const std::string& path, const std::vector<SceneOverride>& overrides) {
  std::error_code ec;
  if (!fs::exists(path, ec)) {
    std::string hint;
    if (fs::path(path).parent_path() == fs::path(bundledScenesDir())) {
      hint = "; expected a file or a bundled scene name:";
      for (const auto& n : bundledSceneNames()) hint += " " + n;
    }
    throw InputError(formatError(path, "", "cannot open scene file: no such file" + hint));
  }
  // A device (/dev/zero) or a FIFO would be read until it ends, which may be never.
  if (const std::string problem = gltf::notARegularFile(path); !problem.empty() && !fs::is_directory(path, ec))
    throw InputError(formatError(
        path, "", "cannot read the scene file: " + problem + "; expected a JSON scene, .gltf or .glb file"));
  // A .gltf/.glb path is the scene of one glTF object (its overrides address the glTF document).
  const bool gltfScene = gltf::isGltfPath(path);
  json doc = gltfScene ? json{{"objects",
                               {{{"type", "gltf"},
                                 {"name", gltf::sanitizeName(fs::path(path).stem().string())},
                                 {"path", fs::path(path).filename().string()}}}}}
                       : readJsonFile(path);
  Reader r(path);
  Node root{&doc, ""};
  if (!doc.is_object()) r.expected(root, "a JSON object with camera, objects and lights");
  std::vector<SceneOverride> sizes, rest;
  const bool cameraFromGltf = gltfScene || (!doc.contains("camera") && hasGltfObject(doc));
  for (const SceneOverride& o : overrides)
    (cameraFromGltf && isImageSizePointer(o.pointer) ? sizes : rest).push_back(o);
  if (!gltfScene) applyOverrides(r, doc, rest);
  if (!gltfScene) r.blame(rest);
  {
    Camera check;  // a bad size is refused before any file is read
    applyImageSize(r, sizes, check);
  }
  r.keys(root, {"description", "camera", "materials", "objects", "lights", "projectors", "failure", "paths"});
  if (Node d = r.child(root, "description")) r.string(d);

  fs::path dir = fs::path(path).parent_path();
  Scene scene;
  scene.path = path;
  scene.name = fs::path(path).stem().string();
  for (const SceneOverride& o : overrides) scene.overridesGiven.emplace_back(o.pointer, dumpJson(o.value));
  GltfState gltfState;
  if (gltfScene) gltfState.overrides = rest;
  gltfState.scene = gltfScene;
  // With a glTF object the camera may come from the glTF file (finishGltf).
  if (r.child(root, "camera") || !hasGltfObject(doc)) readCamera(r, root, scene.camera);
  readMaterials(r, root, dir, scene.materials);
  readObjects(r, root, dir, scene, gltfState);
  readLights(r, root, scene);
  readProjectors(r, root, dir, scene);
  if (gltfState.any) finishGltf(r, root, scene, gltfState, gltfScene);
  applyImageSize(r, sizes, scene.camera);
  if (scene.lights.empty() && scene.projectors.empty())
    r.fail("/lights", "the scene has no light and no projector; expected at least one of them");
  readFailure(r, root, scene);
  readPaths(r, root, scene);
  checkComputed(r, scene, cameraFromGltf ? &gltfState : nullptr);
  scene.hash = sceneHash(doc, scene);
  if (gltfState.any) scene.hash = hashHex(fnv1a64(scene.hash.data(), scene.hash.size(), gltfState.hash));
  // The size is in neither document: hash it (a reference of another size is another result).
  if (!sizes.empty()) {
    const int size[2] = {scene.camera.width, scene.camera.height};
    scene.hash = hashHex(fnv1a64(size, sizeof size, fnv1a64(scene.hash.data(), scene.hash.size())));
  }
  return scene;
}

// $SHADOWLAB_HOME: the folder that holds scenes/data when the binary runs away from its source
// tree (scripts/device-bundle.sh's launcher sets it to the unpacked bundle).
std::string bundledScenesDir() { return envOr("SHADOWLAB_HOME", SHADOWLAB_SOURCE_DIR) + "/scenes/data"; }

std::string sharedAssetsDir() {
  std::string shared = envOr("SHADOWLAB_SHARED_DIR", SHADOWLAB_SHARED_DIR);
  std::error_code ec;
  // SHADOWLAB_SHARED_DIR names the shared/ folder (its assets/ inside); accept the assets folder too.
  if (fs::is_directory(fs::path(shared) / "assets", ec)) return (fs::path(shared) / "assets").string();
  return shared;
}

std::vector<std::string> bundledSceneNames() {
  static const std::vector<std::string> kOrder = {"sphere_on_plane", "grazing",     "contact",
                                                  "thin_wall",       "alpha_fence", "projector",
                                                  "bunny",           "long_view",   "stacked_occluders"};
  std::vector<std::string> found;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(bundledScenesDir(), ec))
    if (e.path().extension() == ".json") found.push_back(e.path().stem().string());
  std::vector<std::string> names;
  for (const auto& n : kOrder)
    if (std::find(found.begin(), found.end(), n) != found.end()) names.push_back(n);
  std::sort(found.begin(), found.end());
  for (const auto& n : found)
    if (std::find(kOrder.begin(), kOrder.end(), n) == kOrder.end()) names.push_back(n);
  return names;
}

std::string resolveScenePath(const std::string& nameOrPath) {
  if (nameOrPath.find('/') != std::string::npos) return nameOrPath;
  if (nameOrPath.size() >= 5 && nameOrPath.compare(nameOrPath.size() - 5, 5, ".json") == 0) return nameOrPath;
  if (gltf::isGltfPath(nameOrPath)) return nameOrPath;
  return bundledScenesDir() + "/" + nameOrPath + ".json";
}

}  // namespace shadowlab
