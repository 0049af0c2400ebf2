#pragma once
// resolve.frag's pipelines, one per specialization (resolve_abi.h's kSpec*), which the planes,
// resolve, lookup and evidence passes share, and the method's technique (method key technique):
// resolve.frag compiled with the file, one module per content hash.
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "passes/pass_common.h"
#include "vk/handle.h"

namespace shadowlab::raster {

// Whether the full resolve of a specialization writes the group's surface: with a light (the lookup
// after it reads it), not in the evidence pass (kSpecCompact).
bool resolveWritesSurface(const ResolveSpecialization& spec);
// Whether the lookup pass of a specialization reads the group's surface: it needs no normal (no
// normal offset, no receiver plane, no adaptive bias), the surface image holds the visible point (or
// its map coordinates).
bool lookupReadsSurface(const ResolveSpecialization& spec);

class ResolvePipelines {
 public:
  explicit ResolvePipelines(const vk::Context& context);
  // The current render's technique module, key (id and constants) and constants (the declared
  // keys' values, specialization constants kSpecCount + i), or none.
  void useTechnique(const vk::Context& context, const Method& method);
  const std::string& techniqueKey() const { return techniqueKey_; }
  // Keyed by the specialization and the technique's key (empty: the built-in resolve.frag). The
  // attachments follow from the specialization (lookup, planes, full resolve).
  VkPipeline pipeline(const PassContext& pc, const ResolveSpecialization& key);

 private:
  vk::ShaderModule resolveFrag_;
  std::map<std::pair<ResolveSpecialization, std::string>, vk::PipelineHandle> pipelines_;
  std::map<std::string, vk::ShaderModule> techniqueModules_;
  VkShaderModule techniqueModule_ = VK_NULL_HANDLE;
  std::string techniqueKey_;
  std::vector<uint32_t> techniqueConstants_;
};

}  // namespace shadowlab::raster
