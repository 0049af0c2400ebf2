#include "passes/lookup_pass.h"

#include <algorithm>
#include <cstring>

namespace shadowlab::raster {

void LookupPass::ensureImages(const vk::Context& c, int width, int height) {
  if (out_.width() == width && out_.height() == height) return;
  out_ = vk::Image(c, width, height, 1, kLookupFormat, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT, VK_IMAGE_ASPECT_COLOR_BIT,
                   true, "camera lookup target");
}

void LookupPass::record(VkCommandBuffer cmd, VkPipeline lookup, int width, int height, bool warmup) const {
  vk::transition(cmd, out_, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL, VK_PIPELINE_STAGE_2_HOST_BIT, 0,
                 VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
  const VkRenderingAttachmentInfo color = overwrittenColor(out_.layerView(0), VK_IMAGE_LAYOUT_GENERAL);
  drawFullscreen(cmd, &color, 1, uint32_t(width), uint32_t(height), lookup, {}, warmup);
  barrierToHost(cmd, VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT | VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
                VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT | VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
}

const uint8_t* LookupPass::bytes(const vk::Context& context) {
  const int width = out_.width(), height = out_.height();
  out_.invalidate(context);
  // The bytes in place when the rows are not padded (the mapped image is the row-major plane).
  const uint8_t* vis8 = static_cast<const uint8_t*>(out_.mapped());
  if (out_.rowPitch() == size_t(width)) return vis8;
  rows_.resize(size_t(width) * size_t(height));
  for (int y = 0; y < height; ++y)
    std::memcpy(rows_.data() + size_t(y) * size_t(width), vis8 + size_t(y) * out_.rowPitch(), size_t(width));
  return rows_.data();
}

std::vector<uint8_t> LookupPass::copy(const vk::Context& context) const {
  std::vector<uint8_t> out;
  if (!out_.mapped()) return out;
  out_.invalidate(context);
  out.resize(size_t(out_.width()) * size_t(out_.height()));
  for (int y = 0; y < out_.height(); ++y) {
    const uint8_t* row = mappedRow<uint8_t>(out_, size_t(y));
    std::copy(row, row + out_.width(), out.data() + size_t(y) * size_t(out_.width()));
  }
  return out;
}

}  // namespace shadowlab::raster
