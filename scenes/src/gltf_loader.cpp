// glTF 2.0 -> the structures of scene.h (gltf_loader.h; the mapping table is scenes/FORMAT.md).
// tinygltf parses (buffers from files, data URIs and the GLB chunk); before it runs, this file checks
// the document's value types against a table of the properties it reads (gltf_schema.cpp), the
// required extensions and every buffer URI; while converting, every accessor, buffer view, index and
// node reference is range-checked, so a malformed file is an error naming the file and the JSON
// pointer, never a read past a buffer.
#include "gltf_loader.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <optional>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <sstream>

#include <glm/gtc/quaternion.hpp>
#include "gltf_tinygltf.h"

#include "gltf_schema.h"
#include "image_io.h"
#include "json_util.h"
#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/number_text.h"
#include "shadowlab/scenes/io.h"
#include "shadowlab/scenes/json_reader.h"

namespace shadowlab::gltf {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr int kMaxTextureSide = 16384;
constexpr uint32_t kGlbMagic = 0x46546C67;   // "glTF"
constexpr uint32_t kChunkJson = 0x4E4F534A;  // "JSON"
constexpr uint32_t kChunkBin = 0x004E4942;   // "BIN\0"
// Required extensions that change nothing shadowlab reads, or that it implements.
const std::vector<std::string> kSupportedRequired = {"KHR_lights_punctual", "KHR_texture_transform",
                                                     "KHR_mesh_quantization", "KHR_materials_unlit"};

// "file: warning: what", the GCC style of formatError with "warning" for "error".
std::string warningLine(const std::string& file, const std::string& what) { return file + ": warning: " + what; }

std::string ptrOf(const char* array, size_t i) { return std::string("/") + array + "/" + std::to_string(i); }

// tinygltf takes a document's length as a 32-bit unsigned, and a GLB header holds its length in 32
// bits: nothing larger is a glTF file.
constexpr uint64_t kMaxGltfBytes = 0xFFFFFFFFull;

std::vector<uint8_t> readBytes(const std::string& path) {
  const std::string problem = notARegularFile(path);
  if (!problem.empty()) fail(path, "", "cannot read the glTF file: " + problem + "; expected a .gltf or .glb file");
  std::error_code ec;
  const uint64_t size = fs::file_size(path, ec);
  if (ec) fail(path, "", "cannot read the glTF file: " + ec.message());
  if (size > kMaxGltfBytes)
    fail(path, "",
         "the file holds " + std::to_string(size) +
             " bytes; expected at most 4 GiB (the largest glTF a GLB header "
             "can describe)");
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, "", "cannot open the glTF file: not readable");
  std::vector<uint8_t> bytes(size);
  if (!bytes.empty()) in.read(reinterpret_cast<char*>(bytes.data()), std::streamsize(bytes.size()));
  if (!in) fail(path, "", "cannot read the glTF file");
  return bytes;
}

uint32_t u32(const uint8_t* p) {
  uint32_t v;
  std::memcpy(&v, p, 4);
  return v;
}

// The JSON text and BIN chunk of a GLB container, checked against its header.
struct Container {
  bool binary = false;
  std::string jsonText;
  const uint8_t* bin = nullptr;
  size_t binSize = 0;
};

Container splitContainer(const std::string& file, const std::vector<uint8_t>& bytes) {
  Container c;
  if (bytes.size() < 4 || u32(bytes.data()) != kGlbMagic) {
    c.jsonText.assign(bytes.begin(), bytes.end());
    return c;
  }
  c.binary = true;
  if (bytes.size() < 12)
    fail(file, "", "GLB file of " + std::to_string(bytes.size()) + " bytes; expected a 12-byte header");
  const uint32_t version = u32(bytes.data() + 4), length = u32(bytes.data() + 8);
  if (version == 1) fail(file, "", "glTF 1.0 is not supported; convert to glTF 2.0");
  if (version != 2) fail(file, "", "GLB version " + std::to_string(version) + "; expected 2");
  if (length > bytes.size())
    fail(file, "",
         "the GLB header gives a length of " + std::to_string(length) + " bytes but the file holds " +
             std::to_string(bytes.size()) + "; expected a complete file");
  if (length < 20) fail(file, "", "GLB file without a JSON chunk; expected one after the header");
  const uint32_t jsonLength = u32(bytes.data() + 12), jsonType = u32(bytes.data() + 16);
  if (jsonType != kChunkJson) fail(file, "", "the first GLB chunk is not JSON; expected the JSON chunk first");
  if (uint64_t(jsonLength) + 20 > length)
    fail(file, "",
         "the GLB JSON chunk of " + std::to_string(jsonLength) + " bytes runs past the file's " +
             std::to_string(length) + " bytes");
  c.jsonText.assign(reinterpret_cast<const char*>(bytes.data() + 20), jsonLength);
  const uint64_t next = 20 + ((uint64_t(jsonLength) + 3) & ~uint64_t(3));
  if (next + 8 <= length) {
    const uint32_t binLength = u32(bytes.data() + next), binType = u32(bytes.data() + next + 4);
    if (binType == kChunkBin) {
      if (next + 8 + binLength > length)
        fail(file, "",
             "the GLB BIN chunk of " + std::to_string(binLength) + " bytes runs past the file's " +
                 std::to_string(length) + " bytes");
      c.bin = bytes.data() + next + 8;
      c.binSize = binLength;
    }
  }
  return c;
}

// A GLB container around new JSON text and the old BIN chunk (the document after overrides).
std::vector<uint8_t> packGlb(const std::string& jsonText, const uint8_t* bin, size_t binSize) {
  std::string j = jsonText;
  while (j.size() % 4) j += ' ';
  const size_t binPadded = (binSize + 3) & ~size_t(3);
  const size_t total = 12 + 8 + j.size() + (bin ? 8 + binPadded : 0);
  std::vector<uint8_t> out(total, 0);
  auto put = [&](size_t at, uint32_t v) { std::memcpy(out.data() + at, &v, 4); };
  put(0, kGlbMagic);
  put(4, 2);
  put(8, uint32_t(total));
  put(12, uint32_t(j.size()));
  put(16, kChunkJson);
  std::memcpy(out.data() + 20, j.data(), j.size());
  if (bin) {
    put(20 + j.size(), uint32_t(binPadded));
    put(24 + j.size(), kChunkBin);
    if (binSize) std::memcpy(out.data() + 28 + j.size(), bin, binSize);
  }
  return out;
}

// RFC 3986 percent-decoding of a relative URI reference.
std::string percentDecode(const std::string& s) {
  std::string out;
  for (size_t i = 0; i < s.size(); ++i) {
    if (s[i] == '%' && i + 2 < s.size() && std::isxdigit(static_cast<unsigned char>(s[i + 1])) &&
        std::isxdigit(static_cast<unsigned char>(s[i + 2]))) {
      out += char(std::stoi(s.substr(i + 1, 2), nullptr, 16));
      i += 2;
    } else {
      out += s[i];
    }
  }
  return out;
}

// tinygltf's own decoding of a buffer URI (its copy of dlib's urldecode: '+' is a space, '%' takes
// the next two characters, a non-hex digit counting as 0), so that the file checked is the file it
// opens.
std::string tinygltfDecode(const std::string& s) {
  auto hex = [](unsigned char c) -> int {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return 0;
  };
  std::string out;
  for (size_t i = 0; i < s.size(); ++i) {
    if (s[i] == '+') {
      out += ' ';
    } else if (s[i] == '%' && s.size() > i + 2) {
      out += char(hex(static_cast<unsigned char>(s[i + 1])) << 4 | hex(static_cast<unsigned char>(s[i + 2])));
      i += 2;
    } else {
      out += s[i];
    }
  }
  return out;
}

bool isDataUri(const std::string& uri) { return uri.rfind("data:", 0) == 0; }

// "http:", "file:", ... : a scheme other than data: (nothing but local files and data URIs is read).
bool hasScheme(const std::string& uri) {
  if (uri.empty() || !std::isalpha(static_cast<unsigned char>(uri[0]))) return false;
  for (size_t i = 1; i < uri.size(); ++i) {
    const char c = uri[i];
    if (c == ':') return true;
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '+' || c == '-' || c == '.')) return false;
  }
  return false;
}

// `path` (absolute, or relative to the working folder) lies inside folder `root`: compared component by
// component after both are made canonical (symbolic links and ".." resolved), so "/a/bc" is not inside
// "/a/b" and a link inside the folder that points out of it is outside.
bool insideFolder(const fs::path& path, const fs::path& root) {
  std::error_code ec;
  const fs::path p = fs::weakly_canonical(fs::absolute(path, ec), ec);
  if (ec) return false;
  const fs::path r = fs::weakly_canonical(fs::absolute(root, ec), ec);
  if (ec) return false;
  auto pi = p.begin();
  for (const fs::path& part : r) {
    if (part.empty()) continue;  // the trailing "" of "/a/b/"
    if (pi == p.end() || *pi != part) return false;
    ++pi;
  }
  return true;
}

// The folder SHADOWLAB_ASSET_ROOT names (buffers and images may lie anywhere inside it), or "".
fs::path assetRoot() {
  const char* root = std::getenv("SHADOWLAB_ASSET_ROOT");
  return root && *root ? fs::path(root) : fs::path();
}

// At most `n` characters of a URI for a message: a data: URI can be megabytes long.
std::string uriPrefix(const std::string& uri, size_t n = 48) {
  return uri.size() <= n ? uri : uri.substr(0, n) + "... (" + std::to_string(uri.size()) + " characters)";
}

// The size of what tinygltf's base64 decoder makes of `text`, or -1 when `text` is not base64
// (RFC 4648 alphabet, '=' padding only at the end).
int64_t base64Size(const std::string& text) {
  size_t n = text.size(), pad = 0;
  while (n > 0 && text[n - 1] == '=' && pad < 2) --n, ++pad;
  for (size_t i = 0; i < n; ++i) {
    const unsigned char c = static_cast<unsigned char>(text[i]);
    if (!(std::isalnum(c) || c == '+' || c == '/')) return -1;
  }
  if (n % 4 == 1) return -1;
  return int64_t(n / 4 * 3 + (n % 4 ? n % 4 - 1 : 0));
}

