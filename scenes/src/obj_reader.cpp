// OBJ line checks (obj_reader.h). One table of the statements an OBJ file may hold and what each
// takes; every line is checked against it with its line number.
#include "obj_reader.h"

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>

#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/io.h"

namespace shadowlab::obj {

namespace fs = std::filesystem;

namespace {

enum class Args {
  Numbers,   // numbers; `counts` has bit k set when k numbers are allowed
  Corners,   // vertex references: at least `minCorners`, each of a form in `forms`
  Names,     // at least `minCorners` names
  Smooth,    // "off" or a smoothing group number
  Ignored,   // display and rendering attributes: no effect on geometry
  FreeForm,  // free-form curves and surfaces: refused (nothing would be drawn)
};

// Corner forms: v, v/vt, v//vn, v/vt/vn.
constexpr unsigned kV = 1, kVVt = 2, kVVn = 4, kVVtVn = 8;

struct Statement {
  const char* keyword;
  Args args;
  unsigned counts;    // Numbers: allowed counts as bits; Corners: allowed forms
  size_t minCorners;  // Corners, Names: the fewest
  const char* expected;
};

// Every statement of the OBJ format (Wavefront's "Object Files (.obj)" appendix) and how it is read.
constexpr Statement kStatements[] = {
    {"v", Args::Numbers, (1u << 3) | (1u << 4) | (1u << 6), 0, "3 numbers (x y z), 4 (x y z w) or 6 (x y z r g b)"},
    {"vt", Args::Numbers, (1u << 1) | (1u << 2) | (1u << 3), 0, "1 to 3 numbers (u v w)"},
    {"vn", Args::Numbers, 1u << 3, 0, "3 numbers (x y z)"},
    {"vp", Args::Numbers, (1u << 1) | (1u << 2) | (1u << 3), 0, "1 to 3 numbers (u v w)"},
    {"f", Args::Corners, kV | kVVt | kVVn | kVVtVn, 3, "at least 3 corners, each v, v/vt, v//vn or v/vt/vn"},
    {"l", Args::Corners, kV | kVVt, 2, "at least 2 corners, each v or v/vt"},
    {"p", Args::Corners, kV, 1, "at least 1 vertex index"},
    {"o", Args::Names, 0, 0, "an object name"},
    {"g", Args::Names, 0, 0, "group names"},
    {"usemtl", Args::Names, 0, 0, "a material name (none: the object's material)"},
    {"mtllib", Args::Names, 0, 1, "MTL file names"},
    {"s", Args::Smooth, 0, 0, "off or a smoothing group number"},
    {"mg", Args::Ignored, 0, 0, ""},
    {"bevel", Args::Ignored, 0, 0, ""},
    {"c_interp", Args::Ignored, 0, 0, ""},
    {"d_interp", Args::Ignored, 0, 0, ""},
    {"lod", Args::Ignored, 0, 0, ""},
    {"maplib", Args::Ignored, 0, 0, ""},
    {"usemap", Args::Ignored, 0, 0, ""},
    {"shadow_obj", Args::Ignored, 0, 0, ""},
    {"trace_obj", Args::Ignored, 0, 0, ""},
    {"ctech", Args::Ignored, 0, 0, ""},
    {"stech", Args::Ignored, 0, 0, ""},
    {"cstype", Args::FreeForm, 0, 0, ""},
    {"deg", Args::FreeForm, 0, 0, ""},
    {"bmat", Args::FreeForm, 0, 0, ""},
    {"step", Args::FreeForm, 0, 0, ""},
    {"curv", Args::FreeForm, 0, 0, ""},
    {"curv2", Args::FreeForm, 0, 0, ""},
    {"surf", Args::FreeForm, 0, 0, ""},
    {"parm", Args::FreeForm, 0, 0, ""},
    {"trim", Args::FreeForm, 0, 0, ""},
    {"hole", Args::FreeForm, 0, 0, ""},
    {"scrv", Args::FreeForm, 0, 0, ""},
    {"sp", Args::FreeForm, 0, 0, ""},
    {"end", Args::FreeForm, 0, 0, ""},
    {"con", Args::FreeForm, 0, 0, ""},
};

const Statement* findStatement(const std::string& keyword) {
  for (const auto& s : kStatements)
    if (keyword == s.keyword) return &s;
  return nullptr;
}

std::string statementList() {
  std::string list;
  for (const auto& s : kStatements)
    if (s.args != Args::FreeForm && s.args != Args::Ignored)
      list += (list.empty() ? "" : ", ") + std::string(s.keyword);
  return list;
}

bool isSpace(char c) { return c == ' ' || c == '\t' || c == '\v' || c == '\f'; }

std::vector<std::string> splitTokens(const std::string& line) {
  std::vector<std::string> out;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && isSpace(line[i])) ++i;
    size_t start = i;
    while (i < line.size() && !isSpace(line[i])) ++i;
    if (i > start) out.push_back(line.substr(start, i - start));
  }
  return out;
}

