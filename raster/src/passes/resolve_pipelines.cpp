#include "passes/resolve_pipelines.h"

#include "resolve_frag.h"
#include "shadowlab/scenes/technique.h"
#include "technique_compiler.h"
#include "vk/pipeline.h"

namespace shadowlab::raster {

bool resolveWritesSurface(const ResolveSpecialization& spec) {
  return spec[abi::kSpecLightType] != uint32_t(abi::kLightNone) && !spec[abi::kSpecCompact];
}

bool lookupReadsSurface(const ResolveSpecialization& spec) {
  return spec[abi::kSpecLightType] != uint32_t(abi::kLightNone) && !spec[abi::kSpecNormalOffset] &&
         !spec[abi::kSpecReceiverPlane] && !spec[abi::kSpecAdaptive] && !spec[abi::kSpecTechniqueNormal];
}

ResolvePipelines::ResolvePipelines(const vk::Context& context) {
  resolveFrag_ = vk::createShaderModule(context, kSpv_resolve_frag, sizeof(kSpv_resolve_frag));
}

void ResolvePipelines::useTechnique(const vk::Context& context, const Method& method) {
  techniqueModule_ = VK_NULL_HANDLE;
  techniqueKey_.clear();
  techniqueConstants_.clear();
  if (method.technique.empty()) return;
  const TechniqueFile& t = loadTechniqueFile(method.technique);
  auto it = techniqueModules_.find(t.hash);
  if (it == techniqueModules_.end()) {
    auto compiled = compileTechnique(t);
    it = techniqueModules_
             .emplace(t.hash, vk::createShaderModule(context, compiled->spirv.data(), compiled->spirv.size() * 4))
             .first;
  }
  techniqueModule_ = it->second.get();
  techniqueKey_ = t.hash;
  for (const TechniqueParam& p : t.params) {
    auto v = method.techniqueParams.find(p.name);
    techniqueConstants_.push_back(
        techniqueParamBits(p, v == method.techniqueParams.end() ? p.defaultValue : v->second));
    techniqueKey_ += "/" + std::to_string(techniqueConstants_.back());
  }
}

VkPipeline ResolvePipelines::pipeline(const PassContext& pc, const ResolveSpecialization& key) {
  // The technique replaces the filter where one runs: not in the planes pass, not without a light.
  const bool technique =
      techniqueModule_ && !key[abi::kSpecPlanesOnly] && key[abi::kSpecLightType] != uint32_t(abi::kLightNone);
  const std::pair<ResolveSpecialization, std::string> mapKey(key, technique ? techniqueKey_ : std::string());
  auto it = pipelines_.find(mapKey);
  if (it != pipelines_.end()) return it->second.get();
  vk::GraphicsPipelineDesc d;
  d.vertex = pc.fullscreenVert;
  d.fragment = technique ? techniqueModule_ : resolveFrag_.get();
  d.layout = pc.layout;
  d.depthTest = false;
  if (key[abi::kSpecLookupOnly]) d.colorFormats = {key[abi::kSpecCompact] ? kResolveFormats[0] : kLookupFormat};
  else if (key[abi::kSpecPlanesOnly]) d.colorFormats = {kResolveFormats[0], kSurfaceFormat};
  else {
    d.colorFormats.assign(kResolveFormats, kResolveFormats + resolveAttachments(Filter(key[abi::kSpecFilter])));
    if (resolveWritesSurface(key))
      d.colorFormats.push_back(kSurfaceFormat);  // the group's surface, for the lookup after it
  }
  d.fragmentSpecialization.assign(key.begin(), key.end());  // straight-line code per case
  if (technique)
    d.fragmentSpecialization.insert(d.fragmentSpecialization.end(), techniqueConstants_.begin(),
                                    techniqueConstants_.end());
  return pipelines_.emplace(mapKey, vk::createGraphicsPipeline(*pc.context, d)).first->second.get();
}

}  // namespace shadowlab::raster
