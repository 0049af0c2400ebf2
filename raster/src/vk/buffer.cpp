#include "vk/buffer.h"

#include <cstring>

#include "shadowlab/raster/device_memory.h"
#include "vk/check.h"

namespace shadowlab::vk {

Buffer::Buffer(const Context& context, VkDeviceSize size, VkBufferUsageFlags usage) : size_(size) {
  VkDevice device = context.device();
  VkBufferCreateInfo info{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
  info.size = size > 0 ? size : 4;  // a zero-sized buffer is illegal; empty tables still bind
  info.usage = usage;
  info.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
  VkBuffer buffer;
  VK_CHECK(vkCreateBuffer(device, &info, nullptr, &buffer));
  buffer_ = BufferHandle(device, buffer);

  VkMemoryRequirements req;
  vkGetBufferMemoryRequirements(device, buffer, &req);
  // Cached memory makes the CPU readback of the output planes a plain memcpy speed read.
  uint32_t memoryType = 0;
  const std::string what = "a buffer of " + formatBytes(double(req.size));
  memory_ =
      context.allocate(req, VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT,
                       VK_MEMORY_PROPERTY_HOST_COHERENT_BIT | VK_MEMORY_PROPERTY_HOST_CACHED_BIT, &memoryType, what);
  VK_CHECK_ALLOC(vkBindBufferMemory(device, buffer, memory_.get(), 0), what, context.deviceName());
  VK_CHECK(vkMapMemory(device, memory_.get(), 0, VK_WHOLE_SIZE, 0, &mapped_));
  context.adviseHugePages(mapped_, req.size);
  coherent_ = context.hostCoherent(memoryType);
}

void Buffer::upload(const void* data, size_t bytes, size_t offset) {
  if (bytes) std::memcpy(static_cast<char*>(mapped_) + offset, data, bytes);
}

void Buffer::invalidate(const Context& context) const {
  if (!coherent_) context.invalidate(memory_.get());
}

}  // namespace shadowlab::vk
