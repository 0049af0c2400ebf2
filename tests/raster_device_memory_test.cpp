// A render whose images cannot fit on the device is refused before any image is allocated, naming
// the image, its size and the limit (raster/device_memory.h). The rule is tested on made-up limits
// (no test allocates gigabytes); the rasterizer's own list of images and limits on lavapipe.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "shadowlab/raster/device_memory.h"
#include "shadowlab/raster/raster.h"
#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/loader.h"
#include "support/raster_device.h"

namespace raster_device_memory_test {

using namespace shadowlab;

namespace {

constexpr uint64_t kGiB = uint64_t(1) << 30;

DeviceMemoryLimits lavapipeLike() {
  DeviceMemoryLimits l;
  l.deviceName = "fake";
  l.cpuDevice = true;
  l.deviceLocalHeapBytes = 2 * kGiB;
  l.maxAllocationBytes = 2 * kGiB;
  l.maxImageDimension2D = 16384;
  l.maxImageArrayLayers = 2048;
  return l;
}

DeviceImage map(int size, int layers, uint64_t bytesPerTexel) {
  return {"shadow map depth",
          "method",
          "map.size",
          size,
          size,
          layers,
          uint64_t(size) * uint64_t(size) * uint64_t(layers) * bytesPerTexel};
}

std::string refusal(const std::vector<DeviceImage>& images, const DeviceMemoryLimits& limits) {
  try {
    checkDeviceMemory(images, limits);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(DeviceMemory, DescribesAnImageWithItsTerms) {
  EXPECT_EQ(map(16384, 3, 4).describe(), "shadow map depth 16384^2 x 3 layers x 4 B = 3.00 GiB");
  EXPECT_EQ(map(2048, 1, 2).describe(), "shadow map depth 2048^2 x 1 layer x 2 B = 8.00 MiB");
  DeviceImage camera{"camera ids", "scene.json", "/camera", 1920, 1080, 1, 1920ull * 1080 * 4};
  EXPECT_EQ(camera.describe(), "camera ids 1920x1080 x 1 layer x 4 B = 7.91 MiB");
}

// The tracker's case: fit=cascades, 3 cascades, map.size=16384 on a device that allocates 2 GiB at
// once. 16384^2 x 3 x 4 B = 3 GiB does not fit; the largest map.size that does: floor(sqrt(2^31 /
// 12)) = 13377, 13376 as a multiple of 16.
TEST(DeviceMemory, RefusesAnImageAboveTheLargestAllocation) {
  const std::string e = refusal({map(16384, 3, 4)}, lavapipeLike());
  EXPECT_EQ(e,
            "method: map.size: error: shadow map depth 16384^2 x 3 layers x 4 B = 3.00 GiB is above the largest "
            "allocation device fake makes, 2.00 GiB (maxMemoryAllocationSize); expected a map.size of at most 13376 "
            "at 3 layers (or fewer layers: cascades.count)");
  // Exactly at the limit fits (one layer of 16384^2 x 8 B = 2 GiB), one texel row more does not.
  EXPECT_EQ(refusal({map(16384, 1, 8)}, lavapipeLike()), "");
  DeviceImage over = map(16384, 1, 8);
  over.bytes += 1;
  EXPECT_NE(refusal({over}, lavapipeLike()), "");
  // The suggested size fits.
  EXPECT_EQ(refusal({map(13376, 3, 4)}, lavapipeLike()), "");
}

TEST(DeviceMemory, RefusesMoreLayersThanTheDeviceAllows) {
  DeviceMemoryLimits l = lavapipeLike();
  l.maxImageArrayLayers = 4;
  EXPECT_EQ(refusal({map(64, 4, 4)}, l), "");
  const std::string e = refusal({map(64, 6, 4)}, l);
  EXPECT_NE(e.find("shadow map depth 64^2 x 6 layers"), std::string::npos) << e;
  EXPECT_NE(e.find("more layers than device fake allows (4, maxImageArrayLayers)"), std::string::npos) << e;
}

// A GPU's images share its device-local heap: their sum is checked there (the error names each
// term); a CPU device's heap is the machine's RAM, which the CLI's --max-memory covers.
TEST(DeviceMemory, ChecksTheSumAgainstAGpuHeapOnly) {
  DeviceMemoryLimits gpu = lavapipeLike();
  gpu.cpuDevice = false;
  gpu.deviceLocalHeapBytes = 4 * kGiB;
  const std::vector<DeviceImage> images = {map(16384, 1, 4), map(16384, 1, 4), map(16384, 1, 4), map(16384, 1, 4),
                                           map(16384, 1, 4)};  // 5 GiB, each 1 GiB
  const std::string e = refusal(images, gpu);
  EXPECT_NE(e.find("method: map.size: error: the device images need 5.00 GiB (shadow map depth 16384^2 x 1 layer "
                   "x 4 B = 1.00 GiB + "),
            std::string::npos)
      << e;
  EXPECT_NE(e.find("above device fake's device-local heap of 4.00 GiB"), std::string::npos) << e;
  EXPECT_EQ(refusal({images.begin(), images.begin() + 4}, gpu), "");  // exactly 4 GiB fits
  EXPECT_EQ(refusal(images, lavapipeLike()), "");                     // a CPU device: RAM's business
}

// On the device: the rasterizer lists its images with the device's sizes and refuses the tracker's
// configuration before it allocates anything (render() too, with the same message).
TEST(DeviceMemory, RasterizerRefusesTheTrackerCaseBeforeAllocating) {
  REQUIRE_DEVICE();
  const DeviceMemoryLimits limits = R->memoryLimits();
  EXPECT_GT(limits.maxAllocationBytes, 0u);
  EXPECT_GT(limits.deviceLocalHeapBytes, 0u);
  EXPECT_EQ(limits.maxImageDimension2D, uint32_t(R->maxMapSize()));
  Scene scene = loadScene(resolveScenePath("long_view"));
  scene.camera.width = 48;
  scene.camera.height = 32;
  Method method;
  method.fit = Fit::Cascades;
  method.cascadeCount = 3;
  method.mapSize = 2048;
  const std::vector<DeviceImage> images = R->plannedImages(scene, method);
  ASSERT_GE(images.size(), 2u);
  EXPECT_EQ(images[0].what, "shadow map depth");
  EXPECT_EQ(images[0].layers, 3);
  // d24 is 4 bytes a texel wherever it is X8_D24 or D24S8 (lavapipe: exactly that).
  EXPECT_GE(images[0].bytes, 2048ull * 2048 * 3 * 4);
  EXPECT_EQ(images[1].what, "shadow map ids");
  EXPECT_GE(images[1].bytes, 2048ull * 2048 * 3 * 4);
  EXPECT_NO_THROW(R->check(scene, method));

  method.mapSize = 16384;  // 3 GiB a map image
  const uint64_t mapBytes = R->plannedImages(scene, method)[0].bytes;
  if (mapBytes <= limits.maxAllocationBytes)
    GTEST_SKIP() << "device " << R->deviceName() << " allocates " << limits.maxAllocationBytes
                 << " bytes at once: the 3 GiB map fits there";
  for (int viaRender = 0; viaRender < 2; ++viaRender) {
    try {
      if (viaRender) R->render(scene, method);
      else R->check(scene, method);
      ADD_FAILURE() << "a map above the largest allocation was accepted";
    } catch (const InputError& e) {
      const std::string m = e.what();
      EXPECT_EQ(m.rfind("method: map.size: error: shadow map depth 16384^2 x 3 layers x ", 0), 0u) << m;
      EXPECT_NE(m.find("(maxMemoryAllocationSize); expected a map.size of at most "), std::string::npos) << m;
    }
  }
}

}  // namespace raster_device_memory_test
