#pragma once
// Pass 1 (shadow): depth + ids (global triangle + 1) from the light into one layer per map (cube
// faces for point lights), then one layer per projector. Evidence on demand writes the stencil
// ids instead of the id attachment: each draw's object index + 1 in the map's stencil aspect (a
// depth-only pass's cost; up to kMaxStencilObjects objects, where the device has the format).
// The maps are kept while everything the pass reads stays the same (key()).
#include <map>
#include <string>
#include <vector>

#include "passes/id_draws.h"

namespace shadowlab::raster {

VkFormat vkDepthFormat(DepthFormat f);
// The map format with a stencil aspect beside the same depth bits: evidence on demand writes the
// occluder's object (index + 1) there instead of an id attachment (a depth-only pass's cost).
VkFormat vkDepthStencilFormat(DepthFormat f);

class ShadowPass {
 public:
  explicit ShadowPass(IdDraws& ids) : ids_(&ids) {}
  // Whether a frame of evidence on demand can take its occluder ids from the map's stencil: the
  // device renders and samples the map format's depth+stencil twin, and the scene's objects fit in
  // 8 bits (the uploaded scene's).
  bool stencilIdsApply(const vk::Context& context, const SceneGpu& scene, const Method& method);
  // The map layers in `format` (a depth+stencil one: the stencil ids); new images forget the key.
  void ensureImages(const vk::Context& context, int mapSize, VkFormat format, int layers);
  // The shadow side of `pipes`: for the map's format (ensureImages chose it) and depth clamp.
  void pipelines(const PassContext& pc, bool depthClamp, const std::vector<MapLayer>& layers, IdPipelines& pipes);
  // What the pass reads besides the scene's buffers: the map image and its format, the pipelines
  // (depth clamp, material tests, light depth, stencil ids), the depth bias and cull, and per
  // layer its clip matrix and light-depth row. Equal keys draw equal maps.
  std::string key(const SceneGpu& scene, const std::vector<LayerDraw>& layerDraws, const IdPipelines& pipes,
                  const Method& method) const;
  // Records every layer; the maps are left readable by the fragment shaders.
  void record(VkCommandBuffer cmd, const PassContext& pc, const SceneGpu& scene,
              const std::vector<LayerDraw>& layerDraws, const IdPipelines& pipes, const Method& method,
              bool warmup) const;
  void bind(const PassContext& pc, BindingResources& r) const;
  const vk::Image& mapDepth() const { return mapDepth_; }
  bool stencilIds() const { return mapDepth_.hasStencil(); }

  // Kept maps: the key of what the images hold (empty: nothing reusable; RasterDeviceOptions::
  // keepShadowMaps), and the layers' GPU time when they were drawn (part of shadow_gpu_ms).
  std::string keptKey;
  double layersGpuMs = 0;

 private:
  IdDraws* ids_;
  vk::Image mapDepth_, mapIds_;
  std::map<DepthFormat, bool> stencilFormatOk_;  // whether the device renders and samples it
};

}  // namespace shadowlab::raster
