// --light-path specs of `shadowlab stability` ("elevation_deg=60:10:11"), one per line.
#include "fuzz_support.h"
#include "shadowlab/scenes/light_path.h"

using namespace shadowlab;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  for (const std::string& line : fuzz::lines(std::string(reinterpret_cast<const char*>(data), size)))
    fuzz::expectOnlyInputErrors([&] {
      const LightPathAxis axis = parseLightPath(line);
      for (int k = 0; k < axis.frames; ++k) (void)axis.value(k);
    });
  return 0;
}
