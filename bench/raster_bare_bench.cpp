// The yardstick, measured here rather than quoted: a bare single-purpose shadow-mapping
// program (depth-only shadow pass with a depth bias; a forward camera pass doing one comparison
// lookup per pixel into an RGBA8 target), on the same device, scene, map and image size as the
// rasterizer, in the same process, one after the other. Each benchmark reports both programs'
// shadow and camera pass times (GPU timestamps, after warm-up) and their ratios: the speed goal
// is shadowlab within 1.3x of the bare program for the filters none and hw2x2.
//
// The bare program draws the whole scene with one indexed draw from a position-only vertex buffer
// and no per-pixel evidence: it is what the rasterizer's numbers are compared with, not a mode of it.
//
// versusBare also times bare shadow passes that write the object of each draw into a D24S8 or
// D32FS8 map's stencil (bare_stencil_shadow_gpu_ms, bare_stencil32_shadow_gpu_ms, beside depth-only
// passes timed in between): what shadowlab's stencil ids cost on evidence-on-demand frames.
//
// harnessVsBare: the whole per-configuration yardstick, the bare harness (that shadow pass,
// that camera pass writing 1 byte (R8) of visibility per pixel, a 1-byte-per-pixel readback, a CPU
// count of the pixels that disagree with the reference) against shadowlab's configuration as a sweep
// runs it: with evidence on demand (the default captures) the shadow pass, the lookup pass, the
// evidence pass over the pixels that disagree with the reference (disagreementSelector), the
// readback into the Frame (bytes, the selection, the kept planes) and compareFrames; the camera's
// visibility buffer is kept from the first frame, as in a sweep (total_with_visibility_ms adds its
// time all the same). The *_full captures: the full frame (shadow + camera passes, the readback
// of every channel, compareFrames), as before evidence on demand. The reference is traced once per
// scene before timing (a sweep reads it from its cache).
// The on-demand captures also time compareFrames through a CompareContext made before the loop
// from a frame of the configuration's group, as the sweep keeps one per group (compare.h):
// compare_context_ms, total_context_ms, ratio_context (the iteration time stays the full
// compareFrames'); each iteration checks both give the same metrics JSON.
#include <benchmark/benchmark.h>

#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <vector>

#include "bare_camera_frag.h"
#include "bare_camera_vert.h"
#include "bare_shadow_frag.h"
#include "bare_shadow_ids_frag.h"
#include "bare_shadow_vert.h"
#include "bench_scene.h"
#include "shadowlab/compare/compare.h"
#include "shadowlab/compare/run_pipeline.h"
#include "shadowlab/raster/raster.h"
#include "shadowlab/reference/reference.h"
#include "vk/buffer.h"
#include "vk/check.h"
#include "vk/commands.h"
#include "vk/context.h"
#include "vk/image.h"
#include "vk/pipeline.h"

using namespace shadowlab;

