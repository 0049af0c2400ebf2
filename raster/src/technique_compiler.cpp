// Run-time compile of technique files (technique_compiler.h) with glslang's library: the same
// front end and SPIR-V back end as the build's glslangValidator, on resolve.frag's embedded text.
#include "technique_compiler.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <map>
#include <mutex>
#include <regex>
#include <set>
#include <sstream>
#include <string>

#include <glslang/Include/intermediate.h>
#include <glslang/MachineIndependent/localintermediate.h>
#include <glslang/Public/ResourceLimits.h>
#include <glslang/Public/ShaderLang.h>
#include <glslang/SPIRV/GlslangToSpv.h>

#include "resolve_text.h"
#include "shadowlab/raster/resolve_abi.h"
#include "shadowlab/scenes/error.h"

namespace shadowlab::raster {
namespace {

// The name glslang reports the harness's own source under (errors there are the harness's).
constexpr const char* kResolveName = "resolve.frag";
constexpr const char* kTechniqueInclude = "shadowlab/technique";

// The declared keys as specialization constants technique_<name> (ids kSpecCount + i, in
// declaration order: the rasterizer appends their values), then the user's text from its line 1.
std::string techniqueText(const TechniqueFile& t) {
  std::ostringstream s;
  for (size_t i = 0; i < t.params.size(); ++i) {
    const TechniqueParam& p = t.params[i];
    const char* type = p.type == TechniqueParam::Type::Float ? "float"
                       : p.type == TechniqueParam::Type::Int ? "int"
                                                             : "bool";
    std::string value;
    if (p.type == TechniqueParam::Type::Bool) value = p.defaultValue != 0 ? "true" : "false";
    else if (p.type == TechniqueParam::Type::Int) value = std::to_string(int(p.defaultValue));
    else {
      char buf[40];
      std::snprintf(buf, sizeof buf, "%.9g", p.defaultValue);
      value = buf;
      if (value.find_first_of(".e") == std::string::npos) value += ".0";
    }
    s << "layout(constant_id = " << abi::kSpecCount + int(i) << ") const " << type << " technique_" << p.name << " = "
      << value << ";\n";
  }
  // A moments line: the moments image under its ABI name (resolve.frag's momentsMap).
  if (!t.moments.empty()) s << "#define mapMoments momentsMap\n";
  s << "#line 1\n" << t.source << "\n";
  // The file's macros end with it: one named like a harness identifier would rewrite the harness's
  // code after the file (an error there, or a silent change).
  static const std::regex define(R"(^[ \t]*#[ \t]*define[ \t]+([A-Za-z_]\w*))", std::regex::multiline);
  for (auto it = std::sregex_iterator(t.source.begin(), t.source.end(), define); it != std::sregex_iterator(); ++it)
    s << "#undef " << (*it)[1] << "\n";
  return s.str();
}

class Includer : public glslang::TShader::Includer {
 public:
  Includer(const TechniqueFile& t) : technique_(t), techniqueText_(techniqueText(t)) {}
  IncludeResult* includeLocal(const char* name, const char*, size_t) override { return find(name); }
  IncludeResult* includeSystem(const char* name, const char*, size_t) override { return find(name); }
  void releaseInclude(IncludeResult* r) override { delete r; }