// Every "uri" of buffers and images, before tinygltf reads any: a data: URI that decodes, or a
// local file inside the glTF file's folder (or SHADOWLAB_ASSET_ROOT), after percent-decoding and
// symbolic links. A buffer's file must be a regular file of exactly its byteLength (tinygltf's own
// rule), so a device (/dev/zero) is never read; images are read only when a MASK material needs
// one (alphaImage checks the file then).
void checkUris(const std::string& file, const json& doc, const fs::path& dir) {
  const fs::path root = assetRoot();
  for (const char* array : {"buffers", "images"}) {
    auto it = doc.find(array);
    if (it == doc.end() || !it->is_array()) continue;
    const bool buffer = std::string(array) == "buffers";
    for (size_t i = 0; i < it->size(); ++i) {
      const json& item = (*it)[i];
      if (!item.is_object() || !item.contains("uri") || !item["uri"].is_string()) continue;
      const std::string uri = item["uri"].get<std::string>();
      const std::string ptr = ptrOf(array, i) + "/uri";
      if (isDataUri(uri)) {
        const size_t comma = uri.find(',');
        const std::string header = comma == std::string::npos ? uri : uri.substr(0, comma + 1);
        const std::vector<std::string> headers =
            buffer ? std::vector<std::string>{"data:application/octet-stream;base64,",
                                              "data:application/gltf-buffer;base64,"}
                   : std::vector<std::string>{"data:image/png;base64,", "data:image/jpeg;base64,"};
        if (std::find(headers.begin(), headers.end(), header) == headers.end())
          fail(file, ptr,
               "got a data: URI starting \"" + uriPrefix(header) + "\"; expected one starting " + headers[0] + " or " +
                   headers[1]);
        const int64_t size = base64Size(uri.substr(comma + 1));
        if (size < 0)
          fail(file, ptr,
               "the data: URI \"" + uriPrefix(uri) +
                   "\" is not valid base64; expected the characters A-Z a-z 0-9 + / "
                   "and at most two '=' at the end");
        if (buffer && item.contains("byteLength") && item["byteLength"].is_number_integer() &&
            size != item["byteLength"].get<int64_t>())
          fail(file, ptr,
               "the data: URI decodes to " + std::to_string(size) + " bytes; expected byteLength " +
                   item["byteLength"].dump() + " bytes");
        continue;
      }
      if (hasScheme(uri))
        fail(file, ptr,
             "got the URI \"" + uriPrefix(uri) +
                 "\"; expected a data: URI or a relative file path (nothing is fetched from a network or by file:)");
      const std::string decoded = buffer ? tinygltfDecode(uri) : percentDecode(uri);
      // A NUL would end the path where the C library opens it, not where it was checked.
      if (decoded.find('\0') != std::string::npos)
        fail(file, ptr, "the URI decodes to a path holding a NUL character; expected a file path");
      const fs::path p = (dir / decoded).lexically_normal();
      if (!insideFolder(p, dir) && (root.empty() || !insideFolder(p, root)))
        fail(file, ptr,
             "the URI names " + p.string() + ", outside the glTF file's folder" +
                 (root.empty() ? "" : " and outside SHADOWLAB_ASSET_ROOT (" + root.string() + ")") +
                 "; expected a file inside " + (root.empty() ? "that folder" : "one of them") +
                 " (SHADOWLAB_ASSET_ROOT names another folder to allow)");
      if (!buffer) continue;
      const std::string problem = notARegularFile(p);
      if (!problem.empty())
        fail(file, ptr,
             "buffer file " + p.string() + ": " + problem + "; expected a regular file beside " +
                 fs::path(file).filename().string());
      std::error_code ec;
      const uint64_t size = fs::file_size(p, ec);
      if (!ec && item.contains("byteLength") && item["byteLength"].is_number_integer() &&
          size != item["byteLength"].get<uint64_t>())
        fail(file, ptr,
             "buffer file " + p.string() + " holds " + std::to_string(size) + " bytes; expected byteLength " +
                 item["byteLength"].dump() + " bytes");
    }
  }
}

// A buffer without "uri" is the GLB's BIN chunk (glTF 2.0, "GLB-stored Buffer"): only in a .glb,
// and only when the chunk is there and long enough.
void checkBinChunk(const std::string& file, const json& doc, const Container& c) {
  if (!doc.contains("buffers")) return;
  for (size_t i = 0; i < doc["buffers"].size(); ++i) {
    const json& b = doc["buffers"][i];
    if (b.contains("uri")) continue;
    const std::string ptr = ptrOf("buffers", i);
    if (!c.binary)
      fail(file, ptr,
           "missing key \"uri\"; expected a file path or a data: URI (only a .glb holds a buffer without one, in its "
           "BIN chunk)");
    if (!c.bin || c.binSize == 0)
      fail(file, ptr,
           "the buffer has no uri and the GLB file has no BIN chunk; expected a BIN chunk after the JSON chunk");
    const uint64_t length = b["byteLength"].get<uint64_t>();
    if (length > c.binSize)
      fail(file, ptr + "/byteLength",
           "got " + std::to_string(length) + "; expected at most " + std::to_string(c.binSize) +
               " bytes (the GLB BIN chunk's length)");
  }
}

// tinygltf reads a bufferView image's bytes at &buffer.data[byteOffset] for byteLength while it
// parses, without checking that they lie inside the buffer (a hostile file read past it: a fuzz
// finding, tests/fuzz/regressions/gltf/image_bufferview_past_buffer). The range of every bufferView
// an image names is checked against its buffer's byteLength first; the buffer's bytes are checked
// to be that long (checkBinChunk, the data: URI and file checks). Geometry's bufferViews are read
// by this loader, after tinygltf, with their own checks.
void checkImageBufferViewRanges(const std::string& file, const json& doc) {
  const auto views = doc.find("bufferViews");
  const auto images = doc.find("images");
  if (views == doc.end() || !views->is_array() || images == doc.end() || !images->is_array()) return;
  const auto buffers = doc.find("buffers");
  for (const json& image : *images) {
    const auto named = image.is_object() ? image.find("bufferView") : image.end();
    if (named == image.end() || !named->is_number_unsigned() || named->get<uint64_t>() >= views->size()) continue;
    const size_t i = named->get<size_t>();
    const json& v = (*views)[i];
    if (!v.is_object()) continue;
    const std::string ptr = ptrOf("bufferViews", i);
    auto count = [&](const char* key, bool required) -> std::optional<uint64_t> {
      const auto it = v.find(key);
      if (it == v.end()) {
        if (required) fail(file, ptr, std::string("missing key \"") + key + "\"; expected an integer >= 0");
        return std::nullopt;
      }
      if (!it->is_number_unsigned())
        fail(file, ptr + "/" + key, "got " + detail::describe(*it) + "; expected an integer >= 0");
      return it->get<uint64_t>();
    };
    const uint64_t buffer = *count("buffer", true), length = *count("byteLength", true);
    const uint64_t offset = count("byteOffset", false).value_or(0);
    if (buffers == doc.end() || !buffers->is_array() || buffer >= buffers->size())
      fail(file, ptr + "/buffer",
           "got " + std::to_string(buffer) + "; expected one of the file's " +
               std::to_string(buffers != doc.end() && buffers->is_array() ? buffers->size() : 0) + " buffers");
    const auto size = (*buffers)[buffer].find("byteLength");
    if (size == (*buffers)[buffer].end() || !size->is_number_unsigned()) continue;  // the buffer's own check
    if (offset > size->get<uint64_t>() || length > size->get<uint64_t>() - offset)
      fail(file, ptr,
           "bytes " + std::to_string(offset) + ".." + std::to_string(offset + length) + " of buffer " +
               std::to_string(buffer) + "; expected a range inside its byteLength " +
               std::to_string(size->get<uint64_t>()));
  }
}

void applyOverrides(const std::string& file, json& doc, const std::vector<SceneOverride>& overrides) {
  for (const auto& o : overrides) {
    const std::string place = "override " + o.pointer;
    json::json_pointer ptr;
    try {
      ptr = json::json_pointer(o.pointer);
    } catch (const json::exception&) {
      fail(file, place, "got \"" + o.pointer + "\"; expected a JSON pointer into the glTF document");
    }
    if (ptr.empty()) fail(file, place, "cannot replace the whole document; expected a pointer to a value");
    bool exists = false, parentIsObject = false;
    try {
      exists = doc.contains(ptr);
    } catch (const json::exception&) {
    }
    try {
      const json::json_pointer parent = ptr.parent_pointer();
      parentIsObject = doc.contains(parent) && doc[parent].is_object();
    } catch (const json::exception&) {
    }
    if (!exists && !parentIsObject)
      fail(file, place, "no such value in the glTF document; expected a pointer to an existing value");
    doc[ptr] = o.value;
  }
}

// tinygltf's callbacks: files are read as they are named (no shell expansion of paths), images are
// kept as their encoded bytes and decoded later, only for a MASK material that reads them.
// The folders tinygltf may read from (the callbacks' user data): checkUris has checked every URI,
// and the callbacks check the path tinygltf actually opens again.
struct ReadableFolders {
  fs::path dir, root;
  bool allows(const std::string& path) const {
    return path.find('\0') == std::string::npos &&
           (insideFolder(path, dir) || (!root.empty() && insideFolder(path, root)));
  }
};
bool fileExists(const std::string& path, void* folders) {
  std::error_code ec;
  return static_cast<const ReadableFolders*>(folders)->allows(path) && fs::is_regular_file(path, ec);
}
std::string expandFilePath(const std::string& path, void*) { return path; }
bool readWholeFile(std::vector<unsigned char>* out, std::string* err, const std::string& path, void* folders) {
  std::error_code ec;
  if (!static_cast<const ReadableFolders*>(folders)->allows(path) || !fs::is_regular_file(path, ec) ||
      fs::file_size(path, ec) > kMaxGltfBytes) {
    if (err) *err += "not a regular file of at most 4 GiB inside the glTF file's folder\n";
    return false;
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    if (err) *err += "cannot open " + path + "\n";
    return false;
  }
  out->assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  return true;
}
bool writeWholeFile(std::string* err, const std::string&, const std::vector<unsigned char>&, void*) {
  if (err) *err += "writing is disabled\n";
  return false;
}
bool keepImageBytes(tinygltf::Image* image, const int, std::string*, std::string*, int, int, const unsigned char* bytes,
                    int size, void*) {
  image->image.assign(bytes, bytes + size);
  image->as_is = true;
  return true;
}

// tinygltf's messages, one per line, joined into one.
std::string oneLine(std::string s) {
  while (!s.empty() && (s.back() == '\n' || s.back() == '\r' || s.back() == ' ')) s.pop_back();
  for (size_t p; (p = s.find('\n')) != std::string::npos;) s.replace(p, 1, "; ");
  // tinygltf quotes whole URIs (a data: URI can be megabytes).
  constexpr size_t kMaxText = 240;
  if (s.size() > kMaxText) s = s.substr(0, kMaxText) + "...";
  return s;
}

int componentCount(int type) {
  switch (type) {
    case TINYGLTF_TYPE_SCALAR: return 1;
    case TINYGLTF_TYPE_VEC2: return 2;
    case TINYGLTF_TYPE_VEC3: return 3;
    case TINYGLTF_TYPE_VEC4: return 4;
    case TINYGLTF_TYPE_MAT2: return 4;
    case TINYGLTF_TYPE_MAT3: return 9;
    case TINYGLTF_TYPE_MAT4: return 16;
    default: return 0;
  }
}
const char* typeName(int type) {
  switch (type) {
    case TINYGLTF_TYPE_SCALAR: return "SCALAR";
    case TINYGLTF_TYPE_VEC2: return "VEC2";
    case TINYGLTF_TYPE_VEC3: return "VEC3";
    case TINYGLTF_TYPE_VEC4: return "VEC4";
    case TINYGLTF_TYPE_MAT2: return "MAT2";
    case TINYGLTF_TYPE_MAT3: return "MAT3";
    case TINYGLTF_TYPE_MAT4: return "MAT4";
    default: return "an unknown type";
  }
}
int componentSize(int componentType) {
  switch (componentType) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return 1;
    case TINYGLTF_COMPONENT_TYPE_SHORT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return 2;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
    case TINYGLTF_COMPONENT_TYPE_FLOAT: return 4;
    default: return 0;
  }
}

