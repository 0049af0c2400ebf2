#pragma once
// A primary command buffer recorded once and submitted with a fence; the caller waits on it.
#include "vk/context.h"
#include "vk/handle.h"

namespace shadowlab::vk {

class Commands {
 public:
  // timeoutNs bounds every wait for a submission (a hung device, a shader that never returns).
  explicit Commands(const Context& context, uint64_t timeoutNs = 120ull * 1000000000ull);
  ~Commands();
  Commands(const Commands&) = delete;
  Commands& operator=(const Commands&) = delete;

  VkCommandBuffer begin();  // resets and begins recording
  void submitAndWait();     // ends, submits, waits for completion

 private:
  const Context& context_;
  VkCommandBuffer cmd_ = VK_NULL_HANDLE;
  Fence fence_;
  uint64_t timeoutNs_;
};

}  // namespace shadowlab::vk
