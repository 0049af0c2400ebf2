// Technique files (raster/METHODS.md "Your own technique"): the input is a technique file, read and
// checked the way `technique=FILE` reads it (the header's keys and moments line, the text checks),
// and, when that accepts it, compiled with glslang into the harness's resolve.frag with the AST
// and interface checks, without a Vulkan device. Only InputErrors are expected.
#include "fuzz_support.h"
#include "shadowlab/scenes/technique.h"
#include "technique_compiler.h"

using namespace shadowlab;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const bool ready = [] {
    fuzz::requireGoodSetup("examples/techniques/pcf.glsl", [] {
      raster::compileTechnique(loadTechniqueFile(SHADOWLAB_SOURCE_DIR "/examples/techniques/pcf.glsl"));
    });
    return true;
  }();
  (void)ready;
  const std::string path = fuzz::writeFile("technique.glsl", std::string(reinterpret_cast<const char*>(data), size));
  fuzz::expectOnlyInputErrors([&] { raster::compileTechnique(loadTechniqueFile(path)); });
  return 0;
}
