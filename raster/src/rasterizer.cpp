// The rasterizer orders the passes of a frame and shares what they share: the Vulkan context, the
// scene on the GPU, the descriptor set (resolve_abi.h's bindings, each pass saying what its own
// hold), the frame's targets and the timestamp queries. Each pass owns its pipelines, images and
// recording, one file each (raster/src/passes/):
//   Pass 1  (shadow_pass):      depth + ids from the light, one layer per map and projector.
//   Pass 1b (moments_pass):     filterable maps' moments, blurred along rows, then columns.
//   Pass 2  (visibility_pass):  the camera's visibility buffer, kept while scene and camera stay.
//   Pass 3a (resolve_pass):     a group's planes and surface, where evidence on demand has none.
//   Pass 3  (resolve_pass):     the full resolve: every pixel's evidence channels.
//   Pass 4  (lookup_pass):      the method's visibility alone, 1 byte per pixel, timed on its own.
//   Pass 5  (evidence_pass):    evidence on demand: the resolve of the listed pixels only, after
//                               the readback of pass 4 (its own submit).
// fit=sdsm samples the camera's visible points before pass 1 (sdsm_sample_pass, its own submit).
// resolve.frag's pipelines (passes 3a, 3, 4, 5) come from one cache (resolve_pipelines), the id
// writers (passes 1 and 2) from another (id_draws).
// A new pass is a new file and a line in record()'s order (and its bind() in writeDescriptors).
#include "rasterizer_impl.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdlib>
#include <string>

#include "light_space.h"
#include "shadowlab/raster/resolve_abi.h"
#include "shadowlab/raster/sdsm.h"
#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/io.h"
#include "shadowlab/scenes/technique.h"
#include "technique_compiler.h"
#include "vk/check.h"
#include "vk/image.h"
#include "vk/pipeline.h"

#include "fullscreen_vert.h"

