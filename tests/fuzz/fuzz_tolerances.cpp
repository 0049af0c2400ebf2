// Tolerance files of `shadowlab gate --tolerances`.
#include "fuzz_support.h"
#include "shadowlab/compare/gate.h"

using namespace shadowlab;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = fuzz::writeFile("tolerances.json", std::string(reinterpret_cast<const char*>(data), size));
  fuzz::expectOnlyInputErrors([&] { loadTolerances(path); });
  return 0;
}
