// Real files nobody on this project wrote: Debian's assimp-testmodels (Assimp's test meshes, good
// and malformed), installed by scripts/install-deps.sh for the tests and never copied into the repo.
//
//   SHADOWLAB_REQUIRE_TEST_MODEL(path, "OBJ/concave_polygon.obj");   // declares std::string path
//
// A missing package skips the test loudly (the reason names the package); under CI=true a missing
// file is a failure, since the install script must have installed it.
#pragma once

#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>

namespace shadowlab::test {

// Where Debian installs the models; SHADOWLAB_TEST_MODELS overrides it (another distribution).
inline std::filesystem::path testModelsDir() {
  if (const char* dir = std::getenv("SHADOWLAB_TEST_MODELS"); dir && *dir) return dir;
  return "/usr/share/assimp/models";
}

inline bool runningInCi() {
  const char* ci = std::getenv("CI");
  return ci && (std::strcmp(ci, "true") == 0 || std::strcmp(ci, "1") == 0);
}

}  // namespace shadowlab::test

// Resolves RELATIVE under testModelsDir(); returns from the test (skipped, or failed under CI) when
// the file is missing. Use in a TEST body or a void helper.
#define SHADOWLAB_TEST_MODEL(RELATIVE)                                                              \
  ([&]() -> std::string {                                                                          \
    return (::shadowlab::test::testModelsDir() / (RELATIVE)).string();                             \
  }())
#define SHADOWLAB_REQUIRE_TEST_MODEL(VAR, RELATIVE)                                                 \
  std::string VAR = SHADOWLAB_TEST_MODEL(RELATIVE);                                                \
  if (!std::filesystem::exists(VAR)) {                                                             \
    if (::shadowlab::test::runningInCi())                                                          \
      FAIL() << "CI=true and the test model " << VAR                                               \
             << " is missing: scripts/install-deps.sh installs assimp-testmodels";                 \
    GTEST_SKIP() << "test model " << VAR                                                           \
                 << " is missing (Debian package assimp-testmodels; scripts/install-deps.sh)";     \
  }
