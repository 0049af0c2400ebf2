// Sweep files and the --grid / --set strings of `shadowlab sweep`: the input is a sweep file, then
// a line "#--ARGS--", then one argument per line ("grid map.size=256,512" or "set filter=pcf").
// Each grid value of a method key goes through the method's own setter, as planSweep does.
#include "fuzz_support.h"
#include "shadowlab/compare/sweep.h"
#include "shadowlab/scenes/method.h"

using namespace shadowlab;

namespace {
bool isMethodKey(const std::string& key) {
  for (const std::string& k : methodKeys())
    if (k == key) return true;
  return false;
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::vector<std::string> parts = fuzz::split(data, size, "\n#--ARGS--\n");
  const std::string path = fuzz::writeFile("sweep.json", parts[0]);
  fuzz::expectOnlyInputErrors([&] {
    SweepSpec spec;
    loadSweepFile(path, spec);
  });
  if (parts.size() < 2) return 0;
  for (const std::string& line : fuzz::lines(parts[1])) {
    fuzz::expectOnlyInputErrors([&] {
      if (line.rfind("grid ", 0) == 0) {
        const SweepAxis axis = parseGridArgument(line.substr(5));
        if (!isMethodKey(axis.key)) return;
        for (const auto& value : axis.values) {
          Method m;  // as sweep_plan.cpp applies a value: text through the setter, JSON as typed
          if (value.is_string()) applyMethodSetting(m, axis.key, value.get<std::string>(), "--grid");
          else applyMethodJson(m, axis.key, value, "--grid");
        }
      } else if (line.rfind("set ", 0) == 0) {
        parseSetArgument(line.substr(4));
      }
    });
  }
  return 0;
}
