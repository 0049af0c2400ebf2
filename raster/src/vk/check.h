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
// instead of hanging or crashing. SHADOWLAB_VK_FAIL=TEXT=VK_ERROR_OUT_OF_DEVICE_MEMORY (or
// VK_ERROR_OUT_OF_HOST_MEMORY) reports that result instead. Unset, it costs one comparison: the
// variable is read once. Returns VK_SUCCESS where nothing is injected.
VkResult injectedResult(const char* expression);
inline bool injectedFailure(const char* expression) { return injectedResult(expression) != VK_SUCCESS; }

// An allocation that ran out of memory: DriverError (exit 3) with a plain message naming what was
// being allocated and its size, the result and the call, and no source path:
//   device llvmpipe could not allocate shadow map depth 16384x16384 x 3 layers = 3.00 GiB
//   (VK_ERROR_OUT_OF_DEVICE_MEMORY at vkBindImageMemory); lower map.size, cascades.count or ...
// Any other failure is VK_CHECK's (its expression, result and file:line).
[[noreturn]] void throwAllocationError(const char* expression, VkResult result, const std::string& what,
                                       const std::string& device, const char* file, int line);

// Under AddressSanitizer only (a no-op otherwise): marks every library loaded by now RTLD_NODELETE,
// so a Vulkan driver that the loader dlcloses stays mapped and LeakSanitizer still sees the blocks
// its one-time init keeps (raster/src/vk/context.cpp). Call it after the loader has loaded drivers.
void keepLoadedLibrariesMapped();

}  // namespace shadowlab::vk

// VK_CHECK for a call that allocates device memory (vkCreateImage, vkAllocateMemory,
// vkBind*Memory): `what` (evaluated on failure only) names the allocation and its size.
#define VK_CHECK_ALLOC(expr, what, device)                                                                \
  do {                                                                                                    \
    VkResult vkCheckResult_ = ::shadowlab::vk::injectedResult(#expr);                                     \
    if (vkCheckResult_ == VK_SUCCESS) vkCheckResult_ = (expr);                                            \
    if (vkCheckResult_ != VK_SUCCESS)                                                                     \
      ::shadowlab::vk::throwAllocationError(#expr, vkCheckResult_, (what), (device), __FILE__, __LINE__); \
  } while (0)

#define VK_CHECK(expr)                                                                                          \
  do {                                                                                                          \
    VkResult vkCheckResult_ = ::shadowlab::vk::injectedResult(#expr);                                           \
    if (vkCheckResult_ == VK_SUCCESS) vkCheckResult_ = (expr);                                                  \
    if (vkCheckResult_ != VK_SUCCESS) ::shadowlab::vk::throwVkError(#expr, vkCheckResult_, __FILE__, __LINE__); \
  } while (0)
