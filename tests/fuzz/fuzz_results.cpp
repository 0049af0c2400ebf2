// Results and metrics files (gate inputs and baselines): one file read as a result file and as
// result rows, then gated against itself with the default tolerances, as `shadowlab gate` does.
#include "fuzz_support.h"
#include "shadowlab/compare/gate.h"
#include "shadowlab/compare/results.h"

using namespace shadowlab;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = fuzz::writeFile("results.json", std::string(reinterpret_cast<const char*>(data), size));
  fuzz::expectOnlyInputErrors([&] {
    const ResultFile file = loadResultFile(path);
    const GateResult result = runGate(file, file, defaultTolerances());
    (void)formatGateTable(result, false);
    (void)gateToJunitXml(result);
  });
  fuzz::expectOnlyInputErrors([&] { loadResultRows(path); });
  return 0;
}