 private:
  IncludeResult* find(const std::string& name) {
    if (name == "shadowlab/raster/resolve_abi.h")
      return new IncludeResult(name, kText_resolve_abi_h, std::strlen(kText_resolve_abi_h), nullptr);
    if (name == "shadowlab/scenes/kinds.h")
      return new IncludeResult(name, kText_kinds_h, std::strlen(kText_kinds_h), nullptr);
    if (name == kTechniqueInclude)
      return new IncludeResult(technique_.path, techniqueText_.data(), techniqueText_.size(), nullptr);
    return nullptr;
  }
  const TechniqueFile& technique_;
  std::string techniqueText_;
};

// One token of a line: its text and 0-based column.
struct LineToken {
  std::string text;
  size_t column;
  bool identifier, number;
};

// The tokens of one line of GLSL (comments are the caller's: glslang reports no error inside one).
std::vector<LineToken> lineTokens(const std::string& text) {
  std::vector<LineToken> out;
  for (size_t i = 0; i < text.size();) {
    const unsigned char c = static_cast<unsigned char>(text[i]);
    if (std::isspace(c)) {
      ++i;
      continue;
    }
    if (text.compare(i, 2, "//") == 0) break;
    size_t e = i + 1;
    const bool identifier = std::isalpha(c) || c == '_';
    const bool number =
        std::isdigit(c) || (c == '.' && i + 1 < text.size() && std::isdigit((unsigned char)text[i + 1]));
    if (identifier)
      while (e < text.size() && (std::isalnum((unsigned char)text[e]) || text[e] == '_')) ++e;
    else if (number)
      while (e < text.size() && (std::isalnum((unsigned char)text[e]) || text[e] == '.' ||
                                 ((text[e] == '+' || text[e] == '-') && (text[e - 1] == 'e' || text[e - 1] == 'E'))))
        ++e;
    else {
      static const char* const kPairs[] = {"<<=", ">>=", "++", "--", "<=", ">=", "==", "!=", "&&", "||", "^^",
                                           "+=",  "-=",  "*=", "/=", "%=", "&=", "|=", "^=", "<<", ">>", "##"};
      for (const char* p : kPairs)
        if (text.compare(i, std::strlen(p), p) == 0) {
          e = i + std::strlen(p);
          break;
        }
    }
    out.push_back({text.substr(i, e - i), i, identifier, number});
    i = e;
  }
  return out;
}

// The column of glslang's error on `line` of the user's text (glslang 12 reports lines only). With
// a quoted token: its first occurrence there as a whole token. A syntax error names the unexpected
// token's kind: the token of that kind where the parser most likely stopped (an operand right
// after another operand, a ';' or ')' right after an operator), else that kind's first token.
// Else 1.
size_t columnOf(const std::string& source, size_t line, const std::string& token, const std::string& message) {
  size_t start = 0;
  for (size_t l = 1; l < line && start != std::string::npos; ++l) {
    start = source.find('\n', start);
    if (start != std::string::npos) ++start;
  }
  if (start == std::string::npos) return 1;
  const std::vector<LineToken> tokens = lineTokens(source.substr(start, source.find('\n', start) - start));
  if (!token.empty()) {
    for (const LineToken& t : tokens)
      if (t.text == token) return t.column + 1;
    for (const LineToken& t : tokens)  // a token glslang quotes with more around it ("x.y")
      if (token.find(t.text) == 0 && t.identifier) return t.column + 1;
    return 1;
  }
  const size_t at = message.find("unexpected ");
  if (at == std::string::npos) return 1;
  const std::string kind = message.substr(at + 11, message.find_first_of(" ,", at + 11) - at - 11);
  static const std::map<std::string, std::string> kTokens = {
      {"SEMICOLON", ";"},     {"RIGHT_PAREN", ")"},  {"LEFT_PAREN", "("},   {"RIGHT_BRACE", "}"}, {"LEFT_BRACE", "{"},
      {"RIGHT_BRACKET", "]"}, {"LEFT_BRACKET", "["}, {"COMMA", ","},        {"EQUAL", "="},       {"DOT", "."},
      {"PLUS", "+"},          {"DASH", "-"},         {"STAR", "*"},         {"SLASH", "/"},       {"PERCENT", "%"},
      {"LEFT_ANGLE", "<"},    {"RIGHT_ANGLE", ">"},  {"COLON", ":"},        {"QUESTION", "?"},    {"BANG", "!"},
      {"TILDE", "~"},         {"AMPERSAND", "&"},    {"VERTICAL_BAR", "|"}, {"CARET", "^"},       {"INC_OP", "++"},
      {"DEC_OP", "--"},       {"LE_OP", "<="},       {"GE_OP", ">="},       {"EQ_OP", "=="},      {"NE_OP", "!="},
      {"AND_OP", "&&"},       {"OR_OP", "||"},       {"ADD_ASSIGN", "+="},  {"SUB_ASSIGN", "-="}, {"MUL_ASSIGN", "*="},
      {"DIV_ASSIGN", "/="}};
  auto operand = [](const LineToken& t) { return t.identifier || t.number || t.text == ")" || t.text == "]"; };
  auto isOperator = [&](const LineToken& t) { return !operand(t) && t.text != "(" && t.text != "}" && t.text != "{"; };
  std::vector<size_t> matches;
  for (size_t i = 0; i < tokens.size(); ++i) {
    const LineToken& t = tokens[i];
    bool match;
    if (kind == "IDENTIFIER" || kind == "TYPE_NAME") match = t.identifier;
    else if (kind == "FLOATCONSTANT" || kind == "INTCONSTANT" || kind == "UINTCONSTANT" || kind == "DOUBLECONSTANT")
      match = t.number;
    else if (kind == "BOOLCONSTANT") match = t.text == "true" || t.text == "false";
    else if (kTokens.count(kind)) match = t.text == kTokens.at(kind);
    else {  // a keyword: its name in lower case (RETURN, FLOAT, VEC2, ...)
      std::string lower = kind;
      for (char& ch : lower) ch = char(std::tolower(static_cast<unsigned char>(ch)));
      match = t.text == lower;
    }
    if (match) matches.push_back(i);
  }
  if (matches.empty()) return 1;
  // An identifier after a type or qualifier is a declaration, not two operands in a row.
  static const std::regex declaring(
      "const|in|out|inout|highp|mediump|lowp|precise|return|else|struct|void|bool|int|uint|float|double|"
      "[biud]?vec[234]|d?mat[234](x[234])?|[A-Z]\\w*");
  for (int pass = 0; pass < 2; ++pass)
    for (size_t i : matches) {
      if (i == 0) continue;
      const LineToken &t = tokens[i], &before = tokens[i - 1];
      if (pass == 0) {
        if ((t.identifier || t.number) && (before.number || before.text == ")" || before.text == "]"))
          return t.column + 1;
        if ((t.text == ";" || t.text == ")" || t.text == "]") && isOperator(before)) return t.column + 1;
      } else if ((t.identifier || t.number) && before.identifier && !std::regex_match(before.text, declaring)) {
        return t.column + 1;
      }
    }
  return tokens[matches.front()].column + 1;
}

// The line and column of `name`'s first occurrence in `source` as a whole word, or false.
bool findWord(const std::string& source, const std::string& name, size_t& line, size_t& column) {
  if (name.empty()) return false;
  auto ident = [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; };
  for (size_t at = source.find(name); at != std::string::npos; at = source.find(name, at + 1)) {
    if ((at > 0 && ident(source[at - 1])) || (at + name.size() < source.size() && ident(source[at + name.size()])))
      continue;
    line = 1, column = 1;
    for (size_t i = 0; i < at; ++i) {
      if (source[i] == '\n') ++line, column = 1;
      else ++column;
    }
    return true;
  }
  return false;
}

// glslang's log ("ERROR: <name>:<line>: '<token>' : <message>") as "file:line:column: error: ..."
// lines; the user's file's errors only, unless the harness's code alone failed. Those are said at
// the user's file too: at the name they quote where the file has it (a name both define), else at
// the file's end (the harness's code follows it), with glslang's words and place.
std::string userErrors(const std::string& log, const TechniqueFile& t) {
  static const std::regex line(R"(^ERROR: (.*?):(\d+): '(.*?)' :\s+(.*?)\s*$)");
  std::istringstream in(log);
  std::string text, mine, harness;
  size_t harnessLine = 0, harnessColumn = 0;
  while (std::getline(in, text)) {
    std::smatch m;
    if (!std::regex_match(text, m, line)) continue;
    const std::string file = m[1], token = m[3], message = m[4];
    if (message.find("compilation terminated") != std::string::npos) continue;
    const std::string what = token.empty() ? message : "'" + token + "': " + message;
    const size_t lineNo = std::stoul(m[2]);
    if (file == t.path)
      mine += t.path + ":" + std::to_string(lineNo) + ":" + std::to_string(columnOf(t.source, lineNo, token, message)) +
              ": error: " + what + "\n";
    else {
      if (harness.empty() && !findWord(t.source, token, harnessLine, harnessColumn)) harnessLine = 0;
      harness += file + ":" + std::to_string(lineNo) + ": " + what + "\n";
    }
  }
  if (!mine.empty()) return mine.substr(0, mine.size() - 1);
  if (harnessLine == 0) {  // the end of the file: its last line, after its last character
    harnessLine = 1, harnessColumn = 1;
    for (size_t i = 0; i < t.source.size(); ++i) {
      if (t.source[i] == '\n' && i + 1 < t.source.size()) ++harnessLine, harnessColumn = 1;
      else if (t.source[i] != '\n') ++harnessColumn;
    }
  }
  return t.path + ":" + std::to_string(harnessLine) + ":" + std::to_string(harnessColumn) +
         ": error: the harness's resolve.frag does not compile with this file (a name both define, or a macro of "
         "the file's): " +
         (harness.empty() ? log : harness.substr(0, harness.size() - 1));
}

// The user's file as glslang names it: its code, as against the harness's.
bool inFile(const glslang::TSourceLoc& loc, const TechniqueFile& t) {
  return loc.name != nullptr && t.path == loc.name->c_str();
}

// "path:line:column: error: what" at a node of the user's file (glslang's AST carries columns).
[[noreturn]] void refuseAt(const TechniqueFile& t, const glslang::TSourceLoc& loc, const std::string& what) {
  throw InputError(t.path + ":" + std::to_string(loc.line) + ":" + std::to_string(std::max(loc.column, 1)) +
                   ": error: " + what + " (raster/METHODS.md \"Your own technique\")");
}

// The globals a technique reads besides ShadowQuery and its keys (raster/METHODS.md): the maps.
bool handedOver(const glslang::TString& name) {
  return name == "mapDepth" || name == "mapShadow" || name == "momentsMap";
}

// The writes, kills and side effects of the user's functions, on glslang's AST: the text checks
// (scenes/src/technique.cpp) see words, this sees what they compile to, whatever macros made them
// (a write to the harness's outputs or buffers, to a global, through an out argument, discard).
class SideEffects : public glslang::TIntermTraverser {
 public:
  explicit SideEffects(const TechniqueFile& t) : t_(t) {}

