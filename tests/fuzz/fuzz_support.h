#pragma once
// Shared by the libFuzzer targets (tests/fuzz/fuzz_*.cpp): the loaders take paths, so each input is
// written to a file in a per-process temporary folder first. An InputError is the parser doing its
// job (a clear message for a bad file); any other exception escapes and libFuzzer reports it as a
// crash, like a sanitizer report or a hang.
#include <stdlib.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "shadowlab/scenes/error.h"

namespace shadowlab::fuzz {

// The folder, made once and removed at exit (it holds only this process's inputs).
inline const std::filesystem::path& workDir() {
  static const std::filesystem::path dir = [] {
    std::string tmpl = (std::filesystem::temp_directory_path() / "shadowlab_fuzz_XXXXXX").string();
    if (!::mkdtemp(tmpl.data())) std::abort();
    std::atexit([] {
      std::error_code ec;
      std::filesystem::remove_all(workDir(), ec);
    });
    return std::filesystem::path(tmpl);
  }();
  return dir;
}

inline std::string writeFile(const std::string& name, const std::string& bytes) {
  const std::filesystem::path p = workDir() / name;
  std::ofstream(p, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
  return p.string();
}

// The input split at each `separator` line (a target that feeds two files or a file plus
// arguments takes its parts this way; the seeds use the same separator).
inline std::vector<std::string> split(const uint8_t* data, size_t size, const std::string& separator) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  std::vector<std::string> parts;
  size_t start = 0;
  for (size_t at; (at = text.find(separator, start)) != std::string::npos; start = at + separator.size())
    parts.push_back(text.substr(start, at - start));
  parts.push_back(text.substr(start));
  return parts;
}

// Lines of `text`, without their '\n'.
inline std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> out;
  size_t start = 0;
  for (size_t at; (at = text.find('\n', start)) != std::string::npos; start = at + 1)
    out.push_back(text.substr(start, at - start));
  if (start < text.size()) out.push_back(text.substr(start));
  return out;
}

// The harness's fixed files must load with a good input, or every mutated input would fail before
// reaching the parser under test and the run would prove nothing: checked once at start.
template <class F>
void requireGoodSetup(const char* what, F&& load) {
  try {
    load();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fuzz harness: %s does not load with a good input: %s\n", what, e.what());
    std::abort();
  }
}

// Runs `parse`; the input errors a user would see are expected, anything else is a finding.
template <class F>
void expectOnlyInputErrors(F&& parse) {
  try {
    parse();
  } catch (const InputError&) {
  }
}

}  // namespace shadowlab::fuzz