// A decimal number as OBJ writers write it: [+-] digits [. digits] [e [+-] digits] (or .digits).
bool decimalNumber(const std::string& t) {
  size_t i = 0;
  if (i < t.size() && (t[i] == '+' || t[i] == '-')) ++i;
  size_t digits = 0;
  while (i < t.size() && std::isdigit(static_cast<unsigned char>(t[i]))) ++i, ++digits;
  if (i < t.size() && t[i] == '.') {
    ++i;
    while (i < t.size() && std::isdigit(static_cast<unsigned char>(t[i]))) ++i, ++digits;
  }
  if (digits == 0) return false;
  if (i < t.size() && (t[i] == 'e' || t[i] == 'E')) {
    ++i;
    if (i < t.size() && (t[i] == '+' || t[i] == '-')) ++i;
    size_t exponent = 0;
    while (i < t.size() && std::isdigit(static_cast<unsigned char>(t[i]))) ++i, ++exponent;
    if (exponent == 0) return false;
  }
  return i == t.size();
}

// A non-empty run of digits with an optional sign; out-of-range magnitudes saturate.
bool integer(const std::string& t, long long& value) {
  size_t i = 0;
  bool negative = false;
  if (i < t.size() && (t[i] == '+' || t[i] == '-')) negative = t[i++] == '-';
  if (i == t.size()) return false;
  long long v = 0;
  for (; i < t.size(); ++i) {
    if (!std::isdigit(static_cast<unsigned char>(t[i]))) return false;
    v = v > (std::numeric_limits<long long>::max() - 9) / 10 ? std::numeric_limits<long long>::max() / 2
                                                             : v * 10 + (t[i] - '0');
  }
  value = negative ? -v : v;
  return true;
}

struct Counts {
  long long v = 0, vt = 0, vn = 0;
};

const char* kindName(int k) { return k == 0 ? "vertex" : (k == 1 ? "texture coordinate" : "normal"); }
const char* kindKeyword(int k) { return k == 0 ? "v" : (k == 1 ? "vt" : "vn"); }

}  // namespace

void objError(const std::string& path, int line, const std::string& what) {
  throw InputError(formatError(line > 0 ? path + ":" + std::to_string(line) : path, "", what));
}

