// Technique files without a GPU: the checks that name file:line:column before glslang sees the
// text (technique.h), the declarations and the content hash.
#include "shadowlab/scenes/technique.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <regex>

#include "json_util.h"
#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/io.h"
#include "shadowlab/scenes/method.h"

namespace shadowlab {
namespace {

// Without a declared range a number may be anything the shader's float holds comfortably.
constexpr double kUnbounded = 1e30;
const char* const kDeclarationSyntax = "// shadowlab: key <name> <float|int|bool> <default> [range <lo>..<hi>]";
const char* const kMomentsSyntax = "// shadowlab: moments <vsm|evsm2|evsm4|msm>";
// The names through which a file reads the moments (raster/METHODS.md "Your own technique"), and
// resolve.frag's own name for the image, which a file without a moments line may not read either.
const char* const kMomentNames = R"(\b(mapMoments|momentsMap|moments|momentKeys|momentBias)\b)";

// "vsm, evsm2, evsm4, msm": the filters whose moments a file may ask for (kinds.h's rows).
std::string momentFilterKeys() {
  std::string s;
  for (const auto& k : filterKinds())
    if (isMomentFilter(k.kind)) s += (s.empty() ? "" : ", ") + std::string(k.key);
  return s;
}

[[noreturn]] void failAt(const std::string& path, size_t line, size_t column, const std::string& what) {
  throw InputError(path + ":" + std::to_string(line) + ":" + std::to_string(column) + ": error: " + what);
}

// The 1-based line and column of byte `offset` (0-based).
void place(const std::string& text, size_t offset, size_t& line, size_t& column) {
  detail::lineColumn(text, offset + 1, line, column);
}

// The first byte that is not UTF-8 (or a NUL, which no text file holds): its offset, or npos.
size_t firstNonUtf8(const std::string& s) {
  const auto* b = reinterpret_cast<const unsigned char*>(s.data());
  const size_t n = s.size();
  for (size_t i = 0; i < n;) {
    const unsigned c = b[i];
    if (c == 0) return i;
    if (c < 0x80) {
      ++i;
      continue;
    }
    size_t len = 0;
    unsigned minCode = 0, code = 0;
    if ((c & 0xE0) == 0xC0) len = 2, minCode = 0x80, code = c & 0x1F;
    else if ((c & 0xF0) == 0xE0) len = 3, minCode = 0x800, code = c & 0x0F;
    else if ((c & 0xF8) == 0xF0) len = 4, minCode = 0x10000, code = c & 0x07;
    else return i;
    if (i + len > n) return i;
    for (size_t k = 1; k < len; ++k) {
      if ((b[i + k] & 0xC0) != 0x80) return i;
      code = (code << 6) | (b[i + k] & 0x3F);
    }
    if (code < minCode || code > 0x10FFFF || (code >= 0xD800 && code <= 0xDFFF)) return i;
    i += len;
  }
  return std::string::npos;
}

// The text with every comment replaced by spaces (newlines kept), so offsets and lines stay.
std::string withoutComments(const std::string& s) {
  std::string out = s;
  for (size_t i = 0; i < out.size(); ++i) {
    if (out[i] == '/' && i + 1 < out.size() && out[i + 1] == '/') {
      while (i < out.size() && out[i] != '\n') out[i++] = ' ';
    } else if (out[i] == '/' && i + 1 < out.size() && out[i + 1] == '*') {
      out[i] = out[i + 1] = ' ';
      i += 2;
      while (i < out.size() && !(out[i] == '*' && i + 1 < out.size() && out[i + 1] == '/')) {
        if (out[i] != '\n') out[i] = ' ';
        ++i;
      }
      if (i < out.size()) out[i] = out[i + 1] = ' ', ++i;
    }
  }
  return out;
}

bool parseNumber(const std::string& text, TechniqueParam::Type type, double& out) {
  if (type == TechniqueParam::Type::Bool) {
    if (text == "true" || text == "1") return out = 1, true;
    if (text == "false" || text == "0") return out = 0, true;
    return false;
  }
  if (text.empty()) return false;
  for (char c : text)
    if (!(std::isdigit(static_cast<unsigned char>(c)) || c == '.' || c == '-' || c == '+' || c == 'e' || c == 'E'))
      return false;
  errno = 0;
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (errno != 0 || end != text.c_str() + text.size() || !std::isfinite(v)) return false;
  if (type == TechniqueParam::Type::Int && (std::floor(v) != v || std::fabs(v) > 2147483647.0)) return false;
  out = v;
  return true;
}

const char* typeName(TechniqueParam::Type t) {
  return t == TechniqueParam::Type::Float ? "float" : t == TechniqueParam::Type::Int ? "int" : "bool";
}

// The whitespace-separated words of a "// shadowlab: ..." line and their offsets in the file
// (`rest` starts at byte `offset`).
struct Token {
  std::string text;
  size_t offset;
};
std::vector<Token> declarationTokens(const std::string& rest, size_t offset) {
  std::vector<Token> tokens;
  for (size_t i = 0; i < rest.size();) {
    if (std::isspace(static_cast<unsigned char>(rest[i]))) {
      ++i;
      continue;
    }
    size_t j = i;
    while (j < rest.size() && !std::isspace(static_cast<unsigned char>(rest[j]))) ++j;
    tokens.push_back({rest.substr(i, j - i), offset + i});
    i = j;
  }
  return tokens;
}

// One "// shadowlab: ..." line (`rest` starts at byte `offset` of the file).
TechniqueParam parseDeclaration(const TechniqueFile& f, const std::string& rest, size_t offset,
                                const std::vector<TechniqueParam>& seen) {
  const std::vector<Token> tokens = declarationTokens(rest, offset);
  size_t line = 0, column = 0;
  auto fail = [&](size_t at, const std::string& what) {
    place(f.source, at, line, column);
    failAt(f.path, line, column, what);
  };
  if (tokens.empty()) fail(offset, "an empty shadowlab: line; expected " + std::string(kDeclarationSyntax));
  if (tokens[0].text != "key")
    fail(tokens[0].offset, "got \"" + tokens[0].text + "\"; expected key (" + kDeclarationSyntax + ") or moments (" +
                               kMomentsSyntax + ")");
  if (tokens.size() < 4)
    fail(tokens.back().offset, "an incomplete declaration; expected " + std::string(kDeclarationSyntax));
  TechniqueParam p;
  p.name = tokens[1].text;
  place(f.source, tokens[0].offset, line, column);
  p.line = int(line);
  static const std::regex identifier("[a-z_][a-z0-9_]*");
  if (!std::regex_match(p.name, identifier) || p.name.size() > 48)
    fail(tokens[1].offset, "key name \"" + p.name + "\"; expected lowercase letters, digits and _ (a GLSL identifier)");
  if (p.name == "hash") fail(tokens[1].offset, "key name \"hash\" is the harness's (technique.hash); expected another");
  for (const TechniqueParam& s : seen)
    if (s.name == p.name)
      fail(tokens[1].offset, "key \"" + p.name + "\" declared twice (first on line " + std::to_string(s.line) + ")");
  const std::string& type = tokens[2].text;
  if (type == "float") p.type = TechniqueParam::Type::Float;
  else if (type == "int") p.type = TechniqueParam::Type::Int;
  else if (type == "bool") p.type = TechniqueParam::Type::Bool;
  else fail(tokens[2].offset, "type \"" + type + "\"; expected float, int or bool");
  if (!parseNumber(tokens[3].text, p.type, p.defaultValue))
    fail(tokens[3].offset, "default \"" + tokens[3].text + "\"; expected " +
                               (p.type == TechniqueParam::Type::Bool  ? std::string("true or false")
                                : p.type == TechniqueParam::Type::Int ? std::string("an integer")
                                                                      : std::string("a finite number")));
  p.lo = p.type == TechniqueParam::Type::Bool ? 0 : -kUnbounded;
  p.hi = p.type == TechniqueParam::Type::Bool ? 1 : kUnbounded;
  if (tokens.size() > 4) {
    if (tokens[4].text != "range" || tokens.size() < 6 || p.type == TechniqueParam::Type::Bool)
      fail(tokens[4].offset,
           "got \"" + tokens[4].text + "\" after the default; expected " +
               (p.type == TechniqueParam::Type::Bool ? std::string("the end of the line (a bool has no range)")
                                                     : std::string("range <lo>..<hi>")));
    if (tokens.size() > 6)
      fail(tokens[6].offset, "got \"" + tokens[6].text + "\" after the range; expected the end of the line");
    const std::string& r = tokens[5].text;
    const size_t dots = r.find("..");
    if (dots == std::string::npos || !parseNumber(r.substr(0, dots), p.type, p.lo) ||
        !parseNumber(r.substr(dots + 2), p.type, p.hi) || !(p.lo <= p.hi))
      fail(tokens[5].offset, "range \"" + r + "\"; expected <lo>..<hi>, two " + typeName(p.type) + "s with lo <= hi");
    if (p.defaultValue < p.lo || p.defaultValue > p.hi)
      fail(tokens[3].offset, "default " + tokens[3].text + " outside the range " + r + "; expected a default in it");
  }
  return p;
}

// What a technique may not say (raster/METHODS.md "Your own technique"): a technique is a pure
// function of what the harness hands it, because anything it declares or writes reaches the
// harness's pipeline unchecked: a resource of its own is bound to nothing (the driver crashes
// building the pipeline), a write to a buffer, an image or an output changes what other pixels
// and passes read, and discard drops the harness's own channels of the pixel.
struct Forbidden {
  const char* word;
  const char* why;
};
const char* const kResources = "declares a resource or an interface variable of its own";
const char* const kWrites = "writes outside the function";
const char* const kEnds = "ends the harness's pixel";
const Forbidden kForbidden[] = {
    {"uniform", kResources},
    {"buffer", kResources},
    {"shared", kResources},
    {"attribute", kResources},
    {"varying", kResources},
    {"layout", kResources},
    {"push_constant", kResources},
    {"patch", kResources},
    {"centroid", kResources},
    {"flat", kResources},
    {"smooth", kResources},
    {"noperspective", kResources},
    {"invariant", kResources},
    {"subroutine", kResources},
    {"coherent", kResources},
    {"volatile", kResources},
    {"restrict", kResources},
    {"readonly", kResources},
    {"writeonly", kResources},
    {"discard", kEnds},
    {"demote", kEnds},
    {"terminateInvocation", kEnds},
    {"imageStore", kWrites},
    {"imageAtomicAdd", kWrites},
    {"imageAtomicMin", kWrites},
    {"imageAtomicMax", kWrites},
    {"imageAtomicAnd", kWrites},
    {"imageAtomicOr", kWrites},
    {"imageAtomicXor", kWrites},
    {"imageAtomicExchange", kWrites},
    {"imageAtomicCompSwap", kWrites},
    {"imageAtomicLoad", kWrites},
    {"imageAtomicStore", kWrites},
    {"atomicAdd", kWrites},
    {"atomicMin", kWrites},
    {"atomicMax", kWrites},
    {"atomicAnd", kWrites},
    {"atomicOr", kWrites},
    {"atomicXor", kWrites},
    {"atomicExchange", kWrites},
    {"atomicCompSwap", kWrites},
    {"atomicLoad", kWrites},
    {"atomicStore", kWrites},
    {"atomicCounterIncrement", kWrites},
    {"atomicCounterDecrement", kWrites},
    {"barrier", kWrites},
    {"memoryBarrier", kWrites},
    {"memoryBarrierBuffer", kWrites},
    {"memoryBarrierImage", kWrites},
    {"memoryBarrierShared", kWrites},
    {"groupMemoryBarrier", kWrites},
    {"gl_FragDepth", kWrites},
    {"gl_SampleMask", kWrites},
    {"gl_FragColor", kWrites},
    {"gl_FragData", kWrites},
};

// The file's code (comments blanked) token by token: what it may not say (kForbidden), `in`/`out`
// at file scope (an interface variable, not a parameter), a definition of main, brackets and
// preprocessor conditionals that do not pair up within the file. The file is compiled in the
// middle of the harness's shader, so an unclosed brace or #if would be reported in the harness's
// code, far from its cause: said here, at the bracket.
void checkTokens(const TechniqueFile& f, const std::string& code) {
  const std::string& s = f.source;
  size_t line = 0, column = 0;
  auto fail = [&](size_t at, const std::string& what) {
    place(s, at, line, column);
    failAt(f.path, line, column, what);
  };
  struct Open {
    char c;
    size_t at;
  };
  std::vector<Open> brackets, conditionals;
  const size_t n = code.size();
  bool lineStart = true, directive = false;
  std::string directiveName;
  auto isIdent = [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; };
  for (size_t i = 0; i < n;) {
    const char c = code[i];
    if (c == '\n') {
      // A directive ends at a newline not escaped by a backslash.
      size_t k = i;
      while (k > 0 && (code[k - 1] == ' ' || code[k - 1] == '\t' || code[k - 1] == '\r')) --k;
      if (!(k > 0 && code[k - 1] == '\\')) directive = false;
      lineStart = !directive;
      ++i;
      continue;
    }
    if (std::isspace(static_cast<unsigned char>(c))) {
      ++i;
      continue;
    }
    if (lineStart && c == '#') {
      lineStart = false;
      directive = true;
      size_t j = i + 1;
      while (j < n && (code[j] == ' ' || code[j] == '\t')) ++j;
      size_t e = j;
      while (e < n && isIdent(code[e])) ++e;
      const std::string name = code.substr(j, e - j);
      if (name == "if" || name == "ifdef" || name == "ifndef") conditionals.push_back({'#', i});
      else if (name == "elif" || name == "else") {
        if (conditionals.empty())
          fail(i, "#" + name + " without an #if in this file; expected the file's own #if first");
      } else if (name == "endif") {
        if (conditionals.empty())
          fail(i, "#endif closes no #if of this file; expected each #if, #ifdef, #ifndef closed within the file");
        conditionals.pop_back();
      }
      i = e;
      continue;
    }
    lineStart = false;
    if (isIdent(c) && !std::isdigit(static_cast<unsigned char>(c))) {
      size_t e = i;
      while (e < n && isIdent(code[e])) ++e;
      const std::string word = code.substr(i, e - i);
      for (const Forbidden& x : kForbidden)
        if (word == x.word)
          fail(i, "'" + word + "' " + x.why +
                      "; expected a technique that reads only what the harness hands it (ShadowQuery q, mapDepth, "
                      "mapShadow, mapMoments, its declared keys) and writes only its locals and its return value "
                      "(raster/METHODS.md \"Your own technique\")");
      if (!directive && brackets.empty() && (word == "in" || word == "out" || word == "inout"))
        fail(i, "'" + word + "' at file scope " + kResources +
                    "; expected parameters and locals only (raster/METHODS.md \"Your own technique\")");
      if (!directive && word == "main") {
        size_t j = e;
        while (j < n && std::isspace(static_cast<unsigned char>(code[j]))) ++j;
        if (brackets.empty() && j < n && code[j] == '(')
          fail(i,
               "defines main(); expected only shadowVisibility and its helpers (the harness's resolve.frag "
               "holds the shader's entry point)");
      }
      i = e;
      continue;
    }
    if (!directive) {
      if (c == '{' || c == '(' || c == '[') brackets.push_back({c, i});
      else if (c == '}' || c == ')' || c == ']') {
        const char want = c == '}' ? '{' : c == ')' ? '(' : '[';
        if (brackets.empty())
          fail(i, std::string("'") + c + "' closes nothing; expected it to close a '" + want + "' of this file");
        if (brackets.back().c != want)
          fail(
              i, std::string("'") + c + "' where the '" + brackets.back().c + "' at " + [&] {
                size_t l = 0, col = 0;
                place(s, brackets.back().at, l, col);
                return std::to_string(l) + ":" + std::to_string(col);
              }() + " is open; expected its closing bracket first");
        brackets.pop_back();
      }
    }
    ++i;
  }
  if (!brackets.empty()) {
    const Open& o = brackets.back();
    const char close = o.c == '{' ? '}' : o.c == '(' ? ')' : ']';
    fail(o.at, std::string("'") + o.c + "' is never closed; expected a '" + close + "' before the end of the file");
  }
  if (!conditionals.empty())
    fail(conditionals.back().at, "#if is never closed; expected its #endif before the end of the file");
}

// The checks of technique.h on `f.source`, filling f.params.
void check(TechniqueFile& f) {
  const std::string& s = f.source;
  size_t line = 0, column = 0;
  const size_t bad = firstNonUtf8(s);
  if (bad != std::string::npos) {
    place(s, bad, line, column);
    char hex[8];
    std::snprintf(hex, sizeof hex, "0x%02x", unsigned(static_cast<unsigned char>(s[bad])));
    failAt(f.path, line, column,
           std::string("byte ") + hex + " is not UTF-8 text; expected a GLSL source file (UTF-8, no NUL bytes)");
  }
  const std::string code = withoutComments(s);
  f.readsPlaneSlope = code.find("planeSlope") != std::string::npos || code.find("##") != std::string::npos;
  // Preprocessor lines that would change what the harness compiles around the file.
  static const std::regex directive(R"(^[ \t]*#[ \t]*(include|version|extension|line)\b)", std::regex::multiline);
  for (auto it = std::sregex_iterator(code.begin(), code.end(), directive); it != std::sregex_iterator(); ++it) {
    place(s, size_t(it->position(0)), line, column);
    const std::string what = (*it)[1];
    failAt(f.path, line, column,
           "#" + what + " in a technique file; expected one self-contained file (the harness sets the version, " +
               "the extensions and includes the ABI: raster/METHODS.md \"Your own technique\")");
  }
  checkTokens(f, code);
  // Declarations: whole-line comments "// shadowlab: ...".
  static const std::regex declaration(R"(^[ \t]*//[ \t]*shadowlab:(.*)$)", std::regex::multiline);
  for (auto it = std::sregex_iterator(s.begin(), s.end(), declaration); it != std::sregex_iterator(); ++it) {
    const size_t restOffset = size_t(it->position(1));
    const std::string rest = (*it)[1];
    // "moments <kind>": its tokens and their offsets in the file.
    const std::vector<Token> tokens = declarationTokens(rest, restOffset);
    if (!tokens.empty() && tokens[0].text == "moments") {
      place(s, tokens[0].offset, line, column);
      if (!f.moments.empty())
        failAt(f.path, line, column,
               "a second moments line (the first on line " + std::to_string(f.momentsLine) + "); expected one");
      const int declaredOn = int(line);
      const std::string kind = tokens.size() > 1 ? tokens[1].text : std::string();
      const KindInfo<Filter>* k = findKind(filterKinds(), kind);
      if (!k || !isMomentFilter(k->kind)) {
        place(s, tokens.size() > 1 ? tokens[1].offset : tokens[0].offset, line, column);
        failAt(f.path, line, column,
               "moments \"" + kind + "\"; expected one of " + momentFilterKeys() + " (" + kMomentsSyntax + ")");
      }
      if (tokens.size() > 2) {
        place(s, tokens[2].offset, line, column);
        failAt(f.path, line, column,
               "got \"" + tokens[2].text + "\" after the moments kind; expected the end of the line");
      }
      f.moments = kind;
      f.momentsLine = declaredOn;
      continue;
    }
    f.params.push_back(parseDeclaration(f, rest, restOffset, f.params));
  }
  // The moments read without asking: no image is bound for them (raster/METHODS.md).
  if (f.moments.empty()) {
    static const std::regex reads(kMomentNames);
    // ShadowQuery's fields only as q.<name>; the global image by its name alone.
    for (auto it = std::sregex_iterator(code.begin(), code.end(), reads); it != std::sregex_iterator(); ++it) {
      const std::string name = (*it)[1];
      const size_t at = size_t(it->position(0));
      const bool global = name == "mapMoments" || name == "momentsMap";
      size_t before = at;
      while (before > 0 && std::isspace(static_cast<unsigned char>(code[before - 1]))) --before;
      if (!global && !(before > 0 && code[before - 1] == '.')) continue;
      place(s, at, line, column);
      failAt(f.path, line, column,
             "reads " + name + " without asking for moments; expected a header line " + kMomentsSyntax +
                 " (the harness renders and blurs that filter's moments for the file only then)");
    }
  }
  // The function: a definition `<type> <name>(<params>) {`.
  static const std::regex definition(R"(\b([A-Za-z_]\w*)\s+([A-Za-z_]\w*)\s*\(([^()]*)\)\s*\{)");
  static const std::regex signature(R"(^\s*(?:(?:in|const)\s+)*ShadowQuery\s+[A-Za-z_]\w*\s*$)");
  size_t wrongAt = std::string::npos, similarAt = std::string::npos;
  std::string wrong, similar;
  for (auto it = std::sregex_iterator(code.begin(), code.end(), definition); it != std::sregex_iterator(); ++it) {
    const std::string type = (*it)[1], name = (*it)[2], params = (*it)[3];
    if (type == "return" || type == "else") continue;
    if (name == kTechniqueFunction) {
      if (type == "float" && std::regex_match(params, signature)) return;
      if (wrongAt == std::string::npos)
        wrongAt = size_t(it->position(1)), wrong = type + " " + name + "(" + params + ")";
    } else if (similarAt == std::string::npos && !detail::didYouMean(name, {kTechniqueFunction}).empty()) {
      similarAt = size_t(it->position(2)), similar = name;
    }
  }
  if (wrongAt != std::string::npos) {
    place(s, wrongAt, line, column);
    failAt(f.path, line, column,
           "got " + wrong + "; expected the signature " + kTechniqueSignature + " (ShadowQuery: raster/METHODS.md)");
  }
  if (similarAt != std::string::npos) {
    place(s, similarAt, line, column);
    failAt(
        f.path, line, column,
        "function \"" + similar + "\" (did you mean \"" + kTechniqueFunction + "\"?); expected " + kTechniqueSignature);
  }
  failAt(f.path, 1, 1,
         std::string("no function ") + kTechniqueFunction + "; expected a definition of " + kTechniqueSignature +
             " (raster/METHODS.md \"Your own technique\")");
}

}  // namespace

const TechniqueParam* TechniqueFile::find(const std::string& name) const {
  for (const TechniqueParam& p : params)
    if (p.name == name) return &p;
  return nullptr;
}

const TechniqueFile& loadTechniqueFile(const std::string& path) {
  // Checked before reading: glslang's time and memory grow with the text (a file of 400k
  // statements, 8.8 MB, compiled for minutes), and a lookup function fits in far less.
  std::string bytes = readFileAtMost(path, kTechniqueMaxBytes, "a technique file");
  const std::string hash = hashHex(fnv1a64(bytes.data(), bytes.size()));
  static std::mutex mutex;
  // Never erased: references stay valid, and an edited file is a new entry (a new hash).
  static std::map<std::string, std::unique_ptr<TechniqueFile>> cache;
  std::lock_guard<std::mutex> lock(mutex);
  auto& slot = cache[path + '\n' + hash];
  if (slot) return *slot;
  auto f = std::make_unique<TechniqueFile>();
  f->path = path;
  // A UTF-8 byte-order mark (some editors write one) is no GLSL: the hash keeps the file's bytes,
  // the text handed on starts after it (line 1's columns as an editor counts them).
  f->source = bytes.compare(0, 3, "\xEF\xBB\xBF") == 0 ? bytes.substr(3) : std::move(bytes);
  f->hash = hash;
  std::string name = path.substr(path.find_last_of('/') + 1);
  const size_t dot = name.find_last_of('.');
  f->stem = dot == std::string::npos || dot == 0 ? name : name.substr(0, dot);
  check(*f);
  slot = std::move(f);
  return *slot;
}

uint32_t techniqueParamBits(const TechniqueParam& p, double value) {
  if (p.type == TechniqueParam::Type::Bool) return value != 0 ? 1u : 0u;
  if (p.type == TechniqueParam::Type::Int) return uint32_t(int32_t(value));
  const float f = float(value);
  uint32_t bits = 0;
  std::memcpy(&bits, &f, 4);
  return bits;
}

}  // namespace shadowlab
