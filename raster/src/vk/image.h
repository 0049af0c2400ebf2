#pragma once
// A 2D (array) image in device memory with one view over all layers (for sampling) and one
// 2D view per layer (for rendering into that layer). A depth+stencil image's array view is its
// depth aspect; stencilView() is the stencil aspect's (both sampled); its layer views hold both.
#include <vector>

#include "vk/context.h"
#include "vk/handle.h"

namespace shadowlab::vk {

class Image {
 public:
  Image() = default;
  // hostReadable: linear tiling in host-visible memory, mapped (one layer): the CPU reads the
  // texels in place at mapped() + y * rowPitch(), no copy to a buffer first. Throws DriverError
  // when the device cannot render to such an image. `label` names it in an out-of-memory error
  // ("shadow map depth"; check.h's VK_CHECK_ALLOC).
  Image(const Context& context, int width, int height, int layers, VkFormat format, VkImageUsageFlags usage,
        VkImageAspectFlags aspect, bool hostReadable = false, const char* label = "an image");
  Image(Image&&) noexcept = default;
  Image& operator=(Image&&) noexcept = default;

  VkImage get() const { return image_.get(); }
  VkImageView arrayView() const { return arrayView_.get(); }
  VkImageView stencilView() const { return stencilView_.get(); }  // depth+stencil images only
  bool hasStencil() const { return (aspect_ & VK_IMAGE_ASPECT_STENCIL_BIT) != 0; }
  VkImageView layerView(int layer) const { return layerViews_[size_t(layer)].get(); }
  int width() const { return width_; }
  int height() const { return height_; }
  int layers() const { return layers_; }
  VkFormat format() const { return format_; }
  VkImageAspectFlags aspect() const { return aspect_; }
  VkImageSubresourceRange range() const { return {aspect_, 0, 1, 0, uint32_t(layers_)}; }
  const void* mapped() const { return mapped_; }  // hostReadable images only
  size_t rowPitch() const { return rowPitch_; }
  // Makes device writes visible to mapped() when the memory is not host-coherent.
  void invalidate(const Context& context) const;

 private:
  ImageHandle image_;
  Memory memory_;
  ImageView arrayView_, stencilView_;
  std::vector<ImageView> layerViews_;
  int width_ = 0, height_ = 0, layers_ = 0;
  VkFormat format_ = VK_FORMAT_UNDEFINED;
  VkImageAspectFlags aspect_ = 0;
  void* mapped_ = nullptr;
  size_t rowPitch_ = 0;
  bool coherent_ = true;
};

// One image layout transition (synchronization2), whole image.
void transition(VkCommandBuffer cmd, const Image& image, VkImageLayout from, VkImageLayout to,
                VkPipelineStageFlags2 srcStage, VkAccessFlags2 srcAccess, VkPipelineStageFlags2 dstStage,
                VkAccessFlags2 dstAccess);

}  // namespace shadowlab::vk