namespace {

constexpr int kMapSize = 2048;

struct Push {
  glm::mat4 clip;      // shadow pass: the light's clip; camera pass: the camera's
  glm::mat4 lightTex;  // camera pass: world -> (u w, v w, depth w, w) of the map
};

struct BareTimes {
  double shadowGpuMs = 0, cameraGpuMs = 0;
};

// The camera pass's clear value: pixels no triangle covers keep it (coverage() tells them apart).
constexpr float kClearVis = 0.2f;
constexpr uint8_t kClearByte = 51;  // round(0.2 * 255)

double msSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

class BareProgram {
 public:
  explicit BareProgram(const vk::Context& c) : c_(c), commands_(c) {
    VkDevice d = c.device();
    VkDescriptorSetLayoutBinding b{0, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1, VK_SHADER_STAGE_FRAGMENT_BIT,
                                   nullptr};
    VkDescriptorSetLayoutCreateInfo sl{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
    sl.bindingCount = 1;
    sl.pBindings = &b;
    VkDescriptorSetLayout setLayout;
    VK_CHECK(vkCreateDescriptorSetLayout(d, &sl, nullptr, &setLayout));
    setLayout_ = vk::DescriptorSetLayout(d, setLayout);
    VkPushConstantRange push{VK_SHADER_STAGE_VERTEX_BIT, 0, sizeof(Push)};
    VkPipelineLayoutCreateInfo pl{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
    pl.setLayoutCount = 1;
    pl.pSetLayouts = &setLayout;
    pl.pushConstantRangeCount = 1;
    pl.pPushConstantRanges = &push;
    VkPipelineLayout layout;
    VK_CHECK(vkCreatePipelineLayout(d, &pl, nullptr, &layout));
    layout_ = vk::PipelineLayout(d, layout);
    VkDescriptorPoolSize size{VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1};
    VkDescriptorPoolCreateInfo dp{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
    dp.maxSets = 1;
    dp.poolSizeCount = 1;
    dp.pPoolSizes = &size;
    VkDescriptorPool pool;
    VK_CHECK(vkCreateDescriptorPool(d, &dp, nullptr, &pool));
    pool_ = vk::DescriptorPool(d, pool);
    VkDescriptorSetAllocateInfo alloc{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
    alloc.descriptorPool = pool;
    alloc.descriptorSetCount = 1;
    alloc.pSetLayouts = &setLayout;
    VK_CHECK(vkAllocateDescriptorSets(d, &alloc, &set_));

    shadowVert_ = vk::createShaderModule(c, kSpv_bare_shadow_vert, sizeof(kSpv_bare_shadow_vert));
    shadowFrag_ = vk::createShaderModule(c, kSpv_bare_shadow_frag, sizeof(kSpv_bare_shadow_frag));
    shadowIdsFrag_ = vk::createShaderModule(c, kSpv_bare_shadow_ids_frag, sizeof(kSpv_bare_shadow_ids_frag));
    cameraVert_ = vk::createShaderModule(c, kSpv_bare_camera_vert, sizeof(kSpv_bare_camera_vert));
    cameraFrag_ = vk::createShaderModule(c, kSpv_bare_camera_frag, sizeof(kSpv_bare_camera_frag));
    auto pipeline = [&](VkShaderModule v, VkShaderModule f, std::vector<VkFormat> colors, VkFormat depth, bool bias,
                        bool stencil = false) {
      vk::GraphicsPipelineDesc p;
      p.vertex = v;
      p.fragment = f;
      p.layout = layout;
      p.bindings = {{0, 3 * sizeof(float), VK_VERTEX_INPUT_RATE_VERTEX}};
      p.attributes = {{0, 0, VK_FORMAT_R32G32B32_SFLOAT, 0}};
      p.colorFormats = std::move(colors);
      p.depthFormat = depth;
      p.stencilFormat = stencil ? depth : VK_FORMAT_UNDEFINED;  // writes the draw's stencil reference
      p.depthBias = bias;
      return vk::createGraphicsPipeline(c, p);
    };
    shadowPipe_ = pipeline(shadowVert_.get(), shadowFrag_.get(), {}, VK_FORMAT_X8_D24_UNORM_PACK32, true);
    shadowIdsPipe_ =
        pipeline(shadowVert_.get(), shadowIdsFrag_.get(), {VK_FORMAT_R32_UINT}, VK_FORMAT_X8_D24_UNORM_PACK32, true);
    cameraPipe_ = pipeline(cameraVert_.get(), cameraFrag_.get(), {VK_FORMAT_R8_UNORM}, VK_FORMAT_D32_SFLOAT, false);
    shadowStencilPipe_ = pipeline(shadowVert_.get(), shadowFrag_.get(), {}, VK_FORMAT_D24_UNORM_S8_UINT, true, true);
    shadowStencil32Pipe_ = pipeline(shadowVert_.get(), shadowFrag_.get(), {}, VK_FORMAT_D32_SFLOAT_S8_UINT, true, true);
    for (int linear = 0; linear < 2; ++linear) {
      VkSamplerCreateInfo s{VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO};
      s.magFilter = s.minFilter = linear ? VK_FILTER_LINEAR : VK_FILTER_NEAREST;
      s.addressModeU = s.addressModeV = s.addressModeW = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_BORDER;
      s.borderColor = VK_BORDER_COLOR_FLOAT_OPAQUE_WHITE;
      s.compareEnable = VK_TRUE;
      s.compareOp = VK_COMPARE_OP_LESS_OR_EQUAL;
      VkSampler sampler;
      VK_CHECK(vkCreateSampler(d, &s, nullptr, &sampler));
      samplers_[linear] = vk::Sampler(d, sampler);
    }
    VkQueryPoolCreateInfo q{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
    q.queryType = VK_QUERY_TYPE_TIMESTAMP;
    q.queryCount = 3;
    VkQueryPool qp;
    VK_CHECK(vkCreateQueryPool(d, &q, nullptr, &qp));
    queries_ = vk::QueryPool(d, qp);
  }

  // The whole scene as one position-only mesh, and the light's and camera's matrices: an
  // orthographic map fit to the scene's bounding sphere along the first light's direction.
  void setScene(const Scene& s) {
    std::vector<float> positions;
    std::vector<uint32_t> indices;
    for (const Object& o : s.objects) {
      uint32_t base = uint32_t(positions.size() / 3);
      for (const glm::vec3& p : o.positions) positions.insert(positions.end(), {p.x, p.y, p.z});
      for (const glm::uvec3& t : o.triangles) indices.insert(indices.end(), {base + t.x, base + t.y, base + t.z});
    }
    vertices_ = vk::Buffer(c_, positions.size() * sizeof(float), VK_BUFFER_USAGE_VERTEX_BUFFER_BIT);
    vertices_.upload(positions.data(), positions.size() * sizeof(float));
    indices_ = vk::Buffer(c_, indices.size() * sizeof(uint32_t), VK_BUFFER_USAGE_INDEX_BUFFER_BIT);
    indices_.upload(indices.data(), indices.size() * sizeof(uint32_t));
    indexCount_ = uint32_t(indices.size());

    glm::vec3 lo = s.boundsMin(), hi = s.boundsMax(), center = 0.5f * (lo + hi);
    float r = 0.5f * glm::length(hi - lo);
    glm::vec3 dir = glm::normalize(s.lights.front().direction);
    glm::vec3 up = std::fabs(dir.y) > 0.99f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0);
    glm::mat4 view = glm::lookAt(center - dir * (2.0f * r), center, up);
    lightClip_ = glm::orthoRH_ZO(-r, r, -r, r, r, 3.0f * r) * view;
    // clip (x, y in [-1, 1], depth in [0, 1]) -> (u, v in [0, 1], depth), v along the viewport's y
    glm::mat4 texFromClip(1.0f);
    texFromClip[0][0] = texFromClip[1][1] = 0.5f;
    texFromClip[3][0] = texFromClip[3][1] = 0.5f;
    lightTex_ = texFromClip * lightClip_;
    cameraClip_ = s.camera.clipFromView() * s.camera.viewFromWorld();
    width_ = s.camera.width;
    height_ = s.camera.height;
    map_ =
        vk::Image(c_, kMapSize, kMapSize, 1, VK_FORMAT_X8_D24_UNORM_PACK32,
                  VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT, VK_IMAGE_ASPECT_DEPTH_BIT);
    mapIds_ = vk::Image(c_, kMapSize, kMapSize, 1, VK_FORMAT_R32_UINT, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT,
                        VK_IMAGE_ASPECT_COLOR_BIT);
    mapStencil_ = vk::Image(c_, kMapSize, kMapSize, 1, VK_FORMAT_D24_UNORM_S8_UINT,
                            VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT,
                            VK_IMAGE_ASPECT_DEPTH_BIT | VK_IMAGE_ASPECT_STENCIL_BIT);
    mapStencil32_ = vk::Image(c_, kMapSize, kMapSize, 1, VK_FORMAT_D32_SFLOAT_S8_UINT,
                              VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT,
                              VK_IMAGE_ASPECT_DEPTH_BIT | VK_IMAGE_ASPECT_STENCIL_BIT);
    // 1 byte of visibility per pixel, host-readable: readback() and coverage() read it in place.
    color_ = vk::Image(c_, width_, height_, 1, VK_FORMAT_R8_UNORM, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT,
                       VK_IMAGE_ASPECT_COLOR_BIT, true);
    depth_ = vk::Image(c_, width_, height_, 1, VK_FORMAT_D32_SFLOAT, VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT,
                       VK_IMAGE_ASPECT_DEPTH_BIT);
  }

  // ids: the shadow pass also writes an R32_UINT id attachment (shadowlab's evidence contract).
  BareTimes frame(bool linear, bool ids = false) {
    VkDescriptorImageInfo image{samplers_[linear ? 1 : 0].get(), map_.arrayView(),
                                VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
    VkWriteDescriptorSet w{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
    w.dstSet = set_;
    w.descriptorCount = 1;
    w.descriptorType = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
    w.pImageInfo = &image;
    vkUpdateDescriptorSets(c_.device(), 1, &w, 0, nullptr);

    VkCommandBuffer cmd = beginFrame();
    VkQueryPool pool = queries_.get();

    vk::transition(cmd, map_, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL,
                   VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, 0, VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT,
                   VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT);
    if (ids)
      vk::transition(cmd, mapIds_, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
                     VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, 0,
                     VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
    begin(cmd, ids ? &mapIds_ : nullptr, map_.layerView(0), kMapSize, kMapSize);
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, (ids ? shadowIdsPipe_ : shadowPipe_).get());
    vkCmdSetCullMode(cmd, VK_CULL_MODE_NONE);
    vkCmdSetDepthBias(cmd, 1.0f, 0.0f, 1.0f);
    Push p{lightClip_, lightTex_};
    vkCmdPushConstants(cmd, layout_.get(), VK_SHADER_STAGE_VERTEX_BIT, 0, sizeof(p), &p);
    vkCmdDrawIndexed(cmd, indexCount_, 1, 0, 0, 0);
    vkCmdEndRendering(cmd);
    vk::transition(cmd, map_, VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
                   VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT, VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT,
                   VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, VK_ACCESS_2_SHADER_SAMPLED_READ_BIT);
    vkCmdWriteTimestamp2(cmd, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, pool, 1);

    vk::transition(cmd, color_, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
                   VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, 0, VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
                   VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
    vk::transition(cmd, depth_, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL,
                   VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT, 0, VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT,
                   VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT);
    begin(cmd, &color_, depth_.layerView(0), width_, height_);
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, cameraPipe_.get());
    vkCmdSetCullMode(cmd, VK_CULL_MODE_NONE);
    vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, layout_.get(), 0, 1, &set_, 0, nullptr);
    p = {cameraClip_, lightTex_};
    vkCmdPushConstants(cmd, layout_.get(), VK_SHADER_STAGE_VERTEX_BIT, 0, sizeof(p), &p);
    vkCmdDrawIndexed(cmd, indexCount_, 1, 0, 0, 0);
    vkCmdEndRendering(cmd);
    vkCmdWriteTimestamp2(cmd, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, pool, 2);
    const std::vector<double> ms = endFrame(3);
    return {ms[0], ms[1]};
  }

  // The shadow pass alone into a depth+stencil map, the draw split into `draws` parts each writing
  // its own stencil reference (the object id): its GPU time.
  double stencilShadow(int draws, bool d32) {
    const vk::Image& map = d32 ? mapStencil32_ : mapStencil_;
    VkCommandBuffer cmd = beginFrame();
    VkQueryPool pool = queries_.get();
    vk::transition(cmd, map, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL,
                   VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, 0, VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT,
                   VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT);
    begin(cmd, nullptr, map.layerView(0), kMapSize, kMapSize, true);
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, (d32 ? shadowStencil32Pipe_ : shadowStencilPipe_).get());
    vkCmdSetCullMode(cmd, VK_CULL_MODE_NONE);
    vkCmdSetDepthBias(cmd, 1.0f, 0.0f, 1.0f);
    Push p{lightClip_, lightTex_};
    vkCmdPushConstants(cmd, layout_.get(), VK_SHADER_STAGE_VERTEX_BIT, 0, sizeof(p), &p);
    uint32_t per = (indexCount_ / 3 + uint32_t(draws) - 1) / uint32_t(draws) * 3;
    for (int k = 0; k < draws; ++k) {
      uint32_t first = uint32_t(k) * per, count = std::min(per, indexCount_ - std::min(indexCount_, first));
      vkCmdSetStencilReference(cmd, VK_STENCIL_FACE_FRONT_AND_BACK, uint32_t(k + 1));
      if (count) vkCmdDrawIndexed(cmd, count, 1, first, 0, 0);
    }
    vkCmdEndRendering(cmd);
    vkCmdWriteTimestamp2(cmd, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, pool, 1);
    return endFrame(2)[0];
  }

  // Of the image's pixels, the fraction drawn (not the clear value) and, of those, the fraction in
  // shadow: evidence that the bare program renders the scene and looks its map up.
  std::pair<double, double> coverage() const {
    color_.invalidate(c_);
    size_t drawn = 0, dark = 0;
    for (int y = 0; y < height_; ++y) {
      const uint8_t* row = static_cast<const uint8_t*>(color_.mapped()) + size_t(y) * color_.rowPitch();
      for (int x = 0; x < width_; ++x)
        if (row[x] != kClearByte) drawn++, dark += row[x] < 128;
    }
    return {double(drawn) / (double(width_) * height_), drawn ? double(dark) / double(drawn) : 0.0};
  }

  // The bare harness's readback: the visibility bytes, one per pixel, into `out`.
  void readback(std::vector<uint8_t>& out) const {
    color_.invalidate(c_);
    out.resize(size_t(width_) * size_t(height_));
    for (int y = 0; y < height_; ++y) {
      const uint8_t* row = static_cast<const uint8_t*>(color_.mapped()) + size_t(y) * color_.rowPitch();
      std::copy(row, row + width_, out.data() + size_t(y) * size_t(width_));
    }
  }

 private:
  // A frame's command buffer: its timestamps reset, the first written, the mesh bound.
  VkCommandBuffer beginFrame() {
    VkCommandBuffer cmd = commands_.begin();
    vkCmdResetQueryPool(cmd, queries_.get(), 0, 3);
    vkCmdWriteTimestamp2(cmd, VK_PIPELINE_STAGE_2_TOP_OF_PIPE_BIT, queries_.get(), 0);
    VkDeviceSize offset = 0;
    VkBuffer vb = vertices_.get();
    vkCmdBindVertexBuffers(cmd, 0, 1, &vb, &offset);
    vkCmdBindIndexBuffer(cmd, indices_.get(), 0, VK_INDEX_TYPE_UINT32);
    return cmd;
  }

  // Submits beginFrame()'s command buffer and waits: the milliseconds between its `stamps`
  // consecutive timestamps.
  std::vector<double> endFrame(uint32_t stamps) {
    commands_.submitAndWait();
    uint64_t t[3] = {};
    VK_CHECK(vkGetQueryPoolResults(c_.device(), queries_.get(), 0, stamps, sizeof(t), t, sizeof(uint64_t),
                                   VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT));
    const double ms = c_.properties().limits.timestampPeriod * 1e-6;
    std::vector<double> out;
    for (uint32_t i = 1; i < stamps; ++i) out.push_back(double(t[i] - t[i - 1]) * ms);
    return out;
  }

  // stencil: depthView is a depth+stencil image's, both aspects attached.
  void begin(VkCommandBuffer cmd, const vk::Image* color, VkImageView depthView, int w, int h, bool stencil = false) {
    VkRenderingAttachmentInfo c{VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO};
    if (color) {
      c.imageView = color->layerView(0);
      c.imageLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
      c.loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
      c.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
      c.clearValue.color.float32[0] = kClearVis;
    }
    VkRenderingAttachmentInfo d{VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO};
    d.imageView = depthView;
    d.imageLayout =
        stencil ? VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL : VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL;
    d.loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
    d.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
    d.clearValue.depthStencil = {1.0f, 0};
    VkRenderingInfo info{VK_STRUCTURE_TYPE_RENDERING_INFO};
    info.renderArea = {{0, 0}, {uint32_t(w), uint32_t(h)}};
    info.layerCount = 1;
    info.colorAttachmentCount = color ? 1 : 0;
    info.pColorAttachments = color ? &c : nullptr;
    info.pDepthAttachment = &d;
    info.pStencilAttachment = stencil ? &d : nullptr;
    vkCmdBeginRendering(cmd, &info);
    VkViewport viewport{0, 0, float(w), float(h), 0.0f, 1.0f};
    VkRect2D scissor{{0, 0}, {uint32_t(w), uint32_t(h)}};
    vkCmdSetViewport(cmd, 0, 1, &viewport);
    vkCmdSetScissor(cmd, 0, 1, &scissor);
  }

  const vk::Context& c_;
  vk::Commands commands_;
  vk::DescriptorSetLayout setLayout_;
  vk::PipelineLayout layout_;
  vk::DescriptorPool pool_;
  VkDescriptorSet set_ = VK_NULL_HANDLE;
  vk::ShaderModule shadowVert_, shadowFrag_, shadowIdsFrag_, cameraVert_, cameraFrag_;
  vk::PipelineHandle shadowPipe_, shadowIdsPipe_, cameraPipe_, shadowStencilPipe_, shadowStencil32Pipe_;
  vk::Sampler samplers_[2];
  vk::QueryPool queries_;
  vk::Buffer vertices_, indices_;
  uint32_t indexCount_ = 0;
  glm::mat4 lightClip_{1.0f}, lightTex_{1.0f}, cameraClip_{1.0f};
  int width_ = 0, height_ = 0;
  vk::Image map_, mapIds_, color_, depth_, mapStencil_, mapStencil32_;
};

vk::Context& bareContext() {
  static vk::Context c(vk::ContextOptions{});  // lavapipe, no validation
  return c;
}

// Every iteration draws its shadow maps: a configuration's whole cost, as in a sweep whose
// shadow pass changes from row to row.
Rasterizer& rasterizer() {
  static Rasterizer r([] {
    RasterDeviceOptions o;
    o.keepShadowMaps = false;
    return o;
  }());
  return r;
}

// One iteration: a bare frame, then a shadowlab frame (visibility buffer kept, as in a sweep, and
// its time included in camera_gpu_ms as in raster.json). Iteration time: shadowlab's two passes.
void versusBare(benchmark::State& state, Filter filter, int copies) {
  const Scene& s = bench::benchScene(copies);
  BareProgram bare(bareContext());
  bare.setScene(s);
  const bool linear = filter == Filter::Hw2x2;
  Method m;
  m.mapSize = kMapSize;
  m.filter = filter;
  RasterTimings t;
  for (int i = 0; i < 2; ++i)  // warm-up: lavapipe compiles shaders at the first draw
    bare.frame(linear), bare.frame(linear, true), rasterizer().render(s, m, "", &t);
  std::vector<double> bs, bc, ss, sc;
  for (auto _ : state) {
    BareTimes b = bare.frame(linear);
    rasterizer().render(s, m, "", &t);
    state.SetIterationTime((t.shadowGpuMs + t.cameraGpuMs) * 1e-3);
    bs.push_back(b.shadowGpuMs), bc.push_back(b.cameraGpuMs), ss.push_back(t.shadowGpuMs), sc.push_back(t.cameraGpuMs);
  }
  auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.empty() ? 0.0 : v[v.size() / 2];
  };
  // Medians per iteration: one slow frame (the VM's neighbours) does not move them.
  state.counters["bare_shadow_gpu_ms"] = median(bs);
  state.counters["bare_camera_gpu_ms"] = median(bc);
  state.counters["shadow_gpu_ms"] = median(ss);
  state.counters["camera_gpu_ms"] = median(sc);
  state.counters["shadow_ratio"] = median(ss) / median(bs);
  state.counters["camera_ratio"] = median(sc) / median(bc);
  state.counters["triangles"] = double(s.triangleCount());
  std::vector<double> withIds;
  for (int i = 0; i < 9; ++i) withIds.push_back(bare.frame(linear, true).shadowGpuMs);
  state.counters["bare_ids_shadow_gpu_ms"] = median(withIds);
  state.counters["shadow_ratio_ids"] = median(ss) / median(withIds);
  for (int d32 = 0; d32 < 2; ++d32) {
    std::vector<double> st, dep;
    for (int i = 0; i < 3; ++i) bare.stencilShadow(4, d32);
    for (int i = 0; i < 9; ++i) st.push_back(bare.stencilShadow(4, d32)), dep.push_back(bare.frame(linear).shadowGpuMs);
    state.counters[d32 ? "bare_stencil32_shadow_gpu_ms" : "bare_stencil_shadow_gpu_ms"] = median(st);
    state.counters[d32 ? "bare_depth_shadow_gpu_ms_2" : "bare_depth_shadow_gpu_ms"] = median(dep);
  }
  auto [drawn, shadowed] = bare.coverage();
  state.counters["bare_drawn"] = drawn;
  state.counters["bare_shadowed"] = shadowed;
  state.SetLabel(rasterizer().deviceName());
}

// The scenes of the goal at 1920x1080: sphere_on_plane, and the four-bunny bench scene.
const Scene& goalScene(const std::string& name) {
  if (name == "bunny_x4") return bench::benchScene(4);
  static std::map<std::string, Scene> cache;
  auto it = cache.find(name);
  if (it != cache.end()) return it->second;
  Scene s = loadScene(resolveScenePath(name));
  s.camera.width = 1920;
  s.camera.height = 1080;
  return cache.emplace(name, std::move(s)).first->second;
}

// The reference of a scene, traced once (a sweep reads it from its cache: not a per-configuration cost).
const Frame& referenceOf(const Scene& s) {
  static std::map<std::string, Frame> cache;
  auto it = cache.find(s.name + s.hash);
  if (it != cache.end()) return it->second;
  return cache.emplace(s.name + s.hash, renderReference(s, ReferenceOptions{})).first->second;
}

// One iteration: a bare harness configuration, then a shadowlab one, each end to end (passes,
// readback, count or compare). Iteration time: shadowlab's.
void harnessVsBare(benchmark::State& state, const std::string& sceneName, Filter filter, bool full) {
  const Scene& s = goalScene(sceneName);
  const Frame& ref = referenceOf(s);
  // The bare count's reference: the traced visibility as bytes, 255 lit, 0 shadowed, the clear
  // value where no surface is (what the bare camera pass leaves there).
  const std::vector<float>& refVis = ref.get("light." + s.lights.front().name + ".vis");
  const std::vector<float>& refHit = ref.get("hit");
  std::vector<uint8_t> refBytes(refVis.size());
  for (size_t i = 0; i < refVis.size(); ++i) refBytes[i] = refHit[i] < 0.5f ? kClearByte : (refVis[i] > 0.5f ? 255 : 0);
  BareProgram bare(bareContext());
  bare.setScene(s);
  const bool linear = filter == Filter::Hw2x2;
  Method m;
  m.mapSize = kMapSize;
  m.filter = filter;
  RasterTimings t;
  std::vector<uint8_t> bytes;
  const EvidenceSelector selectLocal = disagreementSelector(ref, s.lights.front().name);
  const EvidenceSelector* select = full ? nullptr : &selectLocal;
  for (int i = 0; i < 2; ++i)
    bare.frame(linear), rasterizer().recycle(rasterizer().render(s, m, "", &t, nullptr, select));
  CompareContext context;
  if (!full) {
    Frame f = rasterizer().render(s, m, "", &t, nullptr, select);
    context = CompareContext(ref, f);
    rasterizer().recycle(std::move(f));
  }
  std::vector<double> bs, bc, br, bn, ss, sc, sl, sr, sx, se, sv, sxc;
  double partial = 0, listed = 0;
  size_t bareWrong = 0;
  double rasterWrong = 0;
  for (auto _ : state) {
    const BareTimes b = bare.frame(linear);
    auto t0 = std::chrono::steady_clock::now();
    bare.readback(bytes);
    br.push_back(msSince(t0));
    t0 = std::chrono::steady_clock::now();
    size_t wrong = 0;
    for (size_t i = 0; i < bytes.size(); ++i) wrong += (bytes[i] >= 128) != (refBytes[i] >= 128);
    bn.push_back(msSince(t0));
    bareWrong = wrong;
    benchmark::DoNotOptimize(wrong);

    Frame f = rasterizer().render(s, m, "", &t, nullptr, select);
    t0 = std::chrono::steady_clock::now();
    const Metrics metrics = compareFrames(ref, f);
    sx.push_back(msSince(t0));
    rasterWrong = metrics.toJson().value("error_rate", 0.0);
    if (!full) {
      t0 = std::chrono::steady_clock::now();
      const Metrics viaContext = compareFrames(context, ref, f);
      sxc.push_back(msSince(t0));
      if (!context.appliesTo(ref, f) || viaContext.toJson() != metrics.toJson()) {
        state.SkipWithError("compareFrames through the context: not applied, or other metrics");
        break;
      }
    }
    rasterizer().recycle(std::move(f));
    // Per configuration: the full frame's passes (the lookup not counted, as before), or on demand
    // the shadow, lookup and evidence passes (the visibility buffer is kept between configurations).
    const double camera = full ? t.cameraGpuMs : t.lookupGpuMs + t.evidenceGpuMs;
    state.SetIterationTime((t.shadowGpuMs + camera + t.readbackMs + sx.back()) * 1e-3);
    bs.push_back(b.shadowGpuMs), bc.push_back(b.cameraGpuMs), ss.push_back(t.shadowGpuMs), sc.push_back(camera),
        sl.push_back(t.lookupGpuMs), sr.push_back(t.readbackMs), se.push_back(t.evidenceGpuMs),
        sv.push_back(t.visibilityGpuMs);
    partial += t.partialEvidence, listed += double(t.evidencePixels);
  }
  auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.empty() ? 0.0 : v[v.size() / 2];
  };
  const double bareMs = median(bs) + median(bc) + median(br) + median(bn);
  const double ours = median(ss) + median(sc) + median(sr) + median(sx);
  state.counters["bare_shadow_gpu_ms"] = median(bs);
  state.counters["bare_camera_gpu_ms"] = median(bc);
  state.counters["bare_readback_ms"] = median(br);
  state.counters["bare_count_ms"] = median(bn);
  state.counters["bare_total_ms"] = bareMs;
  state.counters["shadow_gpu_ms"] = median(ss);
  state.counters["camera_ms"] = median(sc);  // full: camera_gpu_ms; on demand: lookup + evidence
  state.counters["evidence_gpu_ms"] = median(se);
  state.counters["visibility_gpu_ms"] = median(sv);
  state.counters["total_with_visibility_ms"] = ours + (full ? 0.0 : median(sv));
  state.counters["ratio_with_visibility"] = (ours + (full ? 0.0 : median(sv))) / bareMs;
  state.counters["partial_fraction"] = partial / double(std::max<size_t>(1, sx.size()));
  state.counters["evidence_pixels"] = listed / double(std::max<size_t>(1, sx.size()));
  state.counters["readback_ms"] = median(sr);
  state.counters["compare_ms"] = median(sx);
  if (!full) {
    const double oursContext = median(ss) + median(sc) + median(sr) + median(sxc);
    state.counters["compare_context_ms"] = median(sxc);
    state.counters["total_context_ms"] = oursContext;
    state.counters["ratio_context"] = oursContext / bareMs;
  }
  state.counters["total_ms"] = ours;
  state.counters["ratio"] = ours / bareMs;  // the goal: <= 1.3
  // The method's time (the report's axis) against the bare program's two passes.
  state.counters["lookup_gpu_ms"] = median(sl);
  state.counters["method_ratio"] = (median(ss) + median(sl)) / (median(bs) + median(bc));
  state.counters["bare_wrong_fraction"] = double(bareWrong) / double(bytes.size());
  state.counters["error_rate"] = rasterWrong;
  state.SetLabel(rasterizer().deviceName());
}

}  // namespace

BENCHMARK_CAPTURE(harnessVsBare, none_sphere, "sphere_on_plane", Filter::None, false)
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(harnessVsBare, none_sphere_full, "sphere_on_plane", Filter::None, true)
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(harnessVsBare, hw2x2_sphere, "sphere_on_plane", Filter::Hw2x2, false)
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(harnessVsBare, hw2x2_sphere_full, "sphere_on_plane", Filter::Hw2x2, true)
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(harnessVsBare, none_bunny_x4, "bunny_x4", Filter::None, false)
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(harnessVsBare, none_bunny_x4_full, "bunny_x4", Filter::None, true)
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(harnessVsBare, hw2x2_bunny_x4, "bunny_x4", Filter::Hw2x2, false)
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(harnessVsBare, hw2x2_bunny_x4_full, "bunny_x4", Filter::Hw2x2, true)
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(versusBare, none_bunny, Filter::None, 1)->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(versusBare, none_bunny_x4, Filter::None, 4)->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(versusBare, hw2x2_bunny, Filter::Hw2x2, 1)->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(versusBare, hw2x2_bunny_x4, Filter::Hw2x2, 4)->UseManualTime()->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
