#pragma once
// Pass 1b (moments, filterable maps only): per light layer, the moments of the map depths blurred
// along rows, then along columns (a separable Gaussian), into a moments map sampled with linear
// filtering (moments_rows/cols.frag). Its time is part of shadow_gpu_ms.
#include <map>
#include <utility>
#include <vector>

#include "passes/pass_common.h"
#include "vk/handle.h"

namespace shadowlab::raster {

// A filterable map's moments format: RG32F for 2 moments, RGBA32F for 4 (raster/METHODS.md).
VkFormat momentsFormat(Filter filter);

class MomentsPass {
 public:
  explicit MomentsPass(const vk::Context& context);
  // The pair of images `filter` needs at this size and layer count (a kept one where there is).
  void ensureImages(const vk::Context& context, Filter filter, int mapSize, int lightLayers);
  // Records both blurs of every light layer; without a filterable map, only makes the
  // placeholders readable.
  void record(VkCommandBuffer cmd, const PassContext& pc, const Method& method, int lightLayers, bool warmup);
  void bind(const PassContext& pc, BindingResources& r) const;

 private:
  VkPipeline pipeline(const PassContext& pc, Filter filter, bool cols);

  vk::ShaderModule rowsFrag_, colsFrag_;
  // Keyed by (filter, cols pass): the two pipelines per filterable filter.
  std::map<std::pair<Filter, bool>, vk::PipelineHandle> pipelines_;
  // The rows-blurred moments and the moments map, one layer per light layer (1x1 placeholders,
  // never read, until a filterable map needs them: every binding needs an image; the other
  // filters leave whatever pair is there).
  vk::Image rows_, moments_;
  // Pairs of other sizes, layer counts or formats, kept for when a sweep comes back to them (its
  // rows alternate vsm and msm, and map sizes): a new pair is fresh memory, whose first touch the
  // moments pass would pay inside its timestamps (~15 % of the main job's moments_gpu_ms).
  // At most kMomentsKeptBytes in all, with the pair in use; the least recently used goes first,
  // and a pair over the budget on its own is made alone, as before.
  struct Pair {
    vk::Image rows, map;
    uint64_t lastUse = 0;
  };
  std::vector<Pair> spare_;
  uint64_t uses_ = 0;
};

}  // namespace shadowlab::raster
