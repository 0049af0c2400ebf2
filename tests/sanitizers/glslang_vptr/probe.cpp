// Compiles a technique through technique_compiler.cpp built under UBSan: that it links is the
// guard (raster/GlslangSanitize.cmake); that it runs without a report, the check's other parts.
#include "technique_compiler.h"

#include <cstdio>

int main() {
  shadowlab::TechniqueFile t;
  t.path = "probe.glsl";
  t.source = "float shadowVisibility(ShadowQuery q) {\n  return q.depth > 0.5 ? 1.0 : 0.0;\n}\n";
  t.hash = "0000000000000000";
  const auto compiled = shadowlab::raster::compileTechnique(t);
  std::printf("probe: %zu SPIR-V words\n", compiled->spirv.size());
  return compiled->spirv.empty() ? 1 : 0;
}
