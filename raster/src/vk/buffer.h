#pragma once
// A buffer with its own memory, persistently mapped. Everything the rasterizer shares with the
// CPU lives in host-visible memory: on lavapipe all memory is host memory, and on a discrete GPU
// the buffers here are small (scene data) or read back once per frame (the output planes).
#include <cstddef>

#include "vk/context.h"
#include "vk/handle.h"

namespace shadowlab::vk {

class Buffer {
 public:
  Buffer() = default;
  Buffer(const Context& context, VkDeviceSize size, VkBufferUsageFlags usage);
  Buffer(Buffer&&) noexcept = default;
  Buffer& operator=(Buffer&&) noexcept = default;

  VkBuffer get() const { return buffer_.get(); }
  VkDeviceSize size() const { return size_; }
  void* mapped() const { return mapped_; }
  void upload(const void* data, size_t bytes, size_t offset = 0);
  // Makes GPU writes visible to mapped() when the memory is not host-coherent.
  void invalidate(const Context& context) const;

 private:
  BufferHandle buffer_;
  Memory memory_;
  VkDeviceSize size_ = 0;
  void* mapped_ = nullptr;
  bool coherent_ = true;
};

}  // namespace shadowlab::vk
