#include "shadowlab/raster/device_memory.h"

#include <cmath>
#include <cstdio>

#include "shadowlab/scenes/error.h"

namespace shadowlab {

std::string formatBytes(double bytes) {
  constexpr double kKiB = 1024.0, kMiB = 1024.0 * kKiB, kGiB = 1024.0 * kMiB;
  char buf[48];
  if (bytes >= kGiB) std::snprintf(buf, sizeof buf, "%.2f GiB", bytes / kGiB);
  else if (bytes >= kMiB) std::snprintf(buf, sizeof buf, "%.2f MiB", bytes / kMiB);
  else if (bytes >= kKiB) std::snprintf(buf, sizeof buf, "%.2f KiB", bytes / kKiB);
  else std::snprintf(buf, sizeof buf, "%.0f B", bytes);
  return buf;
}

std::string DeviceImage::describe() const {
  const double texels = double(width) * double(height) * double(layers);
  const double perTexel = texels > 0 ? double(bytes) / texels : 0.0;
  char perTexelText[32];
  std::snprintf(perTexelText, sizeof perTexelText, "%.3g", perTexel);
  const std::string side =
      width == height ? std::to_string(width) + "^2" : std::to_string(width) + "x" + std::to_string(height);
  return what + " " + side + " x " + std::to_string(layers) + (layers == 1 ? " layer" : " layers") + " x " +
         perTexelText + " B = " + formatBytes(double(bytes));
}

namespace {

// The largest square side (a multiple of 16) whose `layers` layers at the image's bytes per texel
// stay within `limit` bytes.
int largestSide(const DeviceImage& image, double limit) {
  const double bytesPerSquareTexel = double(image.bytes) / (double(image.width) * double(image.height));
  const int side = int(std::floor(std::sqrt(limit / bytesPerSquareTexel)));
  return side / 16 * 16;
}

std::string layerKeyHint(const DeviceImage& image) {
  return image.layers > 1 ? " at " + std::to_string(image.layers) + " layers (or fewer layers: cascades.count)" : "";
}

}  // namespace

void checkDeviceMemory(const std::vector<DeviceImage>& images, const DeviceMemoryLimits& limits) {
  const std::string device = limits.deviceName.empty() ? std::string("the device") : "device " + limits.deviceName;
  for (const DeviceImage& image : images) {
    if (limits.maxImageArrayLayers > 0 && uint32_t(image.layers) > limits.maxImageArrayLayers)
      throw InputError(formatError(image.origin, image.place,
                                   image.describe() + " has more layers than " + device + " allows (" +
                                       std::to_string(limits.maxImageArrayLayers) + ", maxImageArrayLayers)"));
    if (limits.maxImageDimension2D > 0 &&
        (uint32_t(image.width) > limits.maxImageDimension2D || uint32_t(image.height) > limits.maxImageDimension2D))
      throw InputError(formatError(image.origin, image.place,
                                   image.describe() + " is wider than " + device + " allows (" +
                                       std::to_string(limits.maxImageDimension2D) + ", maxImageDimension2D)"));
    if (limits.maxAllocationBytes > 0 && image.bytes > limits.maxAllocationBytes) {
      std::string expected = "expected at most " + formatBytes(double(limits.maxAllocationBytes)) + " per image";
      if (image.place == "map.size" && image.width == image.height)
        expected = "expected a map.size of at most " +
                   std::to_string(largestSide(image, double(limits.maxAllocationBytes))) + layerKeyHint(image);
      throw InputError(formatError(image.origin, image.place,
                                   image.describe() + " is above the largest allocation " + device + " makes, " +
                                       formatBytes(double(limits.maxAllocationBytes)) + " (maxMemoryAllocationSize); " +
                                       expected));
    }
  }
  // A GPU's images share its device-local heap; a CPU device's heap is the machine's RAM (the
  // header says why it is not checked here).
  if (limits.cpuDevice || limits.deviceLocalHeapBytes == 0) return;
  double total = 0;
  const DeviceImage* largest = nullptr;
  std::string terms;
  for (const DeviceImage& image : images) {
    total += double(image.bytes);
    if (!largest || image.bytes > largest->bytes) largest = &image;
    terms += (terms.empty() ? "" : " + ") + image.describe();
  }
  if (largest && total > double(limits.deviceLocalHeapBytes))
    throw InputError(formatError(largest->origin, largest->place,
                                 "the device images need " + formatBytes(total) + " (" + terms + "), above " + device +
                                     "'s device-local heap of " + formatBytes(double(limits.deviceLocalHeapBytes)) +
                                     "; expected a smaller " + (largest->place == "map.size" ? "map.size" : "image")));
}

}  // namespace shadowlab