ObjText scanObj(const std::string& path) {
  std::string bytes = readFile(path);
  // Encodings tinyobjloader would read as an empty mesh.
  auto startsWith = [&](const char* bom, size_t n) { return bytes.size() >= n && bytes.compare(0, n, bom, n) == 0; };
  if (startsWith("\xFF\xFE", 2) || startsWith("\xFE\xFF", 2))
    objError(path, 0,
             std::string("the file starts with the UTF-16 byte order mark ") +
                 (bytes[0] == '\xFF' ? "FF FE" : "FE FF") + "; UTF-16 is not supported, expected ASCII or UTF-8 text");
  if (startsWith("\xEF\xBB\xBF", 3)) bytes.erase(0, 3);
  if (bytes.size() >= 2 && (bytes[0] == '\0') != (bytes[1] == '\0'))
    objError(path, 0,
             "every other byte of the file is zero, as in UTF-16 text without a byte order mark; UTF-16 is not "
             "supported, expected ASCII or UTF-8 text");

  // Lines end in LF, CR LF or a lone CR (as tinyobjloader reads them).
  std::vector<std::string> lines;
  {
    size_t start = 0;
    for (size_t i = 0; i <= bytes.size(); ++i) {
      if (i == bytes.size()) {
        if (i > start) lines.push_back(bytes.substr(start));
        break;
      }
      if (bytes[i] == '\n' || bytes[i] == '\r') {
        lines.push_back(bytes.substr(start, i - start));
        if (bytes[i] == '\r' && i + 1 < bytes.size() && bytes[i + 1] == '\n') ++i;
        start = i + 1;
      }
    }
  }

  // Totals first: a positive index may refer to a vertex written further down (tinyobjloader
  // resolves it), a negative one counts back from the line it is on.
  Counts total;
  for (const auto& line : lines) {
    const std::vector<std::string> t = splitTokens(line);
    if (t.empty()) continue;
    if (t[0] == "v") ++total.v;
    else if (t[0] == "vt") ++total.vt;
    else if (t[0] == "vn") ++total.vn;
  }

  ObjText out;
  out.text.reserve(bytes.size());
  Counts sofar;
  size_t points = 0, polylines = 0;
  const fs::path dir = fs::path(path).parent_path();
  for (size_t n = 0; n < lines.size(); ++n) {
    const int lineNo = int(n) + 1;
    std::string line = lines[n];
    if (line.find('\0') != std::string::npos) objError(path, lineNo, "a NUL byte; expected text (ASCII or UTF-8)");
    std::vector<std::string> t = splitTokens(line);
    if (t.empty() || t[0][0] == '#') {
      out.text += line + "\n";
      continue;
    }
    if (!line.empty() && line.back() == '\\')
      objError(path, lineNo,
               "a line continued on the next (\"\\\" at its end); expected each statement on one line (tinyobjloader "
               "does not join lines)");
    const Statement* s = findStatement(t[0]);
    if (!s)
      objError(path, lineNo,
               "unknown statement \"" + t[0] + "\"; expected one of " + statementList() + " or a # comment");
    if (s->args == Args::FreeForm)
      objError(path, lineNo,
               "free-form geometry (\"" + t[0] + "\") is not supported; expected polygonal faces (\"f\" lines)");
    // Geometry statements may end in a comment; names (usemtl, o, g) may hold a '#'.
    const bool geometry = s->args == Args::Numbers || s->args == Args::Corners;
    if (geometry) {
      for (size_t k = 1; k < t.size(); ++k)
        if (t[k][0] == '#') {
          t.resize(k);
          break;
        }
      line = t[0];
      for (size_t k = 1; k < t.size(); ++k) line += " " + t[k];
    }
    const size_t args = t.size() - 1;
    const std::string quoted = "\"" + t[0] + "\" line";
    switch (s->args) {
      case Args::Numbers: {
        for (size_t k = 1; k < t.size(); ++k) {
          const double value = std::strtod(t[k].c_str(), nullptr);
          // Values become floats: 1e39 is a finite double but an infinite float. Underflow gives a
          // tiny or zero value, harmless here.
          if (!decimalNumber(t[k]) || !std::isfinite(value))
            objError(path, lineNo, quoted + " has \"" + t[k] + "\"; expected finite numbers");
          if (std::fabs(value) > double(std::numeric_limits<float>::max()))
            objError(
                path, lineNo,
                quoted + " has \"" + t[k] + "\"; expected finite numbers (magnitude below 3.4e38, the float range)");
        }
        if (args >= 32 || !(s->counts & (1u << args)))
          objError(path, lineNo,
                   quoted + " has " + std::to_string(args) + (args == 1 ? " number" : " numbers") + "; expected " +
                       s->expected);
        if (t[0] == "v") ++sofar.v;
        else if (t[0] == "vt") ++sofar.vt;
        else if (t[0] == "vn") ++sofar.vn;
        break;
      }
      case Args::Corners: {
        if (args < s->minCorners)
          objError(path, lineNo,
                   quoted + " has " +
                       (args == 0 ? std::string("no corners")
                                  : std::to_string(args) + (args == 1 ? " corner" : " corners")) +
                       "; expected " + s->expected);
        for (size_t k = 1; k < t.size(); ++k) {
          // Split at '/': 1, 2 or 3 parts, the middle one possibly empty (v//vn).
          std::vector<std::string> parts;
          size_t start = 0;
          for (size_t slash; (slash = t[k].find('/', start)) != std::string::npos; start = slash + 1)
            parts.push_back(t[k].substr(start, slash - start));
          parts.push_back(t[k].substr(start));
          unsigned form = 0;
          if (parts.size() == 1) form = kV;
          else if (parts.size() == 2) form = kVVt;
          else if (parts.size() == 3) form = parts[1].empty() ? kVVn : kVVtVn;
          long long index[3] = {0, 0, 0};
          bool ok = form != 0 && (s->counts & form);
          for (size_t p = 0; ok && p < parts.size(); ++p)
            ok = (p == 1 && parts[p].empty() && form == kVVn) || integer(parts[p], index[p]);
          if (!ok)
            objError(path, lineNo, quoted + " has corner \"" + t[k] + "\"; expected " + s->expected + " (integers)");
          const long long sofarOf[3] = {sofar.v, sofar.vt, sofar.vn}, totalOf[3] = {total.v, total.vt, total.vn};
          for (int kind = 0; kind < 3; ++kind) {
            if (size_t(kind) >= parts.size() || parts[size_t(kind)].empty()) continue;
            const long long i = index[kind];
            const std::string what = quoted + " has " + kindName(kind) + " index " + std::to_string(i) + "; expected ";
            const std::string count =
                std::to_string(totalOf[kind]) + " \"" + kindKeyword(kind) + "\" line" + (totalOf[kind] == 1 ? "" : "s");
            if (totalOf[kind] == 0)
              objError(path, lineNo, what + "none: the file has no \"" + kindKeyword(kind) + "\" lines");
            if (i == 0)
              objError(path, lineNo, what + "1.." + std::to_string(totalOf[kind]) + " (OBJ indices start at 1)");
            if (i > totalOf[kind])
              objError(path, lineNo, what + "1.." + std::to_string(totalOf[kind]) + " (the file has " + count + ")");
            if (i < 0 && -i > sofarOf[kind])
              objError(path, lineNo,
                       what +
                           (sofarOf[kind] > 0 ? "-" + std::to_string(sofarOf[kind]) + "..-1 (" : "a positive index (") +
                           std::to_string(sofarOf[kind]) + " \"" + kindKeyword(kind) + "\" lines come before it)");
          }
        }
        if (t[0] == "f") {
          out.faceLine.push_back(lineNo);
          out.faceCorners.push_back(uint32_t(args));
        } else if (t[0] == "p") {
          ++points;
        } else {
          ++polylines;
        }
        break;
      }
      case Args::Names: {
        if (args < s->minCorners) objError(path, lineNo, quoted + " has no name; expected " + s->expected);
        if (t[0] == "mtllib") {
          // tinyobjloader's split: at spaces, "\ " keeps one in a name.
          const std::string rest = line.substr(line.find("mtllib") + 6);
          std::string name;
          bool escaping = false;
          auto check = [&]() {
            if (name.empty()) return;
            const fs::path mtl = (dir / name).lexically_normal();
            std::error_code ec;
            if (!fs::is_regular_file(mtl, ec))
              objError(
                  path, lineNo,
                  "MTL file " + mtl.string() + " not found; expected an MTL file (named relative to the OBJ file)");
            name.clear();
          };
          for (char c : rest) {
            if (escaping) escaping = false;
            else if (c == '\\') {
              escaping = true;
              continue;
            } else if (c == ' ' || c == '\t') {
              check();
              continue;
            }
            name += c;
          }
          check();
        }
        break;
      }
      case Args::Smooth: {
        long long group = 0;
        if (args != 1 || (t[1] != "off" && !(integer(t[1], group) && group >= 0)))
          objError(path, lineNo,
                   quoted + " has " + (args == 1 ? "\"" + t[1] + "\"" : std::to_string(args) + " values") +
                       "; expected " + s->expected);
        break;
      }
      case Args::Ignored:
      case Args::FreeForm: break;
    }
    out.text += line + "\n";
  }
  if (out.faceLine.empty()) {
    if (points + polylines > 0)
      objError(path, 0,
               "the file has only points and lines (" + std::to_string(points) + " \"p\" and " +
                   std::to_string(polylines) + " \"l\" lines), which cast no shadow; expected faces (\"f\" lines)");
    objError(path, 0, "the file has no faces; expected at least one \"f\" line");
  }
  return out;
}

}  // namespace shadowlab::obj