namespace shadowlab {

namespace {

namespace abi = raster::abi;
using raster::barrierToHost;
using raster::LayerDraw;
using raster::resolveAttachments;
using raster::vkDepthFormat;
using raster::vkDepthStencilFormat;

// GPU timestamps per frame: 0 start, 5 after the map layers (before the moments pass), 1 after
// the shadow pass (moments included), 3 after the visibility buffer, 4 after the resolve, 2 after
// the lookup (the end).
constexpr uint32_t kTimestamps = 6;

double msSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

std::unique_ptr<vk::Context> makeContext(const RasterDeviceOptions& options) {
  vk::ContextOptions co;
  co.device = options.device;
  co.validation = options.validation;
  return std::make_unique<vk::Context>(co);
}

}  // namespace

Rasterizer::Impl::Impl(const RasterDeviceOptions& options)
    : context(makeContext(options)),
      descriptors(*context),
      idDraws(*context),
      shadow(idDraws),
      moments(*context),
      visibility(idDraws),
      resolvePipelines(*context),
      evidence(*context) {
  keepShadowMaps = options.keepShadowMaps;
  double timeoutS = options.gpuTimeoutS;
  if (!(timeoutS > 0)) {
    timeoutS = 120;
    if (const char* env = std::getenv("SHADOWLAB_GPU_TIMEOUT_S"); env && *env) {
      char* end = nullptr;
      timeoutS = std::strtod(env, &end);
      if (*end || !(timeoutS > 0 && timeoutS <= 1e6))
        throw InputError(std::string("SHADOWLAB_GPU_TIMEOUT_S: error: got \"") + env +
                         "\"; expected seconds, a number > 0 and <= 1e6");
    }
  }
  commands = std::make_unique<vk::Commands>(*context, uint64_t(timeoutS * 1e9));
  fullscreenVert = vk::createShaderModule(*context, kSpv_fullscreen_vert, sizeof(kSpv_fullscreen_vert));

  VkDevice device = context->device();
  auto makeSampler = [&](bool compare, bool linear) {
    VkSamplerCreateInfo s{VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO};
    // Depths are point-sampled; the comparison sampler filters its 0/1 results, the moments
    // sampler the moments.
    s.magFilter = s.minFilter = linear ? VK_FILTER_LINEAR : VK_FILTER_NEAREST;
    s.mipmapMode = VK_SAMPLER_MIPMAP_MODE_NEAREST;
    s.addressModeU = s.addressModeV = s.addressModeW = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE;
    s.compareEnable = compare;
    s.compareOp = VK_COMPARE_OP_LESS_OR_EQUAL;  // lit when reference <= stored depth
    s.maxLod = 0.0f;
    VkSampler sampler;
    VK_CHECK(vkCreateSampler(device, &s, nullptr, &sampler));
    return vk::Sampler(device, sampler);
  };
  nearestSampler = makeSampler(false, false);
  compareSampler = makeSampler(true, true);
  linearSampler = makeSampler(false, true);
  pc = {context.get(),        descriptors.pipelineLayout(), fullscreenVert.get(),
        nearestSampler.get(), compareSampler.get(),         linearSampler.get()};

  VkQueryPoolCreateInfo q{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
  q.queryType = VK_QUERY_TYPE_TIMESTAMP;
  q.queryCount = kTimestamps;
  VkQueryPool pool;
  VK_CHECK(vkCreateQueryPool(device, &q, nullptr, &pool));
  queries = vk::QueryPool(device, pool);
  params = vk::Buffer(*context, sizeof(abi::Params),
                      VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT | VK_BUFFER_USAGE_STORAGE_BUFFER_BIT);  // ParamsLoops too
}

// The descriptor set: the scene's tables and Params here, each pass's images and buffers from it.
void Rasterizer::Impl::writeDescriptors() {
  const raster::SceneGpu& s = *scene;
  raster::BindingResources r{};
  r[abi::kBindingTriangleMaterials].buffer = &s.triangleMaterials;
  r[abi::kBindingMaterials].buffer = &s.materials;
  r[abi::kBindingAlphaTexels].buffer = &s.alphaTexels;
  r[abi::kBindingParams].buffer = &params;
  r[abi::kBindingParamsLoops].buffer = &params;
  r[abi::kBindingTrianglePlanes].texelView = s.trianglePlanesView.get();
  r[abi::kBindingProjectorTexels].buffer = &s.projectorTexels;
  shadow.bind(pc, r);
  moments.bind(pc, r);
  visibility.bind(pc, r);
  resolve.bind(pc, r);
  evidence.bind(r);
  descriptors.write(r);
}

// The frame's order. The timestamps between the passes are the frame's (kTimestamps).
void Rasterizer::Impl::record(VkCommandBuffer cmd, const std::vector<LayerDraw>& layerDraws, int lightLayers,
                              const FramePipelines& frame, const Method& method, const glm::mat4& cameraClip, int width,
                              int height, bool drawVisibility, bool drawShadow) {
  const raster::SceneGpu& s = *scene;
  VkQueryPool pool = queries.get();
  vkCmdResetQueryPool(cmd, pool, 0, kTimestamps);
  vkCmdWriteTimestamp2(cmd, VK_PIPELINE_STAGE_2_TOP_OF_PIPE_BIT, pool, 0);
  VkDescriptorSet set = descriptors.get();
  vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pc.layout, 0, 1, &set, 0, nullptr);
  VkBuffer vb = s.vertices.get();
  VkDeviceSize zero = 0;
  vkCmdBindVertexBuffers(cmd, 0, 1, &vb, &zero);
  vkCmdBindIndexBuffer(cmd, s.indices.get(), 0, VK_INDEX_TYPE_UINT32);

  // Pass 1, skipped while the maps of the last frame still hold (left in their read layout).
  if (drawShadow) shadow.record(cmd, pc, s, layerDraws, frame.ids, method, warmupRun);
  vkCmdWriteTimestamp2(cmd, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, pool, 5);
  moments.record(cmd, pc, method, lightLayers, warmupRun);  // pass 1b
  // After the barriers: a CPU driver may still be rasterizing the maps until they are flushed.
  vkCmdWriteTimestamp2(cmd, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, pool, 1);
  visibility.record(cmd, pc, s, frame.ids, cameraClip, width, height, drawVisibility, warmupRun);  // pass 2
  vkCmdWriteTimestamp2(cmd, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, pool, 3);
  if (!methodOnly) {
    resolve.recordPlanes(cmd, frame.planes, width, height, warmupRun);  // pass 3a
    // Pass 3 (evidence on demand: none; pass 5 resolves the listed pixels after the readback).
    if (frame.resolve != VK_NULL_HANDLE)
      resolve.record(cmd, frame.resolve, resolveAttachments(method.filter), frame.resolveSurface, width, height,
                     warmupRun);
  }
  barrierToHost(cmd, VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT | VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
                VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT | VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
  vkCmdWriteTimestamp2(cmd, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, pool, 4);
  if (frame.lookup != VK_NULL_HANDLE) lookup.record(cmd, frame.lookup, width, height, warmupRun);  // pass 4
  vkCmdWriteTimestamp2(cmd, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, pool, 2);
}

namespace {
// The method as the passes read it: a technique file's moments line (technique.h) makes its
// filterable map the filter whose moments pass, attachments and evidence channels the frame gets
// (the technique's shadowVisibility still gives vis: resolve.frag's kTechnique).
Method withEffectiveFilter(const Method& requested) {
  Method m = requested;
  m.filter = effectiveFilter(requested);
  return m;
}
}  // namespace

Rasterizer::Rasterizer(const RasterDeviceOptions& options) : impl_(std::make_unique<Impl>(options)) {}
Rasterizer::~Rasterizer() {
  // A device that stopped answering is still running what it was given: destroying what it reads
  // could crash it, waiting for it would never end. Left as it is; the process ends with _exit.
  if (impl_ && impl_->context && impl_->context->hung()) (void)impl_.release();
}

namespace {
std::atomic<bool> gDeviceHung{false};
}  // namespace
bool rasterDeviceHung() { return gDeviceHung.load(); }

void checkGpuTimeout(double seconds, const std::string& origin, const std::string& pointer) {
  if (seconds >= 0 && seconds <= 1e6) return;
  char got[32];
  std::snprintf(got, sizeof got, "%g", seconds);
  throw InputError(formatError(
      origin, pointer,
      std::string("got ") + got + "; expected seconds, a number 0..1e6 (0: $SHADOWLAB_GPU_TIMEOUT_S, else 120)"));
}
void markRasterDeviceHung() { gDeviceHung = true; }

void precompileTechnique(const Method& method) {
  if (!method.technique.empty()) raster::compileTechnique(loadTechniqueFile(method.technique));
}
Rasterizer::Rasterizer(Rasterizer&&) noexcept = default;
Rasterizer& Rasterizer::operator=(Rasterizer&&) noexcept = default;

std::string Rasterizer::deviceName() const { return impl_->context->deviceName(); }

int Rasterizer::maxMapSize() const { return impl_->maxMapSize(); }

DeviceMemoryLimits Rasterizer::memoryLimits() const { return impl_->memoryLimits(); }

std::vector<DeviceImage> Rasterizer::plannedImages(const Scene& scene, const Method& requested,
                                                   const std::string& light) const {
  const Method method = withEffectiveFilter(requested);
  const Light* l = impl_->validate(scene, method, light);
  return impl_->plannedImages(scene, method, raster::fitFrameLayers(scene, l, method, scene.camera));
}

void Rasterizer::check(const Scene& scene, const Method& method, const std::string& light) const {
  checkDeviceMemory(plannedImages(scene, method, light), memoryLimits());
}

int Rasterizer::validationMessages() const { return impl_->context->validationMessages(); }

std::vector<glm::mat4> Rasterizer::lastLightClipFromWorld() const {
  return impl_->last.valid ? impl_->last.lightClipFromWorld : std::vector<glm::mat4>{};
}

std::vector<uint8_t> Rasterizer::lookupVisibility() const { return impl_->lookup.copy(*impl_->context); }

std::vector<Rasterizer::MethodTiming> Rasterizer::retimeMethod(int repeats) {
  Impl& im = *impl_;
  std::vector<MethodTiming> out;
  if (!im.last.valid) return out;
  const Impl::LastSubmit& l = im.last;
  for (int k = 0; k < repeats; ++k) {
    VkCommandBuffer cmd = im.commands->begin();
    im.methodOnly = true;
    try {
      im.record(cmd, l.layerDraws, l.lightLayers, l.pipes, l.method, l.cameraClip, l.width, l.height,
                /*drawVisibility=*/false, /*drawShadow=*/true);
    } catch (...) {
      im.methodOnly = false;
      throw;
    }
    im.methodOnly = false;
    im.commands->submitAndWait();
    // Drawn: the shadow layers (their time also becomes the one a next frame with kept maps reports).
    const Impl::PassTimes p = im.readTimestamps({false, true});
    MethodTiming m;
    m.shadowGpuMs = p.shadowGpuMs;
    m.lookupGpuMs = l.light ? p.lookupGpuMs : 0.0;
    m.momentsGpuMs = isMomentFilter(l.method.filter) ? p.momentsGpuMs : 0.0;
    m.sdsmGpuMs = l.sdsmGpuMs;  // the samples are kept: their pass's time when taken
    out.push_back(m);
  }
  return out;
}

void Rasterizer::recycle(Frame&& frame) { impl_->evidence.recycle(std::move(frame), impl_->spare); }

// ---- render()'s steps, in the order it calls them (validation and the planned images:
// rasterizer_checks.cpp) ----

// Upload: the scene's geometry, materials and projector images (cached by content hash).
void Rasterizer::Impl::upload(const Scene& sc) {
  std::string key = raster::sceneKey(sc);
  if (scene && scene->hash == key) return;
  scene.reset();
  visibility.keptKey.clear();
  shadow.keptKey.clear();
  scene = std::make_unique<raster::SceneGpu>(raster::uploadScene(*context, sc, key));
}

// Targets: the map layers, the camera's images, the projector planes, the descriptor set.
// stencilIds: the map in its depth+stencil format (ShadowPass::stencilIdsApply), for the stencil ids.
void Rasterizer::Impl::prepareTargets(const Scene& sc, const Method& method, const raster::FrameLayers& layers,
                                      bool stencilIds) {
  const Camera& camera = sc.camera;
  shadow.ensureImages(*context, method.mapSize,
                      stencilIds ? vkDepthStencilFormat(method.mapFormat) : vkDepthFormat(method.mapFormat),
                      std::max(1, int(layers.layers.size())));
  visibility.ensureImages(*context, camera.width, camera.height);
  const size_t channelCount = size_t(abi::kProjectorChannels) * sc.projectors.size();
  size_t outputBytes = std::max<size_t>(1, channelCount * size_t(camera.width) * size_t(camera.height)) * sizeof(float);
  resolve.ensureImages(*context, camera.width, camera.height, isMomentFilter(method.filter), outputBytes);
  lookup.ensureImages(*context, camera.width, camera.height);
  moments.ensureImages(*context, method.filter, method.mapSize, layers.lightLayers);
  raster::updatePlanes(*scene, raster::cameraRaysOrigin(camera));
  writeDescriptors();
}

// Where each uploaded projector image lies in the projector texel table.
std::vector<raster::ProjectorTexels> Rasterizer::Impl::projectorTexels() const {
  std::vector<raster::ProjectorTexels> out;
  for (const raster::ProjectorImage& pi : scene->projectors) out.push_back({pi.firstTexel, pi.width, pi.height});
  return out;
}

// Pipelines: the id writers for the map's format (the one prepareTargets chose) and clamp, the
// resolve for its specialization.
Rasterizer::Impl::FramePipelines Rasterizer::Impl::pipelinesFor(const raster::FrameLayers& layers,
                                                                const raster::ResolveSpecialization& spec, bool partial,
                                                                bool planes) {
  const VkFormat mapFormat = shadow.mapDepth().format();
  const bool depthClamp = layers.depthClamp;
  FramePipelines p;
  shadow.pipelines(pc, depthClamp, layers.layers, p.ids);
  visibility.pipelines(pc, p.ids);
  // The lookup: the same specialization, the evidence and the projectors compiled out, the
  // visible point from the group's surface where the method needs no normal.
  raster::ResolveSpecialization lookupSpec = spec;
  lookupSpec[abi::kSpecLookupOnly] = 1u;
  lookupSpec[abi::kSpecProjectorCount] = 0u;
  lookupSpec[abi::kSpecSurface] = raster::lookupReadsSurface(spec) ? 1u : 0u;
  const bool light = spec[abi::kSpecLightType] != uint32_t(abi::kLightNone);
  if (partial) {
    p.evidence = evidence.pipelines(pc, resolvePipelines, spec, lookupSpec, light);
  } else {
    p.resolve = resolvePipelines.pipeline(pc, spec);
    p.resolveSurface = raster::resolveWritesSurface(spec);
  }
  if (planes) {
    // A group's first frame: pass 3a draws its planes (m, cascade; kept on demand) and its surface
    // (the lookup's). They depend on no bias or filter (footprintKey), so every filter's group
    // shares one pipeline.
    raster::ResolveSpecialization planesSpec = spec;
    planesSpec[abi::kSpecPlanesOnly] = 1u;
    planesSpec[abi::kSpecProjectorCount] = 0u;
    for (int k : {abi::kSpecFilter, abi::kSpecPcfSize, abi::kSpecAdaptive, abi::kSpecReceiverPlane,
                  abi::kSpecNormalOffset, abi::kSpecTechniqueNormal})
      planesSpec[size_t(k)] = 0u;
    static_assert(int(Filter::None) == 0, "kSpecFilter 0 is filter none");
    p.planes = resolvePipelines.pipeline(pc, planesSpec);
  }
  if (light) p.lookup = resolvePipelines.pipeline(pc, lookupSpec);
  // lavapipe compiles shaders at first use: the first frame of a combination runs twice.
  std::string warmKey = std::to_string(int(mapFormat)) + "/" + std::to_string(depthClamp) + "/" +
                        std::to_string(partial) + "/" + std::to_string(planes);
  for (uint32_t k : spec) warmKey += "/" + std::to_string(k);
  warmKey += "/" + resolvePipelines.techniqueKey();
  p.firstUse = warmed.insert(warmKey).second;
  return p;
}

// Submit: records and runs the frame (twice at a pipeline's first use, the second one timed).
// Draws the visibility buffer unless the one of the same scene and camera is still there.
Rasterizer::Impl::Drawn Rasterizer::Impl::submit(const Scene& sc, const Method& method,
                                                 const raster::FrameLayers& layers, const FramePipelines& pipes) {
  const Camera& camera = sc.camera;
  std::vector<LayerDraw> layerDraws;
  for (const raster::MapLayer& l : layers.layers)
    layerDraws.push_back({raster::clipFromTex() * l.texFromWorld, l.lightDepth, l.depthFromWorld});
  glm::mat4 cameraClip = camera.clipFromView() * camera.viewFromWorld();
  const std::string key = raster::VisibilityPass::cameraKey(*scene, camera);
  const bool drawVisibility = visibility.keptKey != key;
  visibility.keptKey.clear();  // until this frame is through
  // At a pipeline's first use both runs draw the maps: the timed one must not inherit the first's.
  const std::string mapKey = shadow.key(*scene, layerDraws, pipes.ids, method);
  const bool drawShadow = !keepShadowMaps || shadow.keptKey != mapKey || pipes.firstUse;
  shadow.keptKey.clear();
  for (int run = 0; run < (pipes.firstUse ? 2 : 1); ++run) {
    VkCommandBuffer cmd = commands->begin();
    warmupRun = pipes.firstUse && run == 0;  // one pixel per pass: compiles, draws next to nothing
    try {
      record(cmd, layerDraws, layers.lightLayers, pipes, method, cameraClip, camera.width, camera.height,
             drawVisibility, drawShadow);
    } catch (...) {
      warmupRun = false;
      throw;
    }
    warmupRun = false;
    commands->submitAndWait();
  }
  visibility.keptKey = key;
  shadow.keptKey = mapKey;
  last.valid = true;
  last.layerDraws = layerDraws;
  last.lightLayers = layers.lightLayers;
  last.lightClipFromWorld.clear();
  for (int i = 0; i < layers.lightLayers; ++i)
    last.lightClipFromWorld.push_back(raster::clipFromTex() * layers.layers[size_t(i)].texFromWorld);
  last.pipes = pipes;
  last.method = method;
  last.cameraClip = cameraClip;
  last.width = camera.width;
  last.height = camera.height;
  last.light = pipes.lookup != VK_NULL_HANDLE;
  return {drawVisibility, drawShadow};
}

// Timestamps: the passes' GPU times of the last submit (kTimestamps says which stamp is where).
Rasterizer::Impl::PassTimes Rasterizer::Impl::readTimestamps(Drawn drawn) {
  uint64_t stamps[kTimestamps] = {};
  VK_CHECK(vkGetQueryPoolResults(context->device(), queries.get(), 0, kTimestamps, sizeof(stamps), stamps,
                                 sizeof(uint64_t), VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT));
  const double msPerTick = context->properties().limits.timestampPeriod * 1e-6;
  if (drawn.visibility) visibility.gpuMs = double(stamps[3] - stamps[1]) * msPerTick;
  if (drawn.shadow) shadow.layersGpuMs = double(stamps[5] - stamps[0]) * msPerTick;
  PassTimes t;
  // Kept maps: the layers' time when they were drawn, and this frame's moments pass.
  t.shadowGpuMs = shadow.layersGpuMs + double(stamps[1] - stamps[5]) * msPerTick;
  t.resolveGpuMs = double(stamps[4] - stamps[3]) * msPerTick;
  t.lookupGpuMs = double(stamps[2] - stamps[4]) * msPerTick;
  t.momentsGpuMs = double(stamps[1] - stamps[5]) * msPerTick;
  return t;
}

// fit=sdsm's samples (sdsm_sample_pass.h), with the camera's images and the descriptor set as the
// frame will have them (the layer count is the same with or without the samples).
const std::vector<glm::vec3>& Rasterizer::Impl::visiblePoints(const Scene& sc, const Light* light, const Method& method,
                                                              const Camera& fitCamera, bool stencilIds) {
  const std::string key = raster::VisibilityPass::cameraKey(*scene, fitCamera);
  if (const std::vector<glm::vec3>* kept = sdsmSamples.kept(key)) return *kept;
  raster::SdsmSamplePass::checkCamera(fitCamera, sc.camera);
  prepareTargets(sc, method, raster::fitFrameLayers(sc, light, method, fitCamera), stencilIds);
  raster::IdPipelines pipes;
  visibility.pipelines(pc, pipes);
  // lavapipe compiles the id pipelines at first use: then once untimed, as a frame's first run.
  for (int run = warmed.insert("sdsm-samples").second ? 0 : 1; run < 2; ++run) {
    VkCommandBuffer cmd = commands->begin();
    sdsmSamples.record(cmd, pc, descriptors.get(), *scene, visibility, pipes, fitCamera, run == 0);
    commands->submitAndWait();
  }
  visibility.keptKey.clear();  // the camera ids hold the fit camera's ids now
  return sdsmSamples.reduce(*context, *scene, visibility, fitCamera, key);
}

namespace {

// Metadata: what the frame is of, for its EXR header and raster.json.
nlohmann::json frameMeta(const Scene& scene, const Light* light, const Camera& fit, const Method& method,
                         const std::string& device) {
  nlohmann::json lights = nlohmann::json::array(), projectors = nlohmann::json::array();
  for (auto& l : scene.lights) lights.push_back(l.name);
  for (auto& p : scene.projectors) projectors.push_back(p.name);
  return {{"kind", "raster"},
          {"scene", scene.name},
          {"scene_hash", scene.hash},
          {"camera_hash", scene.camera.hash()},
          {"fit_camera_hash", fit.hash()},
          {"width", scene.camera.width},
          {"height", scene.camera.height},
          {"light", light ? light->name : ""},
          {"lights", lights},
          {"projectors", projectors},
          {"method", methodToJson(method)},
          {"device", device}};
}

}  // namespace

Frame Rasterizer::render(const Scene& scene, const Method& requested, const std::string& lightName,
                         RasterTimings* timings, const Camera* fitCamera, const EvidenceSelector* select) {
  auto t0 = std::chrono::steady_clock::now();
  const Method method = withEffectiveFilter(requested);
  Impl& im = *impl_;
  // Planes lent to a frame not handed back before this render stay with it (its group's next
  // frame is a full one): recycle() only takes back what the last render lent.
  im.evidence.forgetLent();
  const Light* light = im.validate(scene, method, lightName);
  const Camera& fit = fitCamera ? *fitCamera : scene.camera;  // what the light frustum follows
  raster::checkOrthographicFit(scene, light, method, fit);
  im.upload(scene);
  // Evidence on demand: with a selector, a light, no projectors (their planes are every pixel's)
  // and the group's planes kept from an earlier frame.
  const bool onDemand = select && *select && light && scene.projectors.empty();
  const bool stencilIds = onDemand && im.shadow.stencilIdsApply(*im.context, *im.scene, method);
  im.resolve.ensureBound(*im.context);  // fit=sdsm's sample pass writes the descriptors
  const std::vector<glm::vec3>* visible =
      raster::fitReadsVisiblePoints(light, method) ? &im.visiblePoints(scene, light, method, fit, stencilIds) : nullptr;
  const raster::FrameLayers layers = raster::fitFrameLayers(scene, light, method, fit, visible);
  checkDeviceMemory(im.plannedImages(scene, method, layers), im.memoryLimits());
  const abi::Params params = raster::packResolveParams(scene, light, method, fit, layers, im.projectorTexels());
  im.params.upload(&params, sizeof(params));
  const raster::ResolveSpecialization spec = raster::resolveSpecialization(scene, light, method, layers);
  const std::string group =
      light ? raster::footprintKey(raster::VisibilityPass::cameraKey(*im.scene, scene.camera), params, spec)
            : std::string();
  const std::string camera = onDemand ? raster::VisibilityPass::cameraKey(*im.scene, scene.camera) : std::string();
  raster::EvidencePass::Footprint* footprint = onDemand ? im.evidence.kept(camera, group) : nullptr;
  // On demand, a group's first frame draws its planes (m, cascade) and its surface in pass 3a and
  // keeps them, then goes on like the group's next ones (the surface drawn again where it was not
  // kept); a full frame's resolve writes the surface beside its channels. Every frame on demand
  // reads the occluder's object from the map's stencil (no id attachment).
  const bool groupStart = onDemand && !footprint;
  const bool lookupSurface = light && raster::lookupReadsSurface(spec);
  const bool resolveSurface = light && !onDemand;  // a full frame's resolve writes the group's surface
  bool surfaceKept = false;
  raster::ResolvePass::SurfaceImage* surface =
      groupStart || lookupSurface || resolveSurface
          ? &im.resolve.surfaceFor(*im.context, group, scene.camera.width, scene.camera.height, surfaceKept)
          : nullptr;
  const bool drawPlanes = groupStart || (onDemand && lookupSurface && !surfaceKept);
  const bool drawsSurface = drawPlanes || resolveSurface;
  if (drawsSurface) surface->key.clear();  // until drawn
  im.resolve.bindSurface(surface);
  im.prepareTargets(scene, method, layers, stencilIds);
  im.resolvePipelines.useTechnique(*im.context, method);
  const Impl::FramePipelines pipes = im.pipelinesFor(layers, spec, onDemand, drawPlanes);
  const Impl::Drawn drawn = im.submit(scene, method, layers, pipes);
  if (drawsSurface) surface->key = group;
  const Impl::PassTimes passes = im.readTimestamps(drawn);

  RasterTimings local;
  RasterTimings& t = timings ? *timings : local;
  t = RasterTimings();
  Frame frame;
  if (onDemand) {
    auto tRead = std::chrono::steady_clock::now();
    if (groupStart)
      footprint = &im.evidence.keepPlanes(*im.context, *im.scene, im.visibility, im.resolve.planes(), group, camera,
                                          scene.camera.width, scene.camera.height);
    const double planesMs = msSince(tRead);
    const raster::EvidencePass::FrameInputs in{
        &im.pc,         im.commands.get(), im.descriptors.get(),   [&im] { im.writeDescriptors(); },
        im.scene.get(), &im.lookup,        im.shadow.stencilIds(), im.maxMapSize()};
    frame = im.evidence.partialFrame(in, scene, *light, method, *select, *footprint, pipes.evidence, im.spare, t);
    if (drawPlanes) t.evidenceGpuMs += passes.resolveGpuMs;  // the planes pass (3a)
    if (groupStart) t.readbackMs += planesMs;
  } else {
    auto tRead = std::chrono::steady_clock::now();
    frame = im.resolve.readback(*im.context, scene, *im.scene, im.visibility, light, method, scene.camera.width,
                                scene.camera.height, im.spare);
    t.readbackMs = msSince(tRead);
    t.evidenceGpuMs = passes.resolveGpuMs;
    t.evidencePixels = frame.pixelCount();
  }
  frame.meta = frameMeta(scene, light, fit, requested, deviceName());
  if (onDemand) frame.meta["evidence_group"] = group;  // CompareContext (compare.h): same hit, ids, m, cascade
  if (t.partialEvidence) {
    frame.meta["evidence"] = "partial";
    frame.meta["evidence_pixels"] = t.evidencePixels;
    if (stencilIds) frame.meta["occluder_prim"] = "unresolved";  // the stencil ids: objects only
  }
  t.shadowGpuMs = passes.shadowGpuMs;
  t.shadowMapsKept = !drawn.shadow;
  t.visibilityGpuMs = im.visibility.gpuMs;
  t.cameraGpuMs = im.visibility.gpuMs + t.evidenceGpuMs;
  t.lookupGpuMs = light ? passes.lookupGpuMs : 0.0;
  t.momentsGpuMs = isMomentFilter(method.filter) ? passes.momentsGpuMs : 0.0;
  if (visible) {
    t.sdsmSampled = true;
    t.sdsmGpuMs = im.sdsmSamples.gpuMs();
    t.sdsmReduceMs = im.sdsmSamples.reduceMs();
  }
  im.last.sdsmGpuMs = t.sdsmGpuMs;
  t.renderWallMs = msSince(t0);
  return frame;
}

}  // namespace shadowlab
