#pragma once
// VK_CHECK is always on (never an assert): a failing call throws DriverError carrying the
// expression, the VkResult name and file:line, so a driver failure reaches the CLI as exit 3.
#include <string>

#include <vulkan/vulkan.h>

namespace shadowlab::vk {

const char* resultName(VkResult result);
[[noreturn]] void throwVkError(const char* expression, VkResult result, const char* file, int line);

// A test-only switch: with SHADOWLAB_VK_FAIL=TEXT in the environment, every checked call whose
// expression contains TEXT (e.g. "vkQueueSubmit") is not made and reports VK_ERROR_DEVICE_LOST, as
// a call that failed, so a test can prove that a lost or failing device exits 3 naming the call
// instead of hanging or crashing. Unset, it costs one comparison: the variable is read once.
bool injectedFailure(const char* expression);

}  // namespace shadowlab::vk

#define VK_CHECK(expr)                                                                                          \
  do {                                                                                                          \
    VkResult vkCheckResult_ = ::shadowlab::vk::injectedFailure(#expr) ? VK_ERROR_DEVICE_LOST : (expr);          \
    if (vkCheckResult_ != VK_SUCCESS) ::shadowlab::vk::throwVkError(#expr, vkCheckResult_, __FILE__, __LINE__); \
  } while (0)
