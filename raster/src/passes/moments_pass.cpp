#include "passes/moments_pass.h"

#include <algorithm>

#include "moments_cols_frag.h"
#include "moments_rows_frag.h"
#include "vk/pipeline.h"

namespace shadowlab::raster {

namespace {
// The moment images kept across frames (MomentsPass::spare_): every vsm and msm pair of a 2048^2
// sweep (3 sizes x 2 formats, 252 MB) fits.
constexpr size_t kMomentsKeptBytes = size_t(384) << 20;
}  // namespace

VkFormat momentsFormat(Filter filter) {
  return momentCount(filter) == 4 ? VK_FORMAT_R32G32B32A32_SFLOAT : VK_FORMAT_R32G32_SFLOAT;
}

MomentsPass::MomentsPass(const vk::Context& context) {
  rowsFrag_ = vk::createShaderModule(context, kSpv_moments_rows_frag, sizeof(kSpv_moments_rows_frag));
  colsFrag_ = vk::createShaderModule(context, kSpv_moments_cols_frag, sizeof(kSpv_moments_cols_frag));
}

VkPipeline MomentsPass::pipeline(const PassContext& pc, Filter filter, bool cols) {
  auto key = std::make_pair(filter, cols);
  auto it = pipelines_.find(key);
  if (it != pipelines_.end()) return it->second.get();
  vk::GraphicsPipelineDesc d;
  d.vertex = pc.fullscreenVert;
  d.fragment = cols ? colsFrag_.get() : rowsFrag_.get();
  d.layout = pc.layout;
  d.depthTest = false;
  d.colorFormats = {momentsFormat(filter)};
  if (!cols) d.fragmentSpecialization = {uint32_t(filter)};  // kSpecFilter: which moments
  return pipelines_.emplace(key, vk::createGraphicsPipeline(*pc.context, d)).first->second.get();
}

void MomentsPass::ensureImages(const vk::Context& context, Filter filter, int mapSize, int lightLayers) {
  const VkImageUsageFlags usage = VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT;
  const VkFormat format = momentsFormat(filter);
  if (!isMomentFilter(filter)) {  // never read: any pair will do, the placeholders until there is one
    if (moments_.width() == 0) {
      rows_ = vk::Image(context, 1, 1, 1, format, usage, VK_IMAGE_ASPECT_COLOR_BIT);
      moments_ = vk::Image(context, 1, 1, 1, format, usage, VK_IMAGE_ASPECT_COLOR_BIT);
    }
    return;
  }
  const int size = mapSize, layers = std::max(1, lightLayers);
  auto fits = [&](const vk::Image& image) {
    return image.width() == size && image.layers() == layers && image.format() == format;
  };
  if (fits(moments_)) return;
  ++uses_;
  // Both images of a pair: size^2 texels per layer, RG32F or RGBA32F.
  auto pairBytes = [](int side, int count, VkFormat f) {
    return 2 * size_t(side) * size_t(side) * size_t(count) * (f == VK_FORMAT_R32G32B32A32_SFLOAT ? 16u : 8u);
  };
  if (moments_.width() > 1) {  // the pair in use becomes a spare (a placeholder is dropped)
    Pair spare;
    spare.lastUse = uses_;
    spare.rows = std::move(rows_);
    spare.map = std::move(moments_);
    spare_.push_back(std::move(spare));
  }
  rows_ = vk::Image();
  moments_ = vk::Image();
  for (auto it = spare_.begin(); it != spare_.end(); ++it)
    if (fits(it->map)) {
      rows_ = std::move(it->rows);
      moments_ = std::move(it->map);
      spare_.erase(it);
      return;
    }
  // A new pair: spares go, least recently used first, until it fits the budget beside them (all
  // of them before a pair over the budget: two sets of 4096^2 RGBA32F layers would not fit).
  const size_t need = pairBytes(size, layers, format);
  auto spareBytes = [&] {
    size_t n = 0;
    for (const Pair& p : spare_) n += pairBytes(p.map.width(), p.map.layers(), p.map.format());
    return n;
  };
  while (!spare_.empty() && spareBytes() + need > kMomentsKeptBytes)
    spare_.erase(std::min_element(spare_.begin(), spare_.end(),
                                  [](const Pair& a, const Pair& b) { return a.lastUse < b.lastUse; }));
  rows_ = vk::Image(context, size, size, layers, format, usage, VK_IMAGE_ASPECT_COLOR_BIT, false, "moments rows");
  moments_ = vk::Image(context, size, size, layers, format, usage, VK_IMAGE_ASPECT_COLOR_BIT, false, "moments map");
}

void MomentsPass::record(VkCommandBuffer cmd, const PassContext& pc, const Method& method, int lightLayers,
                         bool warmup) {
  const bool used = isMomentFilter(method.filter);
  const int size = moments_.width();
  auto fullscreen = [&](const vk::Image& target, int layer, VkPipeline pipeline) {
    const VkRenderingAttachmentInfo color =
        overwrittenColor(target.layerView(layer), VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL);
    drawFullscreen(
        cmd, &color, 1, uint32_t(size), uint32_t(size), pipeline,
        [&] {
          DrawPush push{glm::mat4(1.0f), uint32_t(layer), 0, 0, 0};
          vkCmdPushConstants(cmd, pc.layout, VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT, 0, sizeof(push),
                             &push);
        },
        warmup);
  };
  for (const vk::Image* target : {&rows_, &moments_}) {
    const bool cols = target == &moments_;
    if (used) {
      vk::transition(cmd, *target, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
                     VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, 0, VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
                     VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
      for (int layer = 0; layer < lightLayers; ++layer) fullscreen(*target, layer, pipeline(pc, method.filter, cols));
      vk::transition(cmd, *target, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
                     VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT,
                     VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, VK_ACCESS_2_SHADER_SAMPLED_READ_BIT);
    } else {
      vk::transition(cmd, *target, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
                     VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, 0, VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT,
                     VK_ACCESS_2_SHADER_SAMPLED_READ_BIT);
    }
  }
}

void MomentsPass::bind(const PassContext& pc, BindingResources& r) const {
  r[abi::kBindingMomentsRows].image =
      sampledImage(pc.nearest, rows_.arrayView(), VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
  r[abi::kBindingMoments].image =
      sampledImage(pc.linear, moments_.arrayView(), VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
}

}  // namespace shadowlab::raster
