// Method files and --set strings: the input is a method file, then a line "#--SET--", then one
// key=value per line, applied the way `shadowlab run --set` applies them.
#include "fuzz_support.h"
#include "shadowlab/scenes/method.h"

using namespace shadowlab;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::vector<std::string> parts = fuzz::split(data, size, "\n#--SET--\n");
  const std::string path = fuzz::writeFile("method.json", parts[0]);
  fuzz::expectOnlyInputErrors([&] { validateMethod(loadMethodFile(path), path); });
  if (parts.size() < 2) return 0;
  fuzz::expectOnlyInputErrors([&] {
    Method m;
    for (const std::string& line : fuzz::lines(parts[1])) {
      const size_t eq = line.find('=');
      if (eq == std::string::npos) continue;
      applyMethodSetting(m, line.substr(0, eq), line.substr(eq + 1), "--set");
    }
    validateMethod(m, "--set");
  });
  return 0;
}