  void visitSymbol(glslang::TIntermSymbol* n) override {
    const glslang::TStorageQualifier q = n->getQualifier().storage;
    if ((q == glslang::EvqUniform || q == glslang::EvqBuffer || q == glslang::EvqVaryingIn ||
         q == glslang::EvqVaryingOut || q == glslang::EvqShared) &&
        !handedOver(n->getName()))
      refuseAt(t_, n->getLoc(),
               "reads '" +
                   std::string(std::strncmp(n->getName().c_str(), "anon@", 5) == 0 ? n->getType().getTypeName().c_str()
                                                                                   : n->getName().c_str()) +
                   "', which the harness does not hand a technique; expected ShadowQuery q, mapDepth, mapShadow, "
                   "mapMoments and the declared keys");
  }
  bool visitBinary(glslang::TVisit, glslang::TIntermBinary* n) override {
    const glslang::TOperator op = n->getOp();
    if (op >= glslang::EOpAssign && op <= glslang::EOpRightShiftAssign) written(n->getLeft(), n->getLoc());
    return true;
  }
  bool visitUnary(glslang::TVisit, glslang::TIntermUnary* n) override {
    const glslang::TOperator op = n->getOp();
    if (op >= glslang::EOpPostIncrement && op <= glslang::EOpPreDecrement) written(n->getOperand(), n->getLoc());
    return true;
  }
  bool visitBranch(glslang::TVisit, glslang::TIntermBranch* n) override {
    const glslang::TOperator op = n->getFlowOp();
    if (op == glslang::EOpKill || op == glslang::EOpTerminateInvocation || op == glslang::EOpDemote)
      refuseAt(t_, n->getLoc(), "ends the harness's pixel (discard); expected a visibility returned");
    return true;
  }
  bool visitAggregate(glslang::TVisit, glslang::TIntermAggregate* n) override {
    const glslang::TOperator op = n->getOp();
    if ((op >= glslang::EOpBarrier && op <= glslang::EOpGroupMemoryBarrier) ||
        (op >= glslang::EOpAtomicAdd && op <= glslang::EOpAtomicCounterCompSwap) ||
        (op >= glslang::EOpImageStore && op <= glslang::EOpImageAtomicStore) || op == glslang::EOpDemote ||
        op == glslang::EOpTerminateInvocation)
      refuseAt(t_, n->getLoc(),
               "writes outside the function (an image, a buffer, an atomic or a barrier); expected "
               "writes to its locals and its return value only");
    glslang::TIntermSequence& args = n->getSequence();
    const glslang::TQualifierList& qualifiers = n->getQualifierList();
    for (size_t i = 0; i < args.size() && i < qualifiers.size(); ++i)
      if (qualifiers[i] == glslang::EvqOut || qualifiers[i] == glslang::EvqInOut) written(args[i], n->getLoc());
    // Built-ins whose out parameters glslang keeps as operands.
    size_t firstOut = args.size();
    if (op == glslang::EOpModf || op == glslang::EOpFrexp) firstOut = 1;
    else if (op == glslang::EOpAddCarry || op == glslang::EOpSubBorrow || op == glslang::EOpUMulExtended ||
             op == glslang::EOpIMulExtended)
      firstOut = 2;
    for (size_t i = firstOut; i < args.size(); ++i) written(args[i], n->getLoc());
    return true;
  }

