#pragma once
// Running the real `shadowlab` binary (SHADOWLAB_BINARY) from a test: its exit code, stdout and
// stderr. Each caller passes its own folder for the captured streams (ctest -j runs tests side by side).
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace shadowlab::testing {

inline std::string slurp(const std::filesystem::path& p) {
  std::ifstream f(p);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

// A fresh, empty folder in the system's temporary folder, named for the test and this process
// (ctest -j runs test processes side by side).
inline std::filesystem::path freshTempDir(const std::string& name) {
  const std::filesystem::path d = std::filesystem::temp_directory_path() / (name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(d);
  std::filesystem::create_directories(d);
  return d;
}

struct CliRun {
  int code = -1;  // the exit status; -1 when the process did not exit normally (a crash)
  std::string out, err;
};

// Runs `PREFIX SHADOWLAB_BINARY ARGS` through the shell (ARGS is a shell line: quote paths with
// spaces), with stdout and stderr captured in `dir`/stdout.txt and `dir`/stderr.txt.
inline CliRun runShadowlab(const std::string& args, const std::filesystem::path& dir, const std::string& prefix = "") {
  const std::filesystem::path out = dir / "stdout.txt", err = dir / "stderr.txt";
  const std::string cmd =
      prefix + std::string(SHADOWLAB_BINARY) + " " + args + " >'" + out.string() + "' 2>'" + err.string() + "'";
  const int status = std::system(cmd.c_str());
  CliRun r;
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = slurp(out);
  r.err = slurp(err);
  return r;
}

}  // namespace shadowlab::testing
