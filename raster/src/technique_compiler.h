#pragma once
// Technique files (method key `technique`) compiled at run time with glslang into resolve.frag:
// its source (embedded at build time) with SHADOWLAB_TECHNIQUE defined and the user's file included
// where filterVisibility calls it (raster/METHODS.md "Your own technique").
#include <cstdint>
#include <memory>
#include <vector>

#include "shadowlab/scenes/technique.h"

namespace shadowlab::raster {

struct CompiledTechnique {
  std::vector<uint32_t> spirv;  // resolve.frag with the technique: every pass's specialization of it
  double compileMs = 0;         // wall time of the compile (once per content: later calls return it cached)
};

// The SPIR-V of resolve.frag with `technique`, cached in memory by the file's content hash: a sweep
// compiles each technique once. Throws InputError "file:line:column: error: <glslang's message>"
// where the user's code does not compile (no SPIR-V, no pipeline: nothing is drawn or written).
std::shared_ptr<const CompiledTechnique> compileTechnique(const TechniqueFile& technique);

}  // namespace shadowlab::raster
