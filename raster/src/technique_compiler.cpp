// Run-time compile of technique files (technique_compiler.h) with glslang's library: the same
// front end and SPIR-V back end as the build's glslangValidator, on resolve.frag's embedded text.
#include "technique_compiler.h"

#include <chrono>
#include <cstdio>
#include <cstring>
#include <map>
#include <mutex>
#include <regex>
#include <sstream>
#include <string>

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

// The column of glslang's error on `line` of the user's text (glslang 12 reports lines only): where
// its quoted token first appears there, or for a syntax error the unexpected token's character;
// else 1.
size_t columnOf(const std::string& source, size_t line, const std::string& token, const std::string& message) {
  size_t start = 0;
  for (size_t l = 1; l < line && start != std::string::npos; ++l) {
    start = source.find('\n', start);
    if (start != std::string::npos) ++start;
  }
  if (start == std::string::npos) return 1;
  const std::string text = source.substr(start, source.find('\n', start) - start);
  std::string needle = token;
  static const std::map<std::string, std::string> kTokens = {
      {"SEMICOLON", ";"},     {"RIGHT_PAREN", ")"}, {"LEFT_PAREN", "("}, {"RIGHT_BRACE", "}"}, {"LEFT_BRACE", "{"},
      {"RIGHT_BRACKET", "]"}, {"COMMA", ","},       {"EQUAL", "="},      {"DOT", "."}};
  if (needle.empty()) {
    const size_t at = message.find("unexpected ");
    if (at != std::string::npos) {
      auto it = kTokens.find(message.substr(at + 11, message.find_first_of(" ,", at + 11) - at - 11));
      if (it != kTokens.end()) needle = it->second;
    }
  }
  const size_t col = needle.empty() ? std::string::npos : text.find(needle);
  return col == std::string::npos ? 1 : col + 1;
}

// glslang's log ("ERROR: <name>:<line>: '<token>' : <message>") as "file:line:column: error: ..."
// lines; the user's file's errors only, unless the harness's code alone failed.
std::string userErrors(const std::string& log, const TechniqueFile& t) {
  static const std::regex line(R"(^ERROR: (.*?):(\d+): '(.*?)' :\s+(.*?)\s*$)");
  std::istringstream in(log);
  std::string text, mine, harness;
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
    else harness += file + ":" + std::to_string(lineNo) + ": " + what + "\n";
  }
  if (!mine.empty()) return mine.substr(0, mine.size() - 1);
  // Only the harness's code failed: a name the file defines that resolve.frag defines too, or an
  // error glslang places after the file. Said at the file, with glslang's words.
  return t.path + ":1:1: error: resolve.frag does not compile with this file: " +
         (harness.empty() ? log : harness.substr(0, harness.size() - 1));
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
  auto out = std::make_shared<CompiledTechnique>();
  glslang::SpvOptions options;
  options.disableOptimizer = true;  // as glslangValidator -V without -Os
  glslang::GlslangToSpv(*program.getIntermediate(EShLangFragment), out->spirv, &options);
  out->compileMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

}  // namespace

std::shared_ptr<const CompiledTechnique> compileTechnique(const TechniqueFile& technique) {
  static std::mutex mutex;
  static std::map<std::string, std::shared_ptr<const CompiledTechnique>> cache;  // by content hash
  std::lock_guard<std::mutex> lock(mutex);
  auto it = cache.find(technique.hash);
  if (it != cache.end()) return it->second;
  auto compiled = compile(technique);
  cache.emplace(technique.hash, compiled);
  return compiled;
}

}  // namespace shadowlab::raster
