#include "job_limits.h"

#include <unistd.h>

#include <cmath>
#include <cstdio>

#include "command.h"
#include "shadowlab/reference/reference.h"
#include "shadowlab/scenes/error.h"

namespace shadowlab::app {

namespace {

constexpr double kGiB = 1024.0 * 1024.0 * 1024.0;

std::string gib(double bytes) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2f GiB", bytes / kGiB);
  return buf;
}

double pixels(const Scene& scene) { return double(scene.camera.width) * double(scene.camera.height); }

// The raster frame's channels (scenes/frame.h): hit, object and primitive ids, 11 per rendered
// light (14 with a filterable map's moment channels), 5 per projector.
double rasterFrameBytes(const Scene& scene, const Method& method) {
  const double light = isMomentFilter(effectiveFilter(method)) ? 14.0 : 11.0;
  return (3.0 + light + 5.0 * double(scene.projectors.size())) * 4.0 * pixels(scene);
}

// The device's images: the camera's visibility buffer (id + depth, 8 bytes a pixel), the
// resolve pass's two RGBA32F targets (32; a third, 16 more, once a filterable map is rendered) and
// the lookup pass's R8 target (1), and the map's layers (depth + id, 8 bytes a texel): one per
// cascade, six for a point light, one otherwise, plus one per projector; a filterable map adds two
// moments images per light layer (2 or 4 floats a texel each).
void addDeviceImages(MemoryEstimate& e, const Scene& scene, const Method& method) {
  e.add((isMomentFilter(effectiveFilter(method)) ? 57.0 : 41.0) * pixels(scene), "camera targets");
  int lightLayers = isCascadedFit(method.fit) ? method.cascadeCount : 1;
  for (const Light& light : scene.lights)
    if (light.type == LightType::Point) lightLayers = std::max(lightLayers, 6);
  const int layers = lightLayers + int(scene.projectors.size());
  e.add(8.0 * double(method.mapSize) * double(method.mapSize) * layers,
        "map " + std::to_string(method.mapSize) + "^2 x " + std::to_string(layers) + " layer(s)");
  if (isMomentFilter(effectiveFilter(method)))
    e.add(2.0 * 4.0 * momentCount(effectiveFilter(method)) * double(method.mapSize) * double(method.mapSize) *
              lightLayers,
          "moments " + std::to_string(method.mapSize) + "^2 x " + std::to_string(lightLayers) + " layer(s) x 2");
}

double physicalMemoryBytes() {
  const long pages = ::sysconf(_SC_PHYS_PAGES), pageSize = ::sysconf(_SC_PAGE_SIZE);
  return pages > 0 && pageSize > 0 ? double(pages) * double(pageSize) : 0.0;
}

}  // namespace

void MemoryEstimate::add(double termBytes, const std::string& what) {
  bytes += termBytes;
  breakdown += (breakdown.empty() ? "" : " + ") + what + " " + gib(termBytes);
}

// The program, its libraries, the scene and its BVH at the bundled scenes' sizes (a 48x32 run's
// peak resident set is about 130 MB).
constexpr double kProgramBytes = 0.15 * kGiB;

MemoryEstimate referenceJobMemory(const Scene& scene, ReferenceChannels channels) {
  MemoryEstimate e;
  e.add(kProgramBytes, "program");
  e.add(2.0 * referenceFrameBytes(scene, channels), "reference frame x 2 (the EXR writer's interleaved copy)");
  e.add(6.0 * pixels(scene), "picture");
  return e;
}

MemoryEstimate rasterJobMemory(const Scene& scene, const Method& method) {
  MemoryEstimate e;
  e.add(kProgramBytes, "program");
  e.add(2.0 * rasterFrameBytes(scene, method), "raster frame x 2 (the EXR writer's interleaved copy)");
  addDeviceImages(e, scene, method);
  return e;
}

MemoryEstimate compareJobMemory(const Scene& scene, const Method& method) {
  MemoryEstimate e;
  e.add(kProgramBytes, "program");
  e.add(referenceFrameBytes(scene), "reference frame");
  e.add(rasterFrameBytes(scene, method), "raster frame");
  addDeviceImages(e, scene, method);
  // classes and reference-lit flags (2 bytes), errors.png (3), the triptych (9), their PNG
  // encoders' rows and the picture the triptych is drawn from (~16)
  e.add(30.0 * pixels(scene), "classes and pictures");
  return e;
}

void addMaxMemoryOption(CLI::App* sub, double* maxMemoryGiB) {
  sub->add_option("--max-memory", *maxMemoryGiB,
                  "Refuse a job whose estimated memory exceeds this many GiB (default: 80% of physical memory)")
      ->check(CLI::NonNegativeNumber);
}

void checkMemory(const std::string& command, const MemoryEstimate& estimate, double maxMemoryGiB) {
  const double physical = physicalMemoryBytes();
  const double limit = maxMemoryGiB > 0 ? maxMemoryGiB * kGiB : 0.8 * physical;
  const std::string limitText =
      maxMemoryGiB > 0 ? gib(limit) + " (--max-memory)"
                       : gib(limit) + " (80% of this machine's " + gib(physical) + "; --max-memory sets another)";
  if (limit > 0 && estimate.bytes > limit)
    throw InputError("shadowlab " + command + ": error: this job needs about " + gib(estimate.bytes) + " (" +
                     estimate.breakdown + "); expected at most " + limitText +
                     ": lower the camera's width and height or map.size");
  if (estimate.bytes >= kGiB || verbose())
    std::fprintf(stderr, "%s: about %s of memory (%s); the limit is %s\n", command.c_str(), gib(estimate.bytes).c_str(),
                 estimate.breakdown.c_str(), limitText.c_str());
}

void checkDeviceMemory(const std::string& command, const Rasterizer& rasterizer, const Scene& scene,
                       const Method& method, const std::string& light) {
  const std::vector<DeviceImage> images = rasterizer.plannedImages(scene, method, light);
  const DeviceMemoryLimits limits = rasterizer.memoryLimits();
  if (verbose()) {
    double total = 0;
    std::string terms;
    for (const DeviceImage& image : images) {
      total += double(image.bytes);
      terms += (terms.empty() ? "" : " + ") + image.describe();
    }
    std::fprintf(stderr, "%s: device images %s (%s); device %s allows %s per image%s\n", command.c_str(),
                 formatBytes(total).c_str(), terms.c_str(), limits.deviceName.c_str(),
                 formatBytes(double(limits.maxAllocationBytes)).c_str(),
                 limits.cpuDevice
                     ? " (a CPU device: its memory is this machine's RAM)"
                     : (", " + formatBytes(double(limits.deviceLocalHeapBytes)) + " device-local").c_str());
  }
  shadowlab::checkDeviceMemory(images, limits);
}

std::function<void(double)> terminalProgress(const std::string& label) {
  if (::isatty(STDERR_FILENO) != 1) return {};
  return [label](double fraction) {
    std::fprintf(stderr, "\r%s %3d%%", label.c_str(), int(std::floor(fraction * 100.0)));
    if (fraction >= 1.0) std::fprintf(stderr, "\r%*s\r", int(label.size()) + 5, "");
    std::fflush(stderr);
  };
}

}  // namespace shadowlab::app
