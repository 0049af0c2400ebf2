#pragma once
// The rasterizer's state: the passes in the frame's order and what they share (rasterizer.cpp
// orders them; rasterizer_checks.cpp checks a request and sizes its images before any GPU work).
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "passes/descriptor_set.h"
#include "passes/evidence_pass.h"
#include "passes/id_draws.h"
#include "passes/lookup_pass.h"
#include "passes/moments_pass.h"
#include "passes/resolve_pass.h"
#include "passes/resolve_pipelines.h"
#include "passes/sdsm_sample_pass.h"
#include "passes/shadow_pass.h"
#include "passes/visibility_pass.h"
#include "scene_gpu.h"
#include "shadowlab/raster/device_memory.h"
#include "shadowlab/raster/raster.h"
#include "shadowlab/raster/resolve_params.h"
#include "vk/buffer.h"
#include "vk/commands.h"
#include "vk/context.h"

namespace shadowlab {

namespace raster {
// Every fit but sphere follows the camera's view frustum (tight's and the cascades' corners from
// its field of view, lispsm's, psm's and tsm's eye point, sdsm's perspective samples): with an
// orthographic camera they are refused (exit 2) rather than fitted to a frustum it does not have.
void checkOrthographicFit(const Scene& scene, const Light* light, const Method& method, const Camera& camera);
}  // namespace raster

struct Rasterizer::Impl {
  // First: destroyed last, after everything made with it.
  std::unique_ptr<vk::Context> context;
  std::unique_ptr<vk::Commands> commands;
  raster::DescriptorSet descriptors;
  vk::Sampler nearestSampler, compareSampler, linearSampler;
  vk::ShaderModule fullscreenVert;
  raster::PassContext pc;  // what every pass records with
  vk::QueryPool queries;   // kTimestamps
  vk::Buffer params;       // resolve_abi.h's Params (ParamsLoops too)
  std::unique_ptr<raster::SceneGpu> scene;

  // The passes, in the frame's order (record()); the id writers and resolve.frag's pipelines are
  // shared by the passes that draw with them.
  raster::IdDraws idDraws;
  raster::SdsmSamplePass sdsmSamples;
  raster::ShadowPass shadow;
  raster::MomentsPass moments;
  raster::VisibilityPass visibility;
  raster::ResolvePipelines resolvePipelines;
  raster::ResolvePass resolve;
  raster::LookupPass lookup;
  raster::EvidencePass evidence;
  std::set<std::string> warmed;
  std::vector<std::vector<float>> spare;  // recycled channel planes (Rasterizer::recycle)

  explicit Impl(const RasterDeviceOptions& options);
  // Work may still be in flight when a render throws (a failed call after a submission): wait for
  // the device before the members release what it reads and writes. Not after a timeout, where
  // the wait could last forever; a lost device answers at once.
  ~Impl() {
    if (context && context->device() && !context->hung()) vkDeviceWaitIdle(context->device());
  }

  // render()'s steps (defined beside render(), in its order).
  struct FramePipelines {
    raster::IdPipelines ids;
    VkPipeline planes = VK_NULL_HANDLE;        // pass 3a: the group's planes and surface (none: both kept)
    VkPipeline resolve = VK_NULL_HANDLE;       // pass 3 (none on demand)
    bool resolveSurface = false;               // pass 3 writes the group's surface too (a light)
    VkPipeline lookup = VK_NULL_HANDLE;        // pass 4; none without a light
    raster::EvidencePass::Pipelines evidence;  // pass 5 (evidence on demand)
    bool firstUse = false;                     // lavapipe compiles at first use: run once untimed (warmupRun)
  };
  struct PassTimes {
    double shadowGpuMs = 0;   // pass 1
    double resolveGpuMs = 0;  // pass 3 (pass 2's time is the visibility pass's gpuMs)
    double lookupGpuMs = 0;   // pass 4
    double momentsGpuMs = 0;  // pass 1b (part of shadowGpuMs)
  };
  const Light* validate(const Scene& scene, const Method& method, const std::string& lightName) const;
  int maxMapSize() const;
  DeviceMemoryLimits memoryLimits() const;
  // The images a frame of this request allocates, with the device's sizes; checkDeviceMemory
  // refuses it before any is allocated.
  std::vector<DeviceImage> plannedImages(const Scene& scene, const Method& method,
                                         const raster::FrameLayers& layers) const;
  mutable std::string plannedKey;  // plannedImages' last request and answer
  mutable std::vector<DeviceImage> planned;
  void upload(const Scene& scene);
  void prepareTargets(const Scene& scene, const Method& method, const raster::FrameLayers& layers, bool stencilIds);
  std::vector<raster::ProjectorTexels> projectorTexels() const;
  FramePipelines pipelinesFor(const raster::FrameLayers& layers, const raster::ResolveSpecialization& spec,
                              bool partial, bool planes);
  const std::vector<glm::vec3>& visiblePoints(const Scene& scene, const Light* light, const Method& method,
                                              const Camera& fitCamera, bool stencilIds);
  struct Drawn {
    bool visibility = false, shadow = false;
  };
  Drawn submit(const Scene& scene, const Method& method, const raster::FrameLayers& layers,
               const FramePipelines& pipes);  // what it drew (the rest was kept)
  PassTimes readTimestamps(Drawn drawn);

  void writeDescriptors();
  void record(VkCommandBuffer cmd, const std::vector<raster::LayerDraw>& layerDraws, int lightLayers,
              const FramePipelines& frame, const Method& method, const glm::mat4& cameraClip, int width, int height,
              bool drawVisibility, bool drawShadow);

  bool keepShadowMaps = true;  // RasterDeviceOptions::keepShadowMaps
  // The untimed first run of a pipeline combination (lavapipe compiles its shaders at the first
  // draw): every pass scissored to one pixel, then the timed run draws the frame.
  bool warmupRun = false;
  // retimeMethod's runs: pass 1 (every layer), 1b and 4 only; the visibility buffer, the planes and
  // the resolve are skipped (their outputs stay as the last frame left them).
  bool methodOnly = false;
  // What the last submit recorded, for retimeMethod.
  struct LastSubmit {
    bool valid = false;
    std::vector<raster::LayerDraw> layerDraws;
    int lightLayers = 0;
    std::vector<glm::mat4> lightClipFromWorld;  // the light's layers, Vulkan clip space (lastLightClipFromWorld)
    FramePipelines pipes;
    Method method;
    glm::mat4 cameraClip{1.0f};
    int width = 0, height = 0;
    bool light = false;
    double sdsmGpuMs = 0;  // fit=sdsm: the kept samples' pass (part of the method's time)
  } last;
};

}  // namespace shadowlab