// One component at `p` as a double: floats as stored, integers normalized to [0, 1] / [-1, 1] when
// the accessor says so (glTF 2.0, 3.11 "Animations" table of normalized types), else as integers.
double component(const uint8_t* p, int componentType, bool normalized) {
  switch (componentType) {
    case TINYGLTF_COMPONENT_TYPE_BYTE: {
      int8_t v;
      std::memcpy(&v, p, 1);
      return normalized ? std::max(double(v) / 127.0, -1.0) : double(v);
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return normalized ? double(*p) / 255.0 : double(*p);
    case TINYGLTF_COMPONENT_TYPE_SHORT: {
      int16_t v;
      std::memcpy(&v, p, 2);
      return normalized ? std::max(double(v) / 32767.0, -1.0) : double(v);
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
      uint16_t v;
      std::memcpy(&v, p, 2);
      return normalized ? double(v) / 65535.0 : double(v);
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
      uint32_t v;
      std::memcpy(&v, p, 4);
      return normalized ? double(v) / 4294967295.0 : double(v);
    }
    default: {
      float v;
      std::memcpy(&v, p, 4);
      return double(v);
    }
  }
}

// extras.shadowlab.<what> of a node (written by exportGlb, scenes/FORMAT.md "Exporting a scene as
// glTF"): nullptr when absent. Untrusted like every other value: each reader below checks types,
// ranges and keys and names the JSON pointer.
const json* shadowlabExtras(const std::string& file, const json& node, size_t index, const char* what) {
  if (!node.is_object() || !node.contains("extras")) return nullptr;
  const json& e = node["extras"];
  if (!e.is_object() || !e.contains("shadowlab")) return nullptr;
  const json& s = e["shadowlab"];
  const std::string ptr = ptrOf("nodes", index) + "/extras/shadowlab";
  if (!s.is_object()) fail(file, ptr, "got " + detail::describe(s) + "; expected an object");
  if (!s.contains(what)) return nullptr;
  const json& w = s[what];
  if (!w.is_object()) fail(file, ptr + "/" + what, "got " + detail::describe(w) + "; expected an object");
  return &w;
}

class ExtrasReader {
 public:
  ExtrasReader(const std::string& file, const json& j, std::string ptr) : file_(file), j_(j), ptr_(std::move(ptr)) {}
  void keys(const std::vector<std::string>& allowed) const {
    for (const auto& item : j_.items())
      if (std::find(allowed.begin(), allowed.end(), item.key()) == allowed.end()) {
        std::string list;
        for (const auto& k : allowed) list += (list.empty() ? "" : ", ") + k;
        fail(file_, ptr_, "unknown key \"" + printableText(item.key()) + "\"; expected one of " + list);
      }
  }
  bool has(const char* key) const { return j_.contains(key); }
  const json& require(const char* key, const std::string& what) const {
    if (!j_.contains(key)) fail(file_, ptr_, std::string("missing key \"") + key + "\"; expected " + what);
    return j_[key];
  }
  // A number that is finite as a float, lo < v < hi (or <= where the bound is inclusive).
  float number(const char* key, double lo, bool loOpen, double hi, bool hiOpen, const std::string& what) const {
    const json& v = require(key, what);
    const double d = v.is_number() ? v.get<double>() : std::nan("");
    const bool ok =
        v.is_number() && std::isfinite(float(d)) && (loOpen ? d > lo : d >= lo) && (hiOpen ? d < hi : d <= hi);
    if (!ok) fail(file_, ptr_ + "/" + key, "got " + detail::describe(v) + "; expected " + what);
    return float(d);
  }
  glm::vec3 vec3(const char* key) const {
    const json& v = require(key, "3 numbers (x, y, z)");
    if (!v.is_array() || v.size() != 3)
      fail(file_, ptr_ + "/" + key, "got " + detail::describe(v) + "; expected 3 numbers (x, y, z)");
    glm::vec3 out;
    for (int k = 0; k < 3; ++k) {
      const json& c = v[size_t(k)];
      if (!c.is_number() || !std::isfinite(float(c.get<double>())))
        fail(file_, ptr_ + "/" + key + "/" + std::to_string(k),
             "got " + detail::describe(c) + "; expected a finite number");
      out[k] = float(c.get<double>());
    }
    return out;
  }
  long long integer(const char* key, long long lo, long long hi, const std::string& what) const {
    const json& v = require(key, what);
    if (!v.is_number_integer() || (v.is_number_unsigned() && v.get<uint64_t>() > uint64_t(hi)) ||
        v.get<long long>() < lo || v.get<long long>() > hi)
      fail(file_, ptr_ + "/" + key, "got " + detail::describe(v) + "; expected " + what);
    return v.get<long long>();
  }
  bool boolean(const char* key) const {
    const json& v = require(key, "true or false");
    if (!v.is_boolean()) fail(file_, ptr_ + "/" + key, "got " + detail::describe(v) + "; expected true or false");
    return v.get<bool>();
  }
  std::string ptr(const char* key) const { return ptr_ + "/" + key; }

 private:
  const std::string& file_;
  const json& j_;
  std::string ptr_;
};

// How far the glTF-standard values (node transforms, yfov, cone angles) may lie from the exact
// shadowlab values in the extras for the extras to be used: the export writes both from the same
// floats, in double, so they agree to ~1e-15; a file an editor has changed since is further off,
// and then the standard values win (with a warning). Relative, or absolute below 1.
constexpr double kExtrasTolerance = 1e-6;
bool near(double a, double b) { return std::abs(a - b) <= kExtrasTolerance * std::max(1.0, std::abs(b)); }
bool near(glm::dvec3 a, glm::dvec3 b) { return glm::length(a - b) <= kExtrasTolerance * std::max(1.0, glm::length(b)); }

class Converter {
 public:
  Converter(const Request& req, const json& doc, const tinygltf::Model& model, std::vector<Material>& materials)
      : req_(req),
        file_(req.path),
        dir_(fs::path(req.path).parent_path()),
        doc_(doc),
        m_(model),
        materials_(materials) {}

  Content run();

 private:
  // Where an accessor is used, for messages: "accessor 3 (POSITION of /meshes/0/primitives/1)".
  std::string accessorPlace(int index, const std::string& use) const {
    return "accessor " + std::to_string(index) + " (" + use + ")";
  }
  [[noreturn]] void accessorFail(int index, const std::string& use, const std::string& what) const {
    fail(file_, ptrOf("accessors", size_t(index)), accessorPlace(index, use) + ": " + what);
  }
  // The bytes [offset, offset + size) of buffer view `view`, range-checked.
  const uint8_t* viewBytes(int view, size_t offset, size_t size, int accessor, const std::string& use) const;
  // An accessor's values as doubles, count x components (sparse substitution applied).
  std::vector<double> readAccessor(int index, const std::string& use, const std::vector<int>& types,
                                   bool indices = false) const;

  struct Decoded {
    std::vector<glm::vec3> positions;
    std::vector<glm::vec2> uvs;  // empty when the material reads no texture
    std::vector<glm::uvec3> triangles;
    uint32_t material = 0;
  };
  const Decoded* decode(size_t mesh, size_t prim);
  uint32_t materialFor(int gltfMaterial, const std::string& use);
  Image alphaImage(int texture, const std::string& ptr, double factorAlpha);
  void checkNodes();
  void emitMesh(size_t mesh, const glm::dmat4& world, size_t node, Content& out);
  void chooseCamera(const std::vector<std::pair<size_t, glm::dmat4>>& cameraNodes, Content& out) const;
  void addLights(const std::vector<std::pair<size_t, glm::dmat4>>& lightNodes, Content& out) const;
  void exactCamera(size_t node, const glm::dmat4& world, int ci, Content& out) const;
  void exactLight(size_t node, const glm::dmat4& world, const json& lj, Light& light, Content& out) const;
  void addPart(size_t node, size_t firstVertex, size_t firstTriangle, Content& out);

  const Request& req_;
  std::string file_;
  fs::path dir_;
  const json& doc_;
  const tinygltf::Model& m_;
  std::vector<Material>& materials_;
  std::map<std::pair<size_t, size_t>, Decoded> decoded_;
  std::map<int, uint32_t> materialIndex_;            // glTF material (-1: the default material) -> scene material
  std::map<int, std::pair<int, glm::dmat3>> uvSet_;  // glTF material -> texcoord set and transform (MASK with texture)
  size_t skippedPrimitives_ = 0;
  std::set<int> blendMaterials_;
  uint64_t triangles_ = 0;
  std::vector<size_t> unmarkedMeshNodes_;  // mesh nodes without extras.shadowlab.object
  std::set<uint32_t> partIds_;
  std::set<std::string> partNames_;
};

const uint8_t* Converter::viewBytes(int view, size_t offset, size_t size, int accessor, const std::string& use) const {
  if (view < 0 || size_t(view) >= m_.bufferViews.size())
    accessorFail(accessor, use,
                 "bufferView " + std::to_string(view) + " is out of range; the file has " +
                     std::to_string(m_.bufferViews.size()) + " buffer views");
  const tinygltf::BufferView& bv = m_.bufferViews[size_t(view)];
  const std::string bvPtr = ptrOf("bufferViews", size_t(view));
  if (bv.buffer < 0 || size_t(bv.buffer) >= m_.buffers.size())
    fail(file_, bvPtr + "/buffer",
         "buffer " + std::to_string(bv.buffer) + " is out of range; the file has " + std::to_string(m_.buffers.size()) +
             " buffers");
  const size_t bufferSize = m_.buffers[size_t(bv.buffer)].data.size();
  if (bv.byteOffset > bufferSize || bv.byteLength > bufferSize - bv.byteOffset)
    fail(file_, bvPtr,
         "buffer view of bytes " + std::to_string(bv.byteOffset) + ".." +
             std::to_string(bv.byteOffset + bv.byteLength) + " runs past buffer " + std::to_string(bv.buffer) +
             ", which holds " + std::to_string(bufferSize) + " bytes");
  if (offset > bv.byteLength || size > bv.byteLength - offset)
    accessorFail(accessor, use,
                 "needs bytes " + std::to_string(offset) + ".." + std::to_string(offset + size) + " of bufferView " +
                     std::to_string(view) + ", which holds " + std::to_string(bv.byteLength) + " bytes");
  return m_.buffers[size_t(bv.buffer)].data.data() + bv.byteOffset + offset;
}

std::vector<double> Converter::readAccessor(int index, const std::string& use, const std::vector<int>& types,
                                            bool indices) const {
  if (index < 0 || size_t(index) >= m_.accessors.size())
    fail(file_, use,
         "accessor " + std::to_string(index) + " is out of range; the file has " + std::to_string(m_.accessors.size()) +
             " accessors");
  const tinygltf::Accessor& a = m_.accessors[size_t(index)];
  if (std::find(types.begin(), types.end(), a.type) == types.end()) {
    std::string list;
    for (int t : types) list += (list.empty() ? "" : " or ") + std::string(typeName(t));
    accessorFail(index, use, std::string("type is ") + typeName(a.type) + "; expected " + list);
  }
  const int csize = componentSize(a.componentType);
  if (csize == 0)
    accessorFail(
        index, use,
        "componentType " + std::to_string(a.componentType) + "; expected one of 5120, 5121, 5122, 5123, 5125, 5126");
  if (indices && a.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
      a.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
      a.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
    accessorFail(index, use,
                 "componentType " + std::to_string(a.componentType) +
                     "; expected an unsigned integer type for indices (5121, 5123 or 5125)");
  if (a.count == 0) accessorFail(index, use, "count is 0; expected at least 1");
  // Without a buffer view the values are zeros (before sparse substitution): nothing in the file
  // bounds the count, so it is limited here.
  constexpr size_t kMaxZeroCount = size_t(1) << 20;
  if (a.count > (size_t(1) << 31) || (a.bufferView < 0 && a.count > kMaxZeroCount))
    accessorFail(index, use, "count " + std::to_string(a.count) + " is too large");
  const int n = componentCount(a.type);
  const size_t elem = size_t(csize) * size_t(n);
  const uint8_t* base = nullptr;
  size_t stride = elem;
  if (a.bufferView >= 0) {
    const tinygltf::BufferView& bvCheck =
        size_t(a.bufferView) < m_.bufferViews.size() ? m_.bufferViews[size_t(a.bufferView)] : tinygltf::BufferView();
    stride = bvCheck.byteStride ? bvCheck.byteStride : elem;
    if (stride < elem)
      fail(file_, ptrOf("bufferViews", size_t(a.bufferView)) + "/byteStride",
           "byteStride " + std::to_string(stride) + " is shorter than the " + std::to_string(elem) +
               "-byte elements of " + accessorPlace(index, use) + "; expected at least " + std::to_string(elem));
    // Checked before anything is allocated: the bytes exist, so the count is bounded by the file.
    base = viewBytes(a.bufferView, a.byteOffset, stride * (a.count - 1) + elem, index, use);
  }
  std::vector<double> out(a.count * size_t(n), 0.0);
  if (base) {
    for (size_t i = 0; i < a.count; ++i)
      for (int c = 0; c < n; ++c)
        out[i * size_t(n) + size_t(c)] =
            component(base + i * stride + size_t(c) * size_t(csize), a.componentType, a.normalized);
  }
  if (a.sparse.isSparse) {
    const size_t count = size_t(a.sparse.count);
    if (a.sparse.count < 1 || count > a.count)
      accessorFail(index, use,
                   "sparse count " + std::to_string(a.sparse.count) + "; expected 1.." + std::to_string(a.count));
    const int ict = a.sparse.indices.componentType;
    const int isize = componentSize(ict);
    if (ict != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE && ict != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
        ict != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
      accessorFail(index, use, "sparse indices componentType " + std::to_string(ict) + "; expected 5121, 5123 or 5125");
    const uint8_t* idx = viewBytes(a.sparse.indices.bufferView, size_t(std::max(0, a.sparse.indices.byteOffset)),
                                   count * size_t(isize), index, use + ", sparse indices");
    const uint8_t* val = viewBytes(a.sparse.values.bufferView, size_t(std::max(0, a.sparse.values.byteOffset)),
                                   count * elem, index, use + ", sparse values");
    double previous = -1;
    for (size_t i = 0; i < count; ++i) {
      const double target = component(idx + i * size_t(isize), ict, false);
      if (target >= double(a.count) || target <= previous)
        accessorFail(index, use,
                     "the sparse index at element " + std::to_string(i) +
                         " is out of order or out of range; expected strictly increasing indices below the count " +
                         std::to_string(a.count));
      previous = target;
      for (int c = 0; c < n; ++c)
        out[size_t(target) * size_t(n) + size_t(c)] =
            component(val + i * elem + size_t(c) * size_t(csize), a.componentType, a.normalized);
    }
  }
  return out;
}

// The KHR_texture_transform of a texture info (glTF's uv' = T * R * S * uv) and its texcoord set.
std::pair<int, glm::dmat3> textureTransform(const std::string& file, const json& info, const std::string& ptr) {
  int set = info.value("texCoord", 0);
  glm::dmat3 m(1.0);
  auto ext = info.find("extensions");
  if (ext != info.end() && ext->contains("KHR_texture_transform")) {
    const json& t = (*ext)["KHR_texture_transform"];
    double ox = 0, oy = 0, rot = 0, sx = 1, sy = 1;
    if (t.contains("offset")) {
      if (t["offset"].size() != 2) fail(file, ptr + "/extensions/KHR_texture_transform/offset", "expected 2 numbers");
      ox = t["offset"][0].get<double>();
      oy = t["offset"][1].get<double>();
    }
    if (t.contains("scale")) {
      if (t["scale"].size() != 2) fail(file, ptr + "/extensions/KHR_texture_transform/scale", "expected 2 numbers");
      sx = t["scale"][0].get<double>();
      sy = t["scale"][1].get<double>();
    }
    if (t.contains("rotation")) rot = t["rotation"].get<double>();
    if (t.contains("texCoord")) set = t["texCoord"].get<int>();
    const double c = std::cos(rot), s = std::sin(rot);
    // Column-major: column k is the image of axis k. T*R*S from the extension's specification.
    const glm::dmat3 T(1, 0, 0, 0, 1, 0, ox, oy, 1);
    const glm::dmat3 R(c, -s, 0, s, c, 0, 0, 0, 1);
    const glm::dmat3 S(sx, 0, 0, 0, sy, 0, 0, 0, 1);
    m = T * R * S;
  }
  return {set, m};
}

// Decodes image bytes through the project's image I/O (which reads files): into a private
// temporary file named for its format.
image_io::FloatImage decodeBytes(const std::string& file, const std::string& ptr,
                                 const std::vector<unsigned char>& bytes, const std::string& mime) {
  std::string ext, kind;
  if (bytes.size() >= 8 && std::memcmp(bytes.data(), "\x89PNG", 4) == 0) ext = ".png", kind = "image/png";
  else if (bytes.size() >= 3 && bytes[0] == 0xFF && bytes[1] == 0xD8 && bytes[2] == 0xFF)
    ext = ".jpg", kind = "image/jpeg";
  const std::string says = mime.empty() ? "no mimeType" : "the mimeType \"" + mime + "\"";
  if (ext.empty()) {
    std::string what = "neither PNG nor JPEG";
    if (bytes.size() >= 6 && (std::memcmp(bytes.data(), "GIF8", 4) == 0)) what = "GIF";
    else if (bytes.size() >= 2 && bytes[0] == 'B' && bytes[1] == 'M') what = "BMP";
    else if (bytes.size() >= 12 && std::memcmp(bytes.data(), "RIFF", 4) == 0 &&
             std::memcmp(bytes.data() + 8, "WEBP", 4) == 0)
      what = "WebP";
    else if (bytes.size() >= 12 && std::memcmp(bytes.data(), "\xABKTX 20\xBB", 8) == 0) what = "KTX2";
    fail(file, ptr,
         "the image's " + std::to_string(bytes.size()) + " bytes are " + what + " (" + says +
             "); expected PNG or JPEG bytes");
  }
  if (!mime.empty() && mime != kind)
    fail(file, ptr + "/mimeType",
         "got \"" + mime + "\" for an image whose bytes are " + kind + "; expected \"" + kind + "\"");
  std::string tmpl = (fs::temp_directory_path() / ("shadowlab-gltf-XXXXXX" + ext)).string();
  std::vector<char> name(tmpl.begin(), tmpl.end());
  name.push_back('\0');
  const int fd = ::mkstemps(name.data(), int(ext.size()));
  if (fd < 0) throw DriverError(formatError(file, ptr, "cannot create a temporary file to decode the image"));
  const std::string path(name.data());
  const ssize_t wrote = ::write(fd, bytes.data(), bytes.size());
  ::close(fd);
  image_io::FloatImage img;
  std::string err = wrote == ssize_t(bytes.size()) ? image_io::readTexture(path, img, kMaxTextureSide)
                                                   : std::string("cannot write a temporary file");
  std::error_code ec;
  fs::remove(path, ec);
  if (!err.empty()) fail(file, ptr, "cannot decode the image: " + err);
  return img;
}

Image Converter::alphaImage(int texture, const std::string& ptr, double factorAlpha) {
  if (texture < 0 || size_t(texture) >= m_.textures.size())
    fail(file_, ptr + "/index",
         "texture " + std::to_string(texture) + " is out of range; the file has " + std::to_string(m_.textures.size()) +
             " textures");
  const int source = m_.textures[size_t(texture)].source;
  const std::string texPtr = ptrOf("textures", size_t(texture));
  if (source < 0 || size_t(source) >= m_.images.size())
    fail(file_, texPtr + "/source",
         "image " + std::to_string(source) + " is out of range; the file has " + std::to_string(m_.images.size()) +
             " images");
  const tinygltf::Image& im = m_.images[size_t(source)];
  const std::string imPtr = ptrOf("images", size_t(source));
  image_io::FloatImage read;
  if (!im.image.empty()) {
    read = decodeBytes(file_, imPtr, im.image, im.mimeType);
  } else if (!im.uri.empty()) {
    if (hasScheme(im.uri) && !isDataUri(im.uri))
      fail(file_, imPtr + "/uri", "got a URI with a scheme; expected a data: URI or a local file");
    const fs::path p = (dir_ / percentDecode(im.uri)).lexically_normal();
    const std::string problem = notARegularFile(p);
    if (!problem.empty())
      fail(file_, imPtr + "/uri", "image file " + p.string() + ": " + problem + "; expected a PNG or JPEG file");
    const std::string err = image_io::readTexture(p.string(), read, kMaxTextureSide);
    if (!err.empty()) fail(file_, imPtr + "/uri", "cannot read image " + p.string() + ": " + err);
  } else {
    fail(file_, imPtr, "image without data; expected a uri or a bufferView");
  }
  if (read.width <= 0 || read.height <= 0 || read.width > kMaxTextureSide || read.height > kMaxTextureSide ||
      read.pixels.size() != size_t(read.width) * size_t(read.height) * read.channels.size())
    fail(file_, imPtr,
         "image is " + std::to_string(read.width) + "x" + std::to_string(read.height) +
             "; expected 1..16384 texels per side");
  // Alpha is the "A" channel (gray+alpha and RGBA images); an image without one is opaque (1).
  int alphaChannel = -1;
  for (size_t c = 0; c < read.channels.size(); ++c)
    if (read.channels[c] == "A") alphaChannel = int(c);
  if (alphaChannel < 0 && (read.channels.size() == 2 || read.channels.size() == 4))
    alphaChannel = int(read.channels.size()) - 1;
  Image a;
  a.width = read.width;
  a.height = read.height;
  a.channels = 1;
  a.pixels.resize(size_t(a.width) * size_t(a.height));
  const size_t nc = read.channels.size();
  for (size_t i = 0; i < a.pixels.size(); ++i) {
    const float texAlpha = alphaChannel < 0 ? 1.0f : read.pixels[i * nc + size_t(alphaChannel)];
    if (!std::isfinite(texAlpha)) fail(file_, imPtr, "image holds a non-finite value; expected finite texels");
    a.pixels[i] = float(factorAlpha) * texAlpha;
  }
  return a;
}

uint32_t Converter::materialFor(int gm, const std::string& use) {
  auto it = materialIndex_.find(gm);
  if (it != materialIndex_.end()) return it->second;
  if (gm >= 0 && size_t(gm) >= m_.materials.size())
    fail(file_, use + "/material",
         "material " + std::to_string(gm) + " is out of range; the file has " + std::to_string(m_.materials.size()) +
             " materials");
  const std::string mPtr = gm >= 0 ? ptrOf("materials", size_t(gm)) : "";
  const json empty = json::object();
  const json& mj = gm >= 0 ? doc_["materials"][size_t(gm)] : empty;
  const std::string alphaMode = mj.value("alphaMode", std::string("OPAQUE"));
  const bool doubleSided = mj.value("doubleSided", false);
  if (alphaMode != "OPAQUE" && alphaMode != "MASK" && alphaMode != "BLEND")
    fail(file_, mPtr + "/alphaMode",
         "got " + detail::describe(mj["alphaMode"]) + "; expected one of OPAQUE, MASK, BLEND");
  if (alphaMode == "BLEND") blendMaterials_.insert(gm);
  glm::dvec4 factor(1.0);
  const json* pbr = mj.contains("pbrMetallicRoughness") ? &mj["pbrMetallicRoughness"] : nullptr;
  if (pbr && pbr->contains("baseColorFactor")) {
    const json& f = (*pbr)["baseColorFactor"];
    if (f.size() != 4)
      fail(file_, mPtr + "/pbrMetallicRoughness/baseColorFactor",
           "got " + detail::describe(f) + "; expected 4 numbers (r, g, b, a)");
    for (int k = 0; k < 4; ++k) {
      factor[k] = f[size_t(k)].get<double>();
      if (factor[k] < 0 || factor[k] > 1)
        fail(file_, mPtr + "/pbrMetallicRoughness/baseColorFactor/" + std::to_string(k),
             "got " + detail::describe(f[size_t(k)]) + "; expected a number 0..1");
    }
  }
  uint32_t index = req_.fallbackMaterial;
  if (alphaMode == "MASK" || !doubleSided) {
    Material mat;
    mat.name = req_.objectName + "/" +
               (gm < 0 ? std::string("default")
                       : (m_.materials[size_t(gm)].name.empty() ? "material" + std::to_string(gm)
                                                                : sanitizeName(m_.materials[size_t(gm)].name)));
    mat.twoSided = doubleSided;
    mat.albedo = glm::vec3(factor);
    if (alphaMode == "MASK") {
      double cutoff = 0.5;
      if (mj.contains("alphaCutoff")) {
        cutoff = mj["alphaCutoff"].get<double>();
        if (!(cutoff >= 0))
          fail(file_, mPtr + "/alphaCutoff", "got " + detail::describe(mj["alphaCutoff"]) + "; expected a number >= 0");
      }
      mat.alphaCutoff = float(cutoff);
      const json* tex = pbr && pbr->contains("baseColorTexture") ? &(*pbr)["baseColorTexture"] : nullptr;
      if (tex) {
        const std::string texPtr = mPtr + "/pbrMetallicRoughness/baseColorTexture";
        if (!tex->contains("index")) fail(file_, texPtr, "missing key \"index\"; expected a texture index");
        mat.alphaTexture = alphaImage((*tex)["index"].get<int>(), texPtr, factor.a);
        uvSet_[gm] = textureTransform(file_, *tex, texPtr);
        mat.hasAlpha = true;
      } else if (factor.a < cutoff) {
        // A constant alpha below the cutoff: every point is a hole (a 1x1 texture at uv 0).
        mat.alphaTexture.width = mat.alphaTexture.height = mat.alphaTexture.channels = 1;
        mat.alphaTexture.pixels = {float(factor.a)};
        mat.hasAlpha = true;
      }
    }
    index = uint32_t(materials_.size());
    materials_.push_back(std::move(mat));
  }
  materialIndex_[gm] = index;
  return index;
}

const Converter::Decoded* Converter::decode(size_t mesh, size_t prim) {
  auto key = std::make_pair(mesh, prim);
  auto it = decoded_.find(key);
  if (it != decoded_.end()) return &it->second;
  const tinygltf::Primitive& p = m_.meshes[mesh].primitives[prim];
  const std::string pPtr = "/meshes/" + std::to_string(mesh) + "/primitives/" + std::to_string(prim);
  Decoded d;
  auto pos = p.attributes.find("POSITION");
  if (pos == p.attributes.end()) fail(file_, pPtr + "/attributes", "no POSITION attribute; expected one");
  const std::vector<double> xyz = readAccessor(pos->second, "POSITION of " + pPtr, {TINYGLTF_TYPE_VEC3});
  const size_t vertexCount = xyz.size() / 3;
  d.positions.resize(vertexCount);
  for (size_t i = 0; i < vertexCount; ++i) {
    const glm::dvec3 v(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
    const glm::vec3 f(v);
    if (!std::isfinite(f.x) || !std::isfinite(f.y) || !std::isfinite(f.z))
      accessorFail(pos->second, "POSITION of " + pPtr,
                   "vertex " + std::to_string(i) + " is not finite as a float; expected finite positions");
    d.positions[i] = f;
  }
  std::vector<uint32_t> idx;
  if (p.indices >= 0) {
    const std::vector<double> raw = readAccessor(p.indices, "indices of " + pPtr, {TINYGLTF_TYPE_SCALAR}, true);
    idx.resize(raw.size());
    for (size_t i = 0; i < raw.size(); ++i) {
      if (raw[i] >= double(vertexCount))
        accessorFail(p.indices, "indices of " + pPtr,
                     "the index at element " + std::to_string(i) + " is out of range; the POSITION accessor has " +
                         std::to_string(vertexCount) + " vertices (expected indices below " +
                         std::to_string(vertexCount) + ")");
      idx[i] = uint32_t(raw[i]);
    }
  } else {
    idx.resize(vertexCount);
    for (size_t i = 0; i < vertexCount; ++i) idx[i] = uint32_t(i);
  }
  const int mode = p.mode < 0 ? TINYGLTF_MODE_TRIANGLES : p.mode;
  const size_t n = idx.size();
  // glTF 2.0 ("Meshes"): a TRIANGLES primitive's count is a multiple of 3; a remainder means a
  // truncated or misdeclared accessor, not a mesh to draw part of.
  if (mode == TINYGLTF_MODE_TRIANGLES && n % 3 != 0) {
    if (p.indices >= 0)
      fail(file_, pPtr + "/indices",
           "accessor " + std::to_string(p.indices) + " holds " + std::to_string(n) +
               " indices for TRIANGLES; expected a multiple of 3");
    fail(file_, pPtr + "/attributes/POSITION",
         "accessor " + std::to_string(pos->second) + " holds " + std::to_string(n) +
             " vertices for TRIANGLES without indices; expected a multiple of 3");
  }
  if (mode == TINYGLTF_MODE_TRIANGLES) {
    for (size_t i = 0; i + 2 < n; i += 3) d.triangles.emplace_back(idx[i], idx[i + 1], idx[i + 2]);
  } else if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
    // glTF 2.0, 3.7.2.1: triangle i is (v_i, v_{i+1+i%2}, v_{i+2-i%2}); restart-style degenerate
    // triangles (a repeated index) are dropped.
    for (size_t i = 0; i + 2 < n; ++i) {
      glm::uvec3 t(idx[i], idx[i + 1 + i % 2], idx[i + 2 - i % 2]);
      if (t.x != t.y && t.y != t.z && t.x != t.z) d.triangles.push_back(t);
    }
  } else {  // fan: (v_{i+1}, v_{i+2}, v_0)
    for (size_t i = 0; i + 2 < n; ++i) {
      glm::uvec3 t(idx[i + 1], idx[i + 2], idx[0]);
      if (t.x != t.y && t.y != t.z && t.x != t.z) d.triangles.push_back(t);
    }
  }
  d.material = materialFor(p.material, pPtr);
  auto uvIt = uvSet_.find(p.material);
  if (uvIt != uvSet_.end() && materials_[d.material].hasAlpha) {
    const std::string attr = "TEXCOORD_" + std::to_string(uvIt->second.first);
    auto tc = p.attributes.find(attr);
    if (tc == p.attributes.end())
      fail(file_, pPtr + "/attributes",
           "no " + attr + " attribute, which the MASK material " + std::to_string(p.material) +
               "'s baseColorTexture reads; expected one");
    const std::vector<double> uv = readAccessor(tc->second, attr + " of " + pPtr, {TINYGLTF_TYPE_VEC2});
    if (uv.size() / 2 != vertexCount)
      accessorFail(tc->second, attr + " of " + pPtr,
                   "count " + std::to_string(uv.size() / 2) + " differs from the POSITION count " +
                       std::to_string(vertexCount) + "; expected one per vertex");
    const glm::dmat3& t = uvIt->second.second;
    d.uvs.resize(vertexCount);
    for (size_t i = 0; i < vertexCount; ++i) {
      const glm::dvec3 u = t * glm::dvec3(uv[2 * i], uv[2 * i + 1], 1.0);
      d.uvs[i] = glm::vec2(u);
      if (!std::isfinite(d.uvs[i].x) || !std::isfinite(d.uvs[i].y))
        accessorFail(tc->second, attr + " of " + pPtr, "texture coordinate " + std::to_string(i) + " is not finite");
    }
  }
  // A constant alpha below the cutoff (no texture): the 1x1 alpha texture is read at uv 0.
  if (d.uvs.empty() && materials_[d.material].hasAlpha) d.uvs.assign(vertexCount, glm::vec2(0));
  return &decoded_.emplace(key, std::move(d)).first->second;
}

void Converter::emitMesh(size_t mesh, const glm::dmat4& world, size_t node, Content& out) {
  const tinygltf::Mesh& me = m_.meshes[mesh];
  for (size_t p = 0; p < me.primitives.size(); ++p) {
    const int mode = me.primitives[p].mode < 0 ? TINYGLTF_MODE_TRIANGLES : me.primitives[p].mode;
    if (mode < TINYGLTF_MODE_TRIANGLES) {
      if (mode < 0 || mode > 6)
        fail(file_, "/meshes/" + std::to_string(mesh) + "/primitives/" + std::to_string(p) + "/mode",
             "got " + std::to_string(mode) + "; expected 0..6");
      ++skippedPrimitives_;
      continue;
    }
    if (mode > TINYGLTF_MODE_TRIANGLE_FAN)
      fail(file_, "/meshes/" + std::to_string(mesh) + "/primitives/" + std::to_string(p) + "/mode",
           "got " + std::to_string(mode) + "; expected 0..6");
    const Decoded* d = decode(mesh, p);
    triangles_ += d->triangles.size();
    if (triangles_ > req_.triangleBudget)
      fail(file_, "/nodes/" + std::to_string(node),
           "the scene reaches " + std::to_string(triangles_) + " triangles with this node; expected at most " +
               std::to_string(req_.triangleBudget) + " " + req_.budgetWhy);
    const uint32_t base = uint32_t(out.positions.size());
    for (const glm::vec3& v : d->positions) {
      const glm::vec3 w(world * glm::dvec4(glm::dvec3(v), 1.0));
      if (!std::isfinite(w.x) || !std::isfinite(w.y) || !std::isfinite(w.z))
        fail(file_, "/nodes/" + std::to_string(node),
             "the node's transform makes a vertex non-finite; expected a finite transform");
      out.positions.push_back(w);
    }
    if (!d->uvs.empty() && out.uvs.size() < base) out.uvs.resize(base, glm::vec2(0));
    if (!out.uvs.empty() || !d->uvs.empty()) {
      if (d->uvs.empty()) out.uvs.resize(out.positions.size(), glm::vec2(0));
      else out.uvs.insert(out.uvs.end(), d->uvs.begin(), d->uvs.end());
    }
    // glTF 2.0 ("Transformations"): a world transform with a negative determinant mirrors the mesh,
    // which turns its counter-clockwise front faces clockwise; reversing the winding keeps them front
    // faces for both renderers' culling.
    const bool mirrored = glm::determinant(glm::dmat3(world)) < 0;
    for (const glm::uvec3& t : d->triangles)
      out.triangles.push_back((mirrored ? glm::uvec3(t.x, t.z, t.y) : t) + glm::uvec3(base));
    out.triangleMaterial.insert(out.triangleMaterial.end(), d->triangles.size(), d->material);
  }
}

glm::dmat4 localMatrix(const tinygltf::Node& n) {
  if (n.matrix.size() == 16) {
    glm::dmat4 m;
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r) m[c][r] = n.matrix[size_t(c * 4 + r)];
    return m;
  }
  glm::dmat4 t(1.0), r(1.0), s(1.0);
  if (n.translation.size() == 3) t[3] = glm::dvec4(n.translation[0], n.translation[1], n.translation[2], 1.0);
  if (n.rotation.size() == 4) {
    glm::dquat q(n.rotation[3], n.rotation[0], n.rotation[1], n.rotation[2]);  // glTF stores x, y, z, w
    const double len = glm::length(q);
    if (len > 0) r = glm::mat4_cast(q / len);
  }
  if (n.scale.size() == 3) s = glm::scale(glm::dmat4(1.0), glm::dvec3(n.scale[0], n.scale[1], n.scale[2]));
  return t * r * s;
}

void Converter::checkNodes() {
  const size_t count = m_.nodes.size();
  std::vector<int> parent(count, -1);
  for (size_t i = 0; i < count; ++i) {
    const tinygltf::Node& n = m_.nodes[i];
    const std::string ptr = ptrOf("nodes", i);
    if (n.matrix.size() != 0 && n.matrix.size() != 16)
      fail(file_, ptr + "/matrix", "got " + std::to_string(n.matrix.size()) + " numbers; expected 16");
    if (n.mesh >= 0 && size_t(n.mesh) >= m_.meshes.size())
      fail(file_, ptr + "/mesh",
           "mesh " + std::to_string(n.mesh) + " is out of range; the file has " + std::to_string(m_.meshes.size()) +
               " meshes");
    if (n.camera >= 0 && size_t(n.camera) >= m_.cameras.size())
      fail(file_, ptr + "/camera",
           "camera " + std::to_string(n.camera) + " is out of range; the file has " +
               std::to_string(m_.cameras.size()) + " cameras");
    for (size_t k = 0; k < n.children.size(); ++k) {
      const int c = n.children[k];
      const std::string cPtr = ptr + "/children/" + std::to_string(k);
      if (c < 0 || size_t(c) >= count)
        fail(file_, cPtr,
             "node " + std::to_string(c) + " is out of range; the file has " + std::to_string(count) + " nodes");
      if (size_t(c) == i)
        fail(file_, cPtr, "node " + std::to_string(i) + " is its own child; expected a tree of nodes");
      if (parent[size_t(c)] >= 0)
        fail(file_, cPtr,
             "node " + std::to_string(c) + " is a child of nodes " + std::to_string(parent[size_t(c)]) + " and " +
                 std::to_string(i) + "; expected each node to have at most one parent");
      parent[size_t(c)] = int(i);
    }
  }
  // With one parent each, a cycle is a chain of parents that comes back to its start.
  std::vector<int> state(count, 0);  // 0 unvisited, 1 on the current chain, 2 known to reach a root
  for (size_t start = 0; start < count; ++start) {
    std::vector<size_t> chain;
    for (size_t cur = start;;) {
      if (state[cur] == 2) break;
      if (state[cur] == 1) {
        // The chain came back to `cur`: the nodes from it on form the cycle, listed parent first.
        std::vector<size_t> cycle(std::find(chain.begin(), chain.end(), cur), chain.end());
        std::reverse(cycle.begin(), cycle.end());
        std::string text;
        for (size_t k : cycle) text += "/nodes/" + std::to_string(k) + " -> ";
        text += "/nodes/" + std::to_string(cycle.front());
        fail(file_, "/nodes/" + std::to_string(cycle.front()) + "/children",
             "the nodes form a cycle: " + text + "; expected a tree of nodes");
      }
      state[cur] = 1;
      chain.push_back(cur);
      if (parent[cur] < 0) break;
      cur = size_t(parent[cur]);
    }
    for (size_t k : chain) state[k] = 2;
  }
}

// The camera at its node: at the node's origin, looking down its -Z with its +Y up.
void placeCamera(const std::string& file, const std::string& ptr, const glm::dmat4& world, Camera& cam);

Camera cameraFromNode(const std::string& file, const tinygltf::Camera& c, size_t index, const glm::dmat4& world,
                      bool& infiniteFar) {
  const std::string ptr = ptrOf("cameras", index);
  if (c.type != "perspective" && c.type != "orthographic")
    fail(file, ptr + "/type",
         "camera " + std::to_string(index) + (c.name.empty() ? "" : " (\"" + c.name + "\")") + " is \"" + c.type +
             "\"; expected perspective or orthographic");
  Camera cam;
  if (c.type == "orthographic") {
    // glTF 2.0: xmag, ymag the half extents of the view (world units), znear >= 0, zfar > znear
    // (required). The image is 640 wide and 640 ymag / xmag high, so its aspect is the view's.
    const auto& o = c.orthographic;
    if (!(o.xmag > 0) || !std::isfinite(o.xmag))
      fail(file, ptr + "/orthographic/xmag", "got " + numberText(o.xmag) + "; expected a positive number");
    if (!(o.ymag > 0) || !std::isfinite(o.ymag))
      fail(file, ptr + "/orthographic/ymag", "got " + numberText(o.ymag) + "; expected a positive number");
    if (!(o.znear >= 0))
      fail(file, ptr + "/orthographic/znear", "got " + numberText(o.znear) + "; expected a number >= 0");
    if (!(o.zfar > o.znear) || !std::isfinite(o.zfar))
      fail(file, ptr + "/orthographic/zfar", "got " + numberText(o.zfar) + "; expected zfar > znear");
    const double h = std::round(640.0 * o.ymag / o.xmag);
    if (!(h >= 1 && h <= 16384))
      fail(file, ptr + "/orthographic/ymag",
           "gives a 640 x " + numberText(h) + " image (ymag / xmag); expected 1..16384 rows");
    cam.projection = Projection::Orthographic;
    cam.orthoHeight = float(2.0 * o.ymag);
    cam.width = 640;
    cam.height = int(h);
    cam.nearPlane = float(o.znear);
    cam.farPlane = float(o.zfar);
    infiniteFar = false;
    placeCamera(file, ptr, world, cam);
    return cam;
  }
  const auto& p = c.perspective;
  if (!(p.yfov > 0 && p.yfov < kPi))
    fail(file, ptr + "/perspective/yfov", "got " + numberText(p.yfov) + "; expected 0 < yfov < pi radians");
  if (!(p.znear > 0))
    fail(file, ptr + "/perspective/znear", "got " + numberText(p.znear) + "; expected a positive number");
  if (p.zfar != 0 && !(p.zfar > p.znear))
    fail(file, ptr + "/perspective/zfar", "got " + numberText(p.zfar) + "; expected zfar > znear");
  cam.vfovDeg = float(p.yfov * 180.0 / kPi);
  cam.width = 640;
  cam.height = 480;
  if (p.aspectRatio > 0) {
    const double h = std::round(640.0 / p.aspectRatio);
    if (!(h >= 1 && h <= 16384))
      fail(file, ptr + "/perspective/aspectRatio", "gives a 640 x " + numberText(h) + " image; expected 1..16384 rows");
    cam.height = int(h);
  }
  cam.nearPlane = float(p.znear);
  infiniteFar = p.zfar == 0;
  cam.farPlane = infiniteFar ? float(p.znear) * 2 : float(p.zfar);
  placeCamera(file, ptr, world, cam);
  return cam;
}

void placeCamera(const std::string& file, const std::string& ptr, const glm::dmat4& world, Camera& cam) {
  const glm::dvec3 pos(world * glm::dvec4(0, 0, 0, 1));
  const glm::dvec3 fwd = glm::dmat3(world) * glm::dvec3(0, 0, -1), up = glm::dmat3(world) * glm::dvec3(0, 1, 0);
  if (!(glm::length(fwd) > 1e-12) || !(glm::length(up) > 1e-12) ||
      glm::length(glm::cross(glm::normalize(fwd), glm::normalize(up))) < 1e-4)
    fail(file, ptr, "the camera's node transform is degenerate (zero scale); expected a camera that looks somewhere");
  cam.position = glm::vec3(pos);
  cam.lookAt = glm::vec3(pos + glm::normalize(fwd));
  cam.up = glm::vec3(glm::normalize(up));
}

// The exact camera of extras.shadowlab.camera on the camera's node, where it agrees with the node's
// transform and the glTF camera (kExtrasTolerance): its position, look_at, up, field of view (or
// orthographic height), image size and planes replace what the node gives, bit for bit.
void Converter::exactCamera(size_t node, const glm::dmat4& world, int ci, Content& out) const {
  const json* e = shadowlabExtras(file_, doc_["nodes"][node], node, "camera");
  if (!e) return;
  const tinygltf::Camera& gc = m_.cameras[size_t(ci)];
  const bool ortho = gc.type == "orthographic";
  const ExtrasReader x(file_, *e, ptrOf("nodes", node) + "/extras/shadowlab/camera");
  x.keys({"position", "look_at", "up", "width", "height", "near", "far", ortho ? "ortho_height" : "vfov_deg"});
  Camera k = out.camera;
  k.position = x.vec3("position");
  k.lookAt = x.vec3("look_at");
  k.up = x.vec3("up");
  k.width = int(x.integer("width", 1, 16384, "an integer 1..16384 (pixels)"));
  k.height = int(x.integer("height", 1, 16384, "an integer 1..16384 (pixels)"));
  k.nearPlane = x.number("near", 0, !ortho, 1e30, false, ortho ? "a number >= 0" : "a positive number");
  k.farPlane = x.number("far", double(k.nearPlane), true, 1e30, false, "a number above near");
  if (ortho) k.orthoHeight = x.number("ortho_height", 0, true, 1e30, false, "a positive height (world units)");
  else k.vfovDeg = x.number("vfov_deg", 0, true, 180, true, "a field of view in degrees, 0 < vfov_deg < 180");
  const glm::dvec3 view = glm::dvec3(k.lookAt) - glm::dvec3(k.position);
  if (!(glm::length(view) > 0))
    fail(file_, x.ptr("look_at"), "got the camera's own position; expected a point away from it");
  const glm::dvec3 forward = glm::normalize(view);
  const glm::dvec3 side = glm::cross(forward, glm::dvec3(k.up));
  if (!(glm::length(side) > 1e-12))
    fail(file_, x.ptr("up"), "parallel to the view direction; expected an up vector not parallel to it");
  const glm::dvec3 trueUp = glm::cross(glm::normalize(side), forward);
  // What the node and the glTF camera say (placeCamera's reading of the node).
  const glm::dvec3 nodePos(world * glm::dvec4(0, 0, 0, 1));
  const glm::dvec3 nodeFwd = glm::normalize(glm::dmat3(world) * glm::dvec3(0, 0, -1));
  const glm::dvec3 nodeUp = glm::normalize(glm::dmat3(world) * glm::dvec3(0, 1, 0));
  const double aspect = double(k.width) / double(k.height);
  std::string off;
  if (!near(glm::dvec3(k.position), nodePos)) off = "position";
  else if (!near(forward, nodeFwd)) off = "view direction";
  else if (!near(trueUp, nodeUp)) off = "up";
  else if (ortho && (!near(0.5 * double(k.orthoHeight), gc.orthographic.ymag) ||
                     !near(0.5 * double(k.orthoHeight) * aspect, gc.orthographic.xmag)))
    off = "xmag, ymag";
  else if (!ortho && !near(double(k.vfovDeg) * kPi / 180.0, gc.perspective.yfov)) off = "yfov";
  else if (!ortho && gc.perspective.aspectRatio > 0 && !near(aspect, gc.perspective.aspectRatio)) off = "aspectRatio";
  else if (!near(double(k.nearPlane), ortho ? gc.orthographic.znear : gc.perspective.znear) ||
           !near(double(k.farPlane), ortho ? gc.orthographic.zfar : gc.perspective.zfar))
    off = "znear, zfar";
  if (!off.empty()) {
    out.warnings.push_back(warningLine(file_, ptrOf("nodes", node) + "/extras/shadowlab/camera: its " + off +
                                                  " differs from the glTF camera's; the glTF camera is used"));
    return;
  }
  out.camera = k;
  out.infiniteFar = false;
  out.cameraExact = true;
}

// The exact light of extras.shadowlab.light on a light's node: near plane and size (which
// KHR_lights_punctual has no field for) always; direction, position and cone where they agree with
// the node and the light (kExtrasTolerance).
void Converter::exactLight(size_t node, const glm::dmat4& world, const json& lj, Light& light, Content& out) const {
  out.lightExact.push_back(false);
  out.lightRadiusPtr.emplace_back();
  const json* e = shadowlabExtras(file_, doc_["nodes"][node], node, "light");
  if (!e) return;
  const ExtrasReader x(file_, *e, ptrOf("nodes", node) + "/extras/shadowlab/light");
  const bool directional = light.type == LightType::Directional;
  if (directional) x.keys({"direction", "angular_diameter_deg"});
  else if (light.type == LightType::Spot) x.keys({"direction", "position", "near", "radius", "cone_deg"});
  else x.keys({"direction", "position", "near", "radius"});
  if (directional) {
    if (x.has("angular_diameter_deg"))
      light.angularDiameterDeg = x.number("angular_diameter_deg", 0, false, kMaxAngularDiameterDeg, false,
                                          "an angle in degrees 0.." + std::to_string(int(kMaxAngularDiameterDeg)));
  } else {
    if (x.has("near")) light.nearPlane = x.number("near", 0, true, 1e30, false, "a positive number");
    if (x.has("radius")) {
      light.radius = x.number("radius", 0, false, 1e30, false, "a radius 0..1e30 (a sphere light; 0: a hard light)");
      if (light.radius > 0) out.lightRadiusPtr.back() = x.ptr("radius");
    }
  }
  Light k = light;
  k.direction = x.vec3("direction");
  const double len = glm::length(glm::dvec3(k.direction));
  if (!(std::abs(len - 1.0) <= 1e-5))
    fail(file_, x.ptr("direction"), "has length " + numberText(len) + "; expected a unit vector");
  std::string off;
  if (!near(glm::dvec3(k.direction), glm::dvec3(light.direction))) off = "direction";
  if (!directional) {
    k.position = x.vec3("position");
    if (off.empty() && !near(glm::dvec3(k.position), glm::dvec3(world * glm::dvec4(0, 0, 0, 1)))) off = "position";
  }
  if (light.type == LightType::Spot) {
    k.coneDeg = x.number("cone_deg", 0, true, 180, true, "a cone angle in degrees, 0 < cone_deg < 180");
    const double outer = lj.contains("spot") && lj["spot"].contains("outerConeAngle")
                             ? lj["spot"]["outerConeAngle"].get<double>()
                             : kPi / 4;
    if (off.empty() && !near(double(k.coneDeg) * 0.5 * kPi / 180.0, outer)) off = "cone_deg";
  }
  if (!off.empty()) {
    out.warnings.push_back(warningLine(file_, ptrOf("nodes", node) + "/extras/shadowlab/light: its " + off +
                                                  " differs from the glTF light's; the glTF light's is used"));
    return;
  }
  light = k;
  out.lightExact.back() = true;
}

void Converter::chooseCamera(const std::vector<std::pair<size_t, glm::dmat4>>& cameraNodes, Content& out) const {
  int want = req_.cameraIndex;
  if (!req_.cameraName.empty()) {
    for (size_t i = 0; i < m_.cameras.size() && want < 0; ++i)
      if (m_.cameras[i].name == req_.cameraName) want = int(i);
    if (want < 0) {
      std::string list;
      for (size_t i = 0; i < m_.cameras.size(); ++i)
        list +=
            (list.empty() ? "" : ", ") + (m_.cameras[i].name.empty() ? "(unnamed)" : "\"" + m_.cameras[i].name + "\"");
      throw InputError(formatError(req_.requestFile, req_.requestPtr,
                                   "no camera named \"" + req_.cameraName + "\" in " + file_ + "; expected one of " +
                                       (list.empty() ? "none (the file has no camera)" : list)));
    }
  } else if (want >= 0 && size_t(want) >= m_.cameras.size()) {
    throw InputError(formatError(req_.requestFile, req_.requestPtr,
                                 "camera " + std::to_string(want) + " is out of range; " + file_ + " has " +
                                     std::to_string(m_.cameras.size()) + " cameras"));
  }
  // Without a choice: the first perspective camera a node places, else the first orthographic one.
  for (const char* type : {"perspective", "orthographic"})
    for (const auto& [node, world] : cameraNodes) {
      const int ci = m_.nodes[node].camera;
      if (want >= 0 ? ci != want : m_.cameras[size_t(ci)].type != type) continue;
      out.camera = cameraFromNode(file_, m_.cameras[size_t(ci)], size_t(ci), world, out.infiniteFar);
      exactCamera(node, world, ci, out);
      out.hasCamera = true;
      out.cameraIndex = ci;
      return;
    }
  if (want >= 0)
    throw InputError(formatError(req_.requestFile, req_.requestPtr,
                                 "camera " + std::to_string(want) + " of " + file_ +
                                     " is not placed by any node of the glTF scene; expected a camera a node uses"));
  if (!cameraNodes.empty())
    out.warnings.push_back(warningLine(file_,
                                       "no perspective or orthographic camera; the scene takes the JSON camera or a "
                                       "framing one"));
}

void Converter::addLights(const std::vector<std::pair<size_t, glm::dmat4>>& lightNodes, Content& out) const {
  const json* lights = nullptr;
  if (doc_.contains("extensions") && doc_["extensions"].contains("KHR_lights_punctual") &&
      doc_["extensions"]["KHR_lights_punctual"].contains("lights"))
    lights = &doc_["extensions"]["KHR_lights_punctual"]["lights"];
  std::set<std::string> names;
  for (const auto& [node, world] : lightNodes) {
    const std::string lPtr = "/nodes/" + std::to_string(node) + "/extensions/KHR_lights_punctual/light";
    const json& ref = doc_["nodes"][node]["extensions"]["KHR_lights_punctual"];
    if (!ref.contains("light")) fail(file_, lPtr, "missing; expected a KHR_lights_punctual light index");
    const int li = ref["light"].get<int>();
    if (!lights || li < 0 || size_t(li) >= lights->size())
      fail(file_, lPtr,
           "light " + std::to_string(li) + " is out of range; the file has " +
               std::to_string(lights ? lights->size() : 0) + " KHR_lights_punctual lights");
    const json& lj = (*lights)[size_t(li)];
    const std::string ptr = "/extensions/KHR_lights_punctual/lights/" + std::to_string(li);
    if (!lj.contains("type")) fail(file_, ptr, "missing key \"type\"; expected one of directional, point, spot");
    const std::string type = lj["type"].get<std::string>();
    Light light;
    if (type == "directional") light.type = LightType::Directional;
    else if (type == "spot") light.type = LightType::Spot;
    else if (type == "point") light.type = LightType::Point;
    else
      fail(file_, ptr + "/type", "got " + detail::describe(lj["type"]) + "; expected one of directional, point, spot");
    const glm::dvec3 dir = glm::dmat3(world) * glm::dvec3(0, 0, -1);
    const glm::dvec3 pos(world * glm::dvec4(0, 0, 0, 1));
    if (!(glm::length(dir) > 1e-12) || !std::isfinite(glm::length(dir)) || !std::isfinite(glm::length(pos)))
      fail(file_, "/nodes/" + std::to_string(node),
           "the light's node transform is degenerate; expected a finite, non-zero transform");
    // The light looks down its node's -Z; scale does not change where it points.
    light.direction = glm::vec3(glm::normalize(dir));
    light.position = glm::vec3(pos);
    if (light.type == LightType::Spot) {
      double outer = kPi / 4;
      if (lj.contains("spot") && lj["spot"].contains("outerConeAngle"))
        outer = lj["spot"]["outerConeAngle"].get<double>();
      if (!(outer > 0 && outer < kPi / 2))
        fail(file_, ptr + "/spot/outerConeAngle",
             "got " + std::to_string(outer) +
                 "; expected 0 < outerConeAngle < pi/2 (a spot's shadow map needs a cone under 180 degrees)");
      light.coneDeg = float(2.0 * outer * 180.0 / kPi);
    }
    std::string base = lj.contains("name") ? sanitizeName(lj["name"].get<std::string>()) : "";
    if (base.empty()) base = type == "directional" ? "sun" : type;
    std::string name = base;
    for (int k = 2; !names.insert(name).second; ++k) name = base + "_" + std::to_string(k);
    light.name = name;
    exactLight(node, world, lj, light, out);
    out.lights.push_back(light);
  }
}

// A mesh node's extras.shadowlab.object: the triangles it just emitted are that shadowlab object.
void Converter::addPart(size_t node, size_t firstVertex, size_t firstTriangle, Content& out) {
  const json* e = shadowlabExtras(file_, doc_["nodes"][node], node, "object");
  if (!e) {
    unmarkedMeshNodes_.push_back(node);
    return;
  }
  const ExtrasReader x(file_, *e, ptrOf("nodes", node) + "/extras/shadowlab/object");
  x.keys({"id", "casts_shadow"});
  Part p;
  p.id = uint32_t(x.integer("id", 1, (1ll << 24) - 1, "an object id 1..16777215 (ids travel through float channels)"));
  if (!partIds_.insert(p.id).second)
    fail(file_, x.ptr("id"),
         "object id " + std::to_string(p.id) + " is already used by another node; expected a unique id");
  if (x.has("casts_shadow")) p.castsShadow = x.boolean("casts_shadow");
  p.name = sanitizeName(m_.nodes[node].name);
  if (p.name.empty()) p.name = "object" + std::to_string(p.id);
  if (!partNames_.insert(p.name).second)
    fail(file_, ptrOf("nodes", node) + "/name",
         "object name \"" + p.name + "\" is already used by another node; expected a unique name (it names outputs)");
  p.firstVertex = firstVertex;
  p.vertexCount = out.positions.size() - firstVertex;
  p.firstTriangle = firstTriangle;
  p.triangleCount = out.triangles.size() - firstTriangle;
  out.parts.push_back(std::move(p));
}

Content Converter::run() {
  Content out;
  checkNodes();
  // The glTF scene: the request's, else the file's "scene", else scene 0; a file without scenes
  // shows every root node.
  std::vector<int> roots;
  int sceneIndex = req_.sceneIndex >= 0 ? req_.sceneIndex : (m_.defaultScene >= 0 ? m_.defaultScene : 0);
  if (req_.sceneIndex >= 0 && size_t(req_.sceneIndex) >= m_.scenes.size())
    throw InputError(formatError(req_.requestFile, req_.requestPtr,
                                 "scene " + std::to_string(req_.sceneIndex) + " is out of range; " + file_ + " has " +
                                     std::to_string(m_.scenes.size()) + " scenes"));
  if (m_.scenes.empty()) {
    std::vector<bool> child(m_.nodes.size(), false);
    for (const auto& n : m_.nodes)
      for (int c : n.children) child[size_t(c)] = true;
    for (size_t i = 0; i < m_.nodes.size(); ++i)
      if (!child[i]) roots.push_back(int(i));
  } else {
    if (size_t(sceneIndex) >= m_.scenes.size())
      fail(file_, "/scene",
           "scene " + std::to_string(sceneIndex) + " is out of range; the file has " +
               std::to_string(m_.scenes.size()) + " scenes");
    roots = m_.scenes[size_t(sceneIndex)].nodes;
    for (size_t k = 0; k < roots.size(); ++k)
      if (roots[k] < 0 || size_t(roots[k]) >= m_.nodes.size())
        fail(file_, "/scenes/" + std::to_string(sceneIndex) + "/nodes/" + std::to_string(k),
             "node " + std::to_string(roots[k]) + " is out of range; the file has " + std::to_string(m_.nodes.size()) +
                 " nodes");
  }
  std::vector<std::pair<size_t, glm::dmat4>> cameraNodes, lightNodes;
  // Depth first, children in order (an explicit stack: a long chain of nodes is no recursion).
  std::vector<std::pair<size_t, glm::dmat4>> stack;
  for (auto r = roots.rbegin(); r != roots.rend(); ++r) stack.emplace_back(size_t(*r), glm::dmat4(1.0));
  std::vector<bool> seen(m_.nodes.size(), false);
  while (!stack.empty()) {
    auto [node, parentWorld] = stack.back();
    stack.pop_back();
    if (seen[node])
      fail(file_, "/nodes/" + std::to_string(node),
           "node " + std::to_string(node) + " is reached twice from the scene's roots; expected a tree of nodes");
    seen[node] = true;
    const tinygltf::Node& n = m_.nodes[node];
    const glm::dmat4 world = parentWorld * localMatrix(n);
    if (n.mesh >= 0) {
      const size_t firstVertex = out.positions.size(), firstTriangle = out.triangles.size();
      emitMesh(size_t(n.mesh), world, node, out);
      addPart(node, firstVertex, firstTriangle, out);
    }
    if (n.camera >= 0) cameraNodes.emplace_back(node, world);
    const json& nj = doc_["nodes"][node];
    if (nj.contains("extensions") && nj["extensions"].contains("KHR_lights_punctual"))
      lightNodes.emplace_back(node, world);
    for (auto c = n.children.rbegin(); c != n.children.rend(); ++c) stack.emplace_back(size_t(*c), world);
  }
  auto warning = [&](const std::string& what) { out.warnings.push_back(warningLine(file_, what)); };
  if (skippedPrimitives_)
    warning("skipped " + std::to_string(skippedPrimitives_) + " POINTS/LINES primitive" +
            (skippedPrimitives_ == 1 ? "" : "s") + " (only triangles cast and receive shadows)");
  if (!blendMaterials_.empty())
    warning(std::to_string(blendMaterials_.size()) + " material" + (blendMaterials_.size() == 1 ? "" : "s") +
            " with alphaMode BLEND drawn as OPAQUE (a shadow map has no partial coverage)");
  if (out.triangles.empty())
    fail(file_, "/meshes",
         "the glTF scene has no triangle" + std::string(skippedPrimitives_ ? " (only POINTS/LINES primitives)" : "") +
             "; expected at least one");
  // Objects come from the nodes only when every mesh node says which object it is.
  if (!out.parts.empty() && !unmarkedMeshNodes_.empty())
    fail(file_, ptrOf("nodes", unmarkedMeshNodes_.front()),
         "a mesh node without extras.shadowlab.object where other mesh nodes have one; expected it on every mesh node "
         "or on none");
  chooseCamera(cameraNodes, out);
  addLights(lightNodes, out);
  return out;
}

}  // namespace

bool isGltfPath(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return ext == ".gltf" || ext == ".glb";
}

std::string sanitizeName(const std::string& name) {
  std::string out;
  for (char c : name) out += (std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-') ? c : '_';
  return out;
}

Camera framingCamera(glm::vec3 boundsMin, glm::vec3 boundsMax) {
  const glm::dvec3 lo(boundsMin), hi(boundsMax);
  const glm::dvec3 center = (lo + hi) * 0.5;
  const double radius = std::max(glm::length(hi - lo) * 0.5, 1e-3);
  Camera cam;
  cam.vfovDeg = 45.0f;
  cam.width = 640;
  cam.height = 480;
  const double distance = radius / std::sin(22.5 * kPi / 180.0) / 0.9;
  const glm::dvec3 dir = glm::normalize(glm::dvec3(0.6, 0.5, 1.0));
  cam.position = glm::vec3(center + dir * distance);
  cam.lookAt = glm::vec3(center);
  cam.up = glm::vec3(0, 1, 0);
  cam.nearPlane = float(std::max((distance - radius) * 0.5, distance * 1e-4));
  cam.farPlane = float((distance + radius) * 2.0);
  return cam;
}

std::string notARegularFile(const fs::path& path) {
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  switch (st.type()) {
    case fs::file_type::regular: return "";
    case fs::file_type::not_found: return "not found";
    case fs::file_type::directory: return "a directory, not a file";
    case fs::file_type::character: return "a character device, not a regular file";
    case fs::file_type::block: return "a block device, not a regular file";
    case fs::file_type::fifo: return "a FIFO, not a regular file";
    case fs::file_type::socket: return "a socket, not a regular file";
    default: return ec ? "not accessible (" + ec.message() + ")" : "not a regular file";
  }
}

namespace {

Content loadFile(const Request& req, std::vector<Material>& materials) {
  const std::string& file = req.path;
  const std::vector<uint8_t> bytes = readBytes(file);
  Container c = splitContainer(file, bytes);
  json doc;
  try {
    // The project's one JSON reader: a syntax error at its line:col (of the JSON chunk in a .glb),
    // a number too large for a double or a key given twice refused with its place, and never the
    // file's bytes echoed (it may not be glTF at all).
    doc = parseJsonText(c.jsonText, file);
  } catch (const InputError& e) {
    const std::string what = e.what();
    const auto at = what.find(": error: ");
    if (at == std::string::npos) throw;
    throw InputError(what.substr(0, at) + ": error: not a glTF file: invalid " + (c.binary ? "JSON chunk (" : "JSON (") +
                     what.substr(at + 9) + "); expected a glTF 2.0 .gltf (JSON) or .glb file");
  }
  if (!doc.is_object()) fail(file, "", "got " + detail::describe(doc) + "; expected a glTF JSON object");
  // glTF 1.0: asset.version "1.x", or objects where 2.0 has arrays.
  {
    std::string version;
    if (doc.contains("asset") && doc["asset"].is_object() && doc["asset"].contains("version") &&
        doc["asset"]["version"].is_string())
      version = doc["asset"]["version"].get<std::string>();
    const bool v1 = version.rfind("1", 0) == 0 || (doc.contains("meshes") && doc["meshes"].is_object()) ||
                    (doc.contains("nodes") && doc["nodes"].is_object());
    if (v1) fail(file, "/asset/version", "glTF 1.0 is not supported; convert to glTF 2.0");
  }
  applyOverrides(file, doc, req.overrides);
  checkSchema(file, doc);
  checkRules(file, doc);
  if (doc.contains("extensionsRequired"))
    for (size_t i = 0; i < doc["extensionsRequired"].size(); ++i) {
      const std::string e = doc["extensionsRequired"][i].get<std::string>();
      if (std::find(kSupportedRequired.begin(), kSupportedRequired.end(), e) == kSupportedRequired.end()) {
        std::string list;
        for (const auto& s : kSupportedRequired) list += (list.empty() ? "" : ", ") + s;
        fail(file, "/extensionsRequired/" + std::to_string(i),
             "the file requires the extension " + e + ", which shadowlab does not support; expected only " + list);
      }
    }
  const fs::path dir = fs::path(file).parent_path();
  checkUris(file, doc, dir.empty() ? fs::path(".") : dir);
  checkBinChunk(file, doc, c);
  checkImageBufferViewRanges(file, doc);
  const std::string jsonText = req.overrides.empty() ? c.jsonText : doc.dump();

  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(&keepImageBytes, nullptr);
  const ReadableFolders folders{dir.empty() ? fs::path(".") : dir, assetRoot()};
  tinygltf::FsCallbacks callbacks{&fileExists, &expandFilePath, &readWholeFile, &writeWholeFile,
                                  const_cast<ReadableFolders*>(&folders)};
  loader.SetFsCallbacks(callbacks);
  tinygltf::Model model;
  std::string err, warn;
  bool ok;
  const std::string base = dir.empty() ? std::string(".") : dir.string();
  if (c.binary) {
    std::vector<uint8_t> packed;
    const uint8_t* data = bytes.data();
    size_t size = bytes.size();
    if (!req.overrides.empty()) {
      packed = packGlb(jsonText, c.bin, c.binSize);
      data = packed.data();
      size = packed.size();
    }
    ok = loader.LoadBinaryFromMemory(&model, &err, &warn, data, unsigned(size), base);
  } else {
    ok = loader.LoadASCIIFromString(&model, &err, &warn, jsonText.data(), unsigned(jsonText.size()), base);
  }
  if (!ok || !err.empty()) fail(file, "", "cannot read glTF: " + oneLine(err.empty() ? warn : err));

  Converter conv(req, doc, model, materials);
  Content out = conv.run();
  // The document decides lights, cameras and materials; geometry and textures are hashed by the
  // scene (loader.cpp's sceneHash).
  const std::string canonical = doc.dump();
  out.hash = fnv1a64(canonical.data(), canonical.size());
  return out;
}

}  // namespace

Content load(const Request& req, std::vector<Material>& materials) {
  try {
    return loadFile(req, materials);
  } catch (const InputError& e) {
    // An error at or below a value an override put into the document is the override's fault:
    // name where it came from first (as loader.cpp does for JSON scenes), the file and place after.
    const std::string msg = e.what(), prefix = printableText(req.path) + ": ";
    const size_t sep = msg.find(": error: ", prefix.size());
    if (msg.rfind(prefix, 0) != 0 || sep == std::string::npos) throw;
    const std::string place = msg.substr(prefix.size(), sep - prefix.size());
    const std::string what = msg.substr(sep + 9);
    for (const SceneOverride& o : req.overrides) {
      if (o.origin.empty()) continue;
      const bool blamed =
          place == "override " + o.pointer || place == o.pointer || place.rfind(o.pointer + "/", 0) == 0;
      if (blamed) throw InputError(formatError(o.origin, "", what + " (" + req.path + ": " + place + ")"));
    }
    throw;
  }
}

}  // namespace shadowlab::gltf
