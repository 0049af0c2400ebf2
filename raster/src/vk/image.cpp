#include "vk/image.h"

#include "shadowlab/raster/device_memory.h"
#include "shadowlab/scenes/error.h"
#include "vk/check.h"

namespace shadowlab::vk {

Image::Image(const Context& context, int width, int height, int layers, VkFormat format, VkImageUsageFlags usage,
             VkImageAspectFlags aspect, bool hostReadable, const char* label)
    : width_(width), height_(height), layers_(layers), format_(format), aspect_(aspect) {
  VkDevice device = context.device();
  if (hostReadable) {
    VkFormatProperties fp;
    vkGetPhysicalDeviceFormatProperties(context.physical(), format, &fp);
    VkFormatFeatureFlags need = 0;
    if (usage & VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT) need |= VK_FORMAT_FEATURE_COLOR_ATTACHMENT_BIT;
    if (usage & VK_IMAGE_USAGE_SAMPLED_BIT) need |= VK_FORMAT_FEATURE_SAMPLED_IMAGE_BIT;
    if ((fp.linearTilingFeatures & need) != need || layers != 1)
      throw DriverError("device " + context.deviceName() + " cannot render to linear images of format " +
                        std::to_string(int(format)));
  }
  VkImageCreateInfo info{VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
  info.imageType = VK_IMAGE_TYPE_2D;
  info.format = format;
  info.extent = {uint32_t(width), uint32_t(height), 1};
  info.mipLevels = 1;
  info.arrayLayers = uint32_t(layers);
  info.samples = VK_SAMPLE_COUNT_1_BIT;
  info.tiling = hostReadable ? VK_IMAGE_TILING_LINEAR : VK_IMAGE_TILING_OPTIMAL;
  info.usage = usage;
  info.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
  info.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
  // What an out-of-memory error names: "shadow map depth 16384x16384 x 3 layers = 3.00 GiB".
  const std::string shape = std::string(label) + " " + std::to_string(width) + "x" + std::to_string(height) + " x " +
                            std::to_string(layers) + (layers == 1 ? " layer" : " layers");
  VkImage image;
  VK_CHECK_ALLOC(vkCreateImage(device, &info, nullptr, &image), shape, context.deviceName());
  image_ = ImageHandle(device, image);

  VkMemoryRequirements req;
  vkGetImageMemoryRequirements(device, image, &req);
  const std::string what = shape + " = " + formatBytes(double(req.size));
  uint32_t memoryType = 0;
  memory_ = hostReadable ? context.allocate(req, VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT,
                                            VK_MEMORY_PROPERTY_HOST_CACHED_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT,
                                            &memoryType, what)
                         : context.allocate(req, 0, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT, &memoryType, what);
  VkDeviceMemory memory = memory_.get();
  VK_CHECK_ALLOC(vkBindImageMemory(device, image, memory, 0), what, context.deviceName());
  if (!hostReadable && context.properties().deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU &&
      context.hostVisible(memoryType)) {
    // Mapped only to reach the pages (Context::adviseHugePages); a GPU's memory is left alone.
    void* p = nullptr;
    if (vkMapMemory(device, memory, 0, VK_WHOLE_SIZE, 0, &p) == VK_SUCCESS) {
      context.adviseHugePages(p, req.size);
      vkUnmapMemory(device, memory);
    }
  }
  if (hostReadable) {
    VkImageSubresource sub{aspect, 0, 0};
    VkSubresourceLayout layout;
    vkGetImageSubresourceLayout(device, image, &sub, &layout);
    VK_CHECK(vkMapMemory(device, memory, 0, VK_WHOLE_SIZE, 0, &mapped_));
    context.adviseHugePages(mapped_, req.size);
    mapped_ = static_cast<char*>(mapped_) + layout.offset;
    rowPitch_ = size_t(layout.rowPitch);
    coherent_ = context.hostCoherent(memoryType);
  }

  auto makeView = [&](VkImageViewType type, int first, int count, VkImageAspectFlags viewAspect) {
    VkImageViewCreateInfo v{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
    v.image = image;
    v.viewType = type;
    v.format = format;
    v.subresourceRange = {viewAspect, 0, 1, uint32_t(first), uint32_t(count)};
    VkImageView view;
    VK_CHECK(vkCreateImageView(device, &v, nullptr, &view));
    return ImageView(device, view);
  };
  // A sampled view holds one aspect: a depth+stencil image's depth, and its stencil on its own.
  const bool depthStencil = hasStencil() && (aspect & VK_IMAGE_ASPECT_DEPTH_BIT);
  arrayView_ = makeView(VK_IMAGE_VIEW_TYPE_2D_ARRAY, 0, layers,
                        depthStencil ? VkImageAspectFlags(VK_IMAGE_ASPECT_DEPTH_BIT) : aspect);
  if (depthStencil) stencilView_ = makeView(VK_IMAGE_VIEW_TYPE_2D_ARRAY, 0, layers, VK_IMAGE_ASPECT_STENCIL_BIT);
  for (int i = 0; i < layers; ++i) layerViews_.push_back(makeView(VK_IMAGE_VIEW_TYPE_2D, i, 1, aspect));
}

void Image::invalidate(const Context& context) const {
  if (mapped_ && !coherent_) context.invalidate(memory_.get());
}

void transition(VkCommandBuffer cmd, const Image& image, VkImageLayout from, VkImageLayout to,
                VkPipelineStageFlags2 srcStage, VkAccessFlags2 srcAccess, VkPipelineStageFlags2 dstStage,
                VkAccessFlags2 dstAccess) {
  VkImageMemoryBarrier2 b{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER_2};
  b.srcStageMask = srcStage;
  b.srcAccessMask = srcAccess;
  b.dstStageMask = dstStage;
  b.dstAccessMask = dstAccess;
  b.oldLayout = from;
  b.newLayout = to;
  b.srcQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  b.image = image.get();
  b.subresourceRange = image.range();
  VkDependencyInfo dep{VK_STRUCTURE_TYPE_DEPENDENCY_INFO};
  dep.imageMemoryBarrierCount = 1;
  dep.pImageMemoryBarriers = &b;
  vkCmdPipelineBarrier2(cmd, &dep);
}

}  // namespace shadowlab::vk
