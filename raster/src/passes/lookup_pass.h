#pragma once
// Pass 4 (lookup, with a light): resolve.frag specialized to the method's lookup alone
// (kSpecLookupOnly): the visibility as 1 byte per pixel (kLookupFormat; 0 and 255 only for
// exactly 0 and 1, the 0.5 threshold exact), the evidence compiled out; timed on its own
// (lookup_gpu_ms, what an engine pays for the method besides its shadow pass). A method that needs
// no normal reads the visible point from the group's surface (kSpecSurface), one fetch per pixel.
#include <cstdint>
#include <vector>

#include "passes/pass_common.h"

namespace shadowlab::raster {

class LookupPass {
 public:
  // The target of a width x height camera, host-readable.
  void ensureImages(const vk::Context& context, int width, int height);
  // Records the lookup and makes its bytes visible to the host.
  void record(VkCommandBuffer cmd, VkPipeline lookup, int width, int height, bool warmup) const;
  // The bytes, row-major: in place when the rows are not padded, else a copy without the padding.
  const uint8_t* bytes(const vk::Context& context);
  // A copy of the bytes (Rasterizer::lookupVisibility), empty before the first frame.
  std::vector<uint8_t> copy(const vk::Context& context) const;

 private:
  vk::Image out_;
  std::vector<uint8_t> rows_;  // the bytes when the image's rows are padded
};

}  // namespace shadowlab::raster