 private:
  // `target` is written: refused unless it is one of the function's locals or parameters.
  void written(TIntermNode* target, const glslang::TSourceLoc& at) {
    std::string member;  // a member of an anonymous block is named by the member
    while (glslang::TIntermBinary* b = target ? target->getAsBinaryNode() : nullptr) {
      const glslang::TOperator op = b->getOp();
      if (op != glslang::EOpIndexDirect && op != glslang::EOpIndexIndirect && op != glslang::EOpIndexDirectStruct &&
          op != glslang::EOpVectorSwizzle)
        break;
      const glslang::TType& type = b->getLeft()->getType();
      if (op == glslang::EOpIndexDirectStruct && type.getStruct() && b->getRight()->getAsConstantUnion()) {
        const int index = b->getRight()->getAsConstantUnion()->getConstArray()[0].getIConst();
        if (index >= 0 && size_t(index) < type.getStruct()->size())
          member = (*type.getStruct())[size_t(index)].type->getFieldName().c_str();
      }
      target = b->getLeft();
    }
    glslang::TIntermSymbol* symbol = target ? target->getAsSymbolNode() : nullptr;
    if (!symbol) return;  // a temporary (glslang refuses writes to values itself)
    const glslang::TStorageQualifier q = symbol->getQualifier().storage;
    if (q == glslang::EvqTemporary || q == glslang::EvqIn || q == glslang::EvqOut || q == glslang::EvqInOut) return;
    const bool anonymous = std::strncmp(symbol->getName().c_str(), "anon@", 5) == 0;
    refuseAt(t_, inFile(symbol->getLoc(), t_) ? symbol->getLoc() : at,
             "writes '" + (anonymous && !member.empty() ? member : std::string(symbol->getName().c_str())) +
                 "', which is not one of its locals; expected writes to its locals and its return value only");
  }
  const TechniqueFile& t_;
};

// The AST's functions and globals from the user's file (SideEffects), and its declarations of
// anything but plain globals and constants (resources and interface variables however spelled).
void checkSideEffects(glslang::TIntermediate& intermediate, const TechniqueFile& t) {
  glslang::TIntermAggregate* root = intermediate.getTreeRoot() ? intermediate.getTreeRoot()->getAsAggregate() : nullptr;
  if (!root) return;
  SideEffects check(t);
  for (TIntermNode* node : root->getSequence()) {
    glslang::TIntermAggregate* a = node->getAsAggregate();
    if (!a) continue;
    if (a->getOp() == glslang::EOpFunction && inFile(a->getLoc(), t)) a->traverse(&check);
    if (a->getOp() != glslang::EOpLinkerObjects) continue;
    for (TIntermNode* object : a->getSequence()) {
      glslang::TIntermSymbol* symbol = object->getAsSymbolNode();
      if (!symbol || !inFile(symbol->getLoc(), t)) continue;
      const glslang::TStorageQualifier q = symbol->getQualifier().storage;
      if (q != glslang::EvqGlobal && q != glslang::EvqConst && q != glslang::EvqTemporary)
        refuseAt(t, symbol->getLoc(),
                 "declares '" + std::string(symbol->getName().c_str()) +
                     "', a resource or interface variable of its own; expected a technique to read only what the "
                     "harness hands it");
    }
  }
}

// The compiled module's interface: every variable that is neither a function's nor the shader's
// private one (descriptors, push constants, inputs, outputs, workgroup memory), as
// "storage class/set/binding" or "storage class/location|builtin", with its OpName.
std::map<std::string, std::string> spirvInterface(const std::vector<uint32_t>& spirv) {
  constexpr uint32_t kOpName = 5, kOpDecorate = 71, kOpVariable = 59;
  constexpr uint32_t kDecorationBuiltIn = 11, kDecorationLocation = 30, kDecorationBinding = 33,
                     kDecorationDescriptorSet = 34;
  constexpr uint32_t kStoragePrivate = 6, kStorageFunction = 7;
  std::map<uint32_t, std::string> names;
  std::map<uint32_t, std::map<uint32_t, uint32_t>> decorations;  // id -> decoration -> first literal
  std::map<uint32_t, uint32_t> variables;                        // id -> storage class
  for (size_t i = 5; i < spirv.size();) {
    const uint32_t count = spirv[i] >> 16, op = spirv[i] & 0xffff;
    if (count == 0 || i + count > spirv.size()) break;
    if (op == kOpName && count >= 3) {
      const char* text = reinterpret_cast<const char*>(&spirv[i + 2]);
      names[spirv[i + 1]] = std::string(text, strnlen(text, (count - 2) * 4));
    } else if (op == kOpDecorate && count >= 4) {
      decorations[spirv[i + 1]][spirv[i + 2]] = spirv[i + 3];
    } else if (op == kOpVariable && count >= 4 && spirv[i + 3] != kStoragePrivate && spirv[i + 3] != kStorageFunction) {
      variables[spirv[i + 2]] = spirv[i + 3];
    }
    i += count;
  }
  std::map<std::string, std::string> out;
  for (const auto& [id, storage] : variables) {
    const auto& d = decorations[id];
    static const std::map<uint32_t, const char*> kStorage = {
        {0, "UniformConstant"}, {1, "Input"},        {2, "Uniform"}, {3, "Output"},
        {4, "Workgroup"},       {9, "PushConstant"}, {11, "Image"},  {12, "StorageBuffer"}};
    std::string key = kStorage.count(storage) ? kStorage.at(storage) : "storage class " + std::to_string(storage);
    auto has = [&](uint32_t k) { return d.count(k) != 0; };
    if (has(kDecorationBuiltIn)) key += ", builtin " + std::to_string(d.at(kDecorationBuiltIn));
    if (has(kDecorationLocation)) key += ", location " + std::to_string(d.at(kDecorationLocation));
    if (has(kDecorationDescriptorSet)) key += ", set " + std::to_string(d.at(kDecorationDescriptorSet));
    if (has(kDecorationBinding)) key += ", binding " + std::to_string(d.at(kDecorationBinding));
    out[key] = names.count(id) ? names[id] : "(unnamed)";
  }
  return out;
}

std::shared_ptr<const CompiledTechnique> compileBounded(const TechniqueFile& t);

// The interface of the harness's own shader in technique mode (with a file that only returns):
// what the pipeline layout and the render pass provide. Compiled once per process.
const std::map<std::string, std::string>& harnessInterface() {
  static const std::map<std::string, std::string> interface = [] {
    TechniqueFile trivial;
    trivial.path = "harness_interface.glsl";
    trivial.source = "float shadowVisibility(ShadowQuery q) {\n  return 1.0;\n}\n";
    return spirvInterface(compileBounded(trivial)->spirv);
  }();
  return interface;
}

// Refuses a module that declares what the harness does not bind: the driver would build a pipeline
// whose layout lacks it (on lavapipe a crash, not an error). Named at the variable's first mention
// in the file where the name is found there.
void checkInterface(const std::vector<uint32_t>& spirv, const TechniqueFile& t) {
  const auto& harness = harnessInterface();
  for (const auto& [key, name] : spirvInterface(spirv)) {
    if (harness.count(key)) continue;
    std::string where = t.path + ":";
    const std::regex word("\\b" + std::regex_replace(name, std::regex(R"([^\w])"), "") + "\\b");
    std::smatch m;
    if (!name.empty() && std::regex_search(t.source, m, word)) {
      size_t line = 1, column = 1;
      for (size_t i = 0; i < size_t(m.position(0)); ++i) {
        if (t.source[i] == '\n') ++line, column = 1;
        else ++column;
      }
      where += std::to_string(line) + ":" + std::to_string(column) + ":";
    }
    throw InputError(where + " error: the compiled shader has '" + name + "' (" + key +
                     "), which the harness's resolve shader does not declare; expected a technique to read only what "
                     "the harness hands it (raster/METHODS.md \"Your own technique\")");
  }
}

std::shared_ptr<const CompiledTechnique> compile(const TechniqueFile& t) {
  static const bool initialized = glslang::InitializeProcess();
  (void)initialized;
  auto t0 = std::chrono::steady_clock::now();
  glslang::TShader shader(EShLangFragment);
  const char* sources[] = {kText_resolve_frag};
  const char* names[] = {kResolveName};
  shader.setStringsWithLengthsAndNames(sources, nullptr, names, 1);
  shader.setPreamble("#define SHADOWLAB_TECHNIQUE 1\n");
  shader.setEnvInput(glslang::EShSourceGlsl, EShLangFragment, glslang::EShClientVulkan, 100);
  shader.setEnvClient(glslang::EShClientVulkan, glslang::EShTargetVulkan_1_3);
  shader.setEnvTarget(glslang::EShTargetSpv, glslang::EShTargetSpv_1_6);
  Includer includer(t);
  const auto messages = EShMessages(EShMsgSpvRules | EShMsgVulkanRules);
  if (!shader.parse(GetDefaultResources(), 460, false, messages, includer))
    throw InputError(userErrors(shader.getInfoLog(), t));
  glslang::TProgram program;
  program.addShader(&shader);
  if (!program.link(messages)) throw InputError(userErrors(program.getInfoLog(), t));
  checkSideEffects(*program.getIntermediate(EShLangFragment), t);
  auto out = std::make_shared<CompiledTechnique>();
  glslang::SpvOptions options;
  options.disableOptimizer = true;  // as glslangValidator -V without -Os
  glslang::GlslangToSpv(*program.getIntermediate(EShLangFragment), out->spirv, &options);
  out->compileMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

// The compile's bounds (raster/METHODS.md "Your own technique"): glslang's time and memory grow
// with what the text expands to, which no bound on the file's size limits (a macro can expand to
// millions of statements), so the compile runs in a child process that the kernel stops.
constexpr unsigned kCompileCpuSeconds = 20;
constexpr unsigned kCompileWallSeconds = 90;  // a shared machine: CPU time lags the wall clock
constexpr unsigned long kCompileMiB = 1536;   // address space; not under ASan, which reserves terabytes

std::string limitsText() {
  return std::to_string(kCompileCpuSeconds) + " s of CPU, " + std::to_string(kCompileWallSeconds) + " s, " +
         std::to_string(kCompileMiB) + " MiB";
}

#if defined(__SANITIZE_ADDRESS__)
constexpr bool kAddressSanitizer = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
constexpr bool kAddressSanitizer = true;
#else
constexpr bool kAddressSanitizer = false;
#endif
#else
constexpr bool kAddressSanitizer = false;
#endif

// compile() in a forked child under RLIMIT_CPU and RLIMIT_AS, its answer through a pipe: 'S' and
// the SPIR-V, 'E' and an input error's message. A child stopped by a limit (or failing otherwise)
// is a DriverError naming the file and the limits (exit 3). The caller holds compileTechnique's
// lock, so no other thread of this process is inside glslang while it forks. Under AddressSanitizer
// (GCC 12's allocator has no fork handler) a fork while another thread allocates can leave the child
// blocked on a copied allocator lock until the wall limit: the CLI's one other thread at this point
// already waits in sigwait (app/main.cpp, cleanUpOnSignal).
std::shared_ptr<const CompiledTechnique> compileBounded(const TechniqueFile& t) {
#ifdef SHADOWLAB_TECHNIQUE_COMPILE_IN_PROCESS
  // The fuzz target (tests/fuzz/fuzz_technique.cpp): libFuzzer sees the coverage of this process
  // only, and bounds each input's time and memory itself.
  return compile(t);
#endif
  const auto t0 = std::chrono::steady_clock::now();
  int fds[2];
  if (::pipe2(fds, O_CLOEXEC) != 0) throw DriverError(std::string("pipe: ") + std::strerror(errno));
  const pid_t pid = ::fork();
  if (pid < 0) {
    ::close(fds[0]), ::close(fds[1]);
    throw DriverError(std::string("fork: ") + std::strerror(errno));
  }
  if (pid == 0) {
    ::close(fds[0]);
    rlimit cpu{kCompileCpuSeconds, kCompileCpuSeconds + 1};
    ::setrlimit(RLIMIT_CPU, &cpu);
    if (!kAddressSanitizer) {
      rlimit as{kCompileMiB << 20, kCompileMiB << 20};
      ::setrlimit(RLIMIT_AS, &as);
    }
    std::string reply;
    try {
      const auto c = compile(t);
      reply = "S" + std::string(reinterpret_cast<const char*>(c->spirv.data()), c->spirv.size() * 4);
    } catch (const InputError& e) {
      reply = std::string("E") + e.what();
    } catch (const std::bad_alloc&) {
      reply = "M";
    } catch (const std::exception& e) {
      reply = std::string("X") + e.what();
    }
    for (size_t at = 0; at < reply.size();) {
      const ssize_t n = ::write(fds[1], reply.data() + at, reply.size() - at);
      if (n <= 0) ::_exit(1);
      at += size_t(n);
    }
    ::_exit(0);  // no atexit handlers or destructors of the parent's state
  }
  ::close(fds[1]);
  std::string reply;
  bool timedOut = false;
  char buffer[1 << 16];
  for (;;) {
    const double left =
        kCompileWallSeconds - std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    pollfd p{fds[0], POLLIN, 0};
    const int ready = left > 0 ? ::poll(&p, 1, int(left * 1000) + 1) : 0;
    if (ready < 0 && errno == EINTR) continue;
    if (ready <= 0) {
      timedOut = true;
      break;
    }
    const ssize_t n = ::read(fds[0], buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    reply.append(buffer, size_t(n));
  }
  ::close(fds[0]);
  if (timedOut) ::kill(pid, SIGKILL);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  const bool clean = !timedOut && WIFEXITED(status) && WEXITSTATUS(status) == 0 && !reply.empty();
  if (clean && reply[0] == 'E') throw InputError(reply.substr(1));
  if (clean && reply[0] == 'S' && (reply.size() - 1) % 4 == 0) {
    auto out = std::make_shared<CompiledTechnique>();
    out->spirv.resize((reply.size() - 1) / 4);
    std::memcpy(out->spirv.data(), reply.data() + 1, reply.size() - 1);
    out->compileMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    return out;
  }
  std::string how = timedOut                            ? "ran past " + std::to_string(kCompileWallSeconds) + " s"
                    : WIFSIGNALED(status)               ? std::string("was stopped by ") + ::strsignal(WTERMSIG(status))
                    : reply == "M"                      ? "ran out of memory"
                    : !reply.empty() && reply[0] == 'X' ? "failed: " + reply.substr(1)
                                                        : "failed (exit " + std::to_string(WEXITSTATUS(status)) + ")";
  throw DriverError(t.path + ": error: compiling the technique " + how + "; the compile's limits are " + limitsText() +
                    " (raster/METHODS.md \"Your own technique\"): expected a smaller file");
}

}  // namespace

std::shared_ptr<const CompiledTechnique> compileTechnique(const TechniqueFile& technique) {
  static std::mutex mutex;
  static std::map<std::string, std::shared_ptr<const CompiledTechnique>> cache;  // by content hash
  std::lock_guard<std::mutex> lock(mutex);
  auto it = cache.find(technique.hash);
  if (it != cache.end()) return it->second;
  auto compiled = compileBounded(technique);
  checkInterface(compiled->spirv, technique);
  cache.emplace(technique.hash, compiled);
  return compiled;
}

}  // namespace shadowlab::raster
