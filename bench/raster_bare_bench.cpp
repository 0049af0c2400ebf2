// The speed goals' yardstick, measured here rather than quoted: a bare single-purpose shadow-mapping
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
// of every channel, compareFrames), every evidence channel at every pixel. The reference is
// traced once per scene before timing (a sweep reads it from its cache).
// The on-demand captures also time compareFrames through a CompareContext made before the loop
// from a frame of the configuration's group, as the sweep keeps one per group (compare.h):
// compare_context_ms, total_context_ms, ratio_context (the iteration time stays the full
// compareFrames'); each iteration checks both give the same metrics JSON.
//
// bareSweep: the yardstick of the 100-configuration sweep's 5 s goal (compare/SWEEPS.md), that bare
// harness over the sweep's 100 configurations in its order (the map size and depth bias of each
// row, the facing rule and pcf 3x3 in the camera pass, the light's map fit as shadowlab fits it, so
// that its counts match shadowlab's error counts), beside the same configurations through the
// sweep's own runner in the same process. Run: build/bench/raster_bare_bench --benchmark_filter=bareSweep
#include <benchmark/benchmark.h>

#include <glm/gtc/matrix_transform.hpp>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <map>
#include <vector>

#include "bare_camera_facing_frag.h"
#include "bare_camera_frag.h"
#include "bare_camera_pcf_frag.h"
#include "bare_camera_vert.h"
#include "bare_shadow_frag.h"
#include "bare_shadow_ids_frag.h"
#include "bare_shadow_vert.h"
#include "bench_scene.h"
#include "light_space.h"
#include "shadowlab/compare/compare.h"
#include "shadowlab/compare/run_pipeline.h"
#include "shadowlab/compare/sweep.h"
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

// One bare frame's settings: the camera pass's lookup, the shadow pass's depth bias (shadowlab's
// bias.constant, bias.slope, bias.clamp: vkCmdSetDepthBias with the same values, rasterizer.cpp),
// and whether the shadow pass is drawn or the last frame's map kept (a sweep's filter axis).
struct BareFrame {
  // Nearest, Linear: one comparison (bare_camera.frag); NearestFacing: and unlit where the light is
  // behind the visible side, as shadowlab's facing rule (bare_camera_facing.frag); Pcf3Facing:
  // pcf 3x3's nine comparisons and the facing rule (bare_camera_pcf.frag).
  enum class Lookup { Nearest, Linear, NearestFacing, Pcf3Facing } lookup = Lookup::Nearest;
  float biasConstant = 1.0f, biasSlope = 1.0f, biasClamp = 0.0f;
  bool ids = false;  // the shadow pass also writes the R32_UINT id attachment
  bool drawShadow = true;
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
    cameraFacingFrag_ = vk::createShaderModule(c, kSpv_bare_camera_facing_frag, sizeof(kSpv_bare_camera_facing_frag));
    cameraPcfFrag_ = vk::createShaderModule(c, kSpv_bare_camera_pcf_frag, sizeof(kSpv_bare_camera_pcf_frag));
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
    cameraFacingPipe_ =
        pipeline(cameraVert_.get(), cameraFacingFrag_.get(), {VK_FORMAT_R8_UNORM}, VK_FORMAT_D32_SFLOAT, false);
    cameraPcfPipe_ =
        pipeline(cameraVert_.get(), cameraPcfFrag_.get(), {VK_FORMAT_R8_UNORM}, VK_FORMAT_D32_SFLOAT, false);
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
    mapSize_ = 0;
    setMapSize(kMapSize);
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

  // The depth map's texels per side: made again when it changes, as shadowlab's is (the new map
  // is drawn by the next frame, whose drawShadow must be true). The id attachment follows when a
  // frame asks for it.
  void setMapSize(int size) {
    if (size == mapSize_) return;
    map_ = vk::Image();  // released first: maps of 4096^2
    mapIds_ = vk::Image();
    map_ =
        vk::Image(c_, size, size, 1, VK_FORMAT_X8_D24_UNORM_PACK32,
                  VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT, VK_IMAGE_ASPECT_DEPTH_BIT);
    mapSize_ = size;
  }

  // The light's map as shadowlab fits it for `method` (raster/src/light_space.h, fitLight: for the
  // sphere fit the same texel grid and depth range at every map size), instead of setScene's own
  // fit: each texel and depth step then the same as shadowlab's, so that the bare harness's
  // decisions are the same up to the lookup's rounding. A directional light with one layer only.
  void useShadowlabFit(const Scene& s, const Method& method) {
    const raster::LightSpace fit = raster::fitLight(s, s.lights.front(), method, s.camera);
    if (fit.layers.size() != 1 || fit.layers.front().lightDepth)
      throw std::logic_error("bare program: one plain map layer only");
    lightTex_ = fit.layers.front().texFromWorld;
    lightClip_ = raster::clipFromTex() * lightTex_;
  }

  // ids: the shadow pass also writes an R32_UINT id attachment (shadowlab's evidence contract).
  // The constant depth bias 1 and slope factor 1.
  BareTimes frame(bool linear, bool ids = false) {
    BareFrame f;
    f.lookup = linear ? BareFrame::Lookup::Linear : BareFrame::Lookup::Nearest;
    f.ids = ids;
    return frame(f);
  }

  BareTimes frame(const BareFrame& f) {
    const bool ids = f.ids;
    if (ids && mapIds_.width() != mapSize_)
      mapIds_ = vk::Image(c_, mapSize_, mapSize_, 1, VK_FORMAT_R32_UINT, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT,
                          VK_IMAGE_ASPECT_COLOR_BIT);
    // pcf gathers comparisons: the sampler's filter does not apply to a gather.
    const bool linear = f.lookup == BareFrame::Lookup::Linear;
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

    if (f.drawShadow) {
      vk::transition(cmd, map_, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL,
                     VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, 0, VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT,
                     VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT);
      if (ids)
        vk::transition(cmd, mapIds_, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
                       VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, 0,
                       VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
      begin(cmd, ids ? &mapIds_ : nullptr, map_.layerView(0), mapSize_, mapSize_);
      vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, (ids ? shadowIdsPipe_ : shadowPipe_).get());
      vkCmdSetCullMode(cmd, VK_CULL_MODE_NONE);
      vkCmdSetDepthBias(cmd, f.biasConstant, f.biasClamp, f.biasSlope);
      const Push light{lightClip_, lightTex_};
      vkCmdPushConstants(cmd, layout_.get(), VK_SHADER_STAGE_VERTEX_BIT, 0, sizeof(light), &light);
      vkCmdDrawIndexed(cmd, indexCount_, 1, 0, 0, 0);
      vkCmdEndRendering(cmd);
      vk::transition(cmd, map_, VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
                     VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT, VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT,
                     VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, VK_ACCESS_2_SHADER_SAMPLED_READ_BIT);
    }
    vkCmdWriteTimestamp2(cmd, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, pool, 1);

    vk::transition(cmd, color_, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
                   VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, 0, VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
                   VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
    vk::transition(cmd, depth_, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL,
                   VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT, 0, VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT,
                   VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT);
    begin(cmd, &color_, depth_.layerView(0), width_, height_);
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS,
                      (f.lookup == BareFrame::Lookup::Pcf3Facing      ? cameraPcfPipe_
                       : f.lookup == BareFrame::Lookup::NearestFacing ? cameraFacingPipe_
                                                                      : cameraPipe_)
                          .get());
    vkCmdSetCullMode(cmd, VK_CULL_MODE_NONE);
    vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, layout_.get(), 0, 1, &set_, 0, nullptr);
    const Push p = {cameraClip_, lightTex_};
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
  vk::ShaderModule shadowVert_, shadowFrag_, shadowIdsFrag_, cameraVert_, cameraFrag_, cameraFacingFrag_,
      cameraPcfFrag_;
  vk::PipelineHandle shadowPipe_, shadowIdsPipe_, cameraPipe_, cameraFacingPipe_, cameraPcfPipe_, shadowStencilPipe_,
      shadowStencil32Pipe_;
  vk::Sampler samplers_[2];
  vk::QueryPool queries_;
  vk::Buffer vertices_, indices_;
  uint32_t indexCount_ = 0;
  glm::mat4 lightClip_{1.0f}, lightTex_{1.0f}, cameraClip_{1.0f};
  int width_ = 0, height_ = 0, mapSize_ = 0;
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

// The scenes of the speed goal at 1920x1080: sphere_on_plane, and the four-bunny bench scene.
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

// The bare count's reference: the traced visibility as bytes, 255 lit, 0 shadowed, the clear
// value where no surface is (what the bare camera pass leaves there).
std::vector<uint8_t> referenceBytes(const Scene& s, const Frame& ref) {
  const std::vector<float>& refVis = ref.get("light." + s.lights.front().name + ".vis");
  const std::vector<float>& refHit = ref.get("hit");
  std::vector<uint8_t> bytes(refVis.size());
  for (size_t i = 0; i < refVis.size(); ++i) bytes[i] = refHit[i] < 0.5f ? kClearByte : (refVis[i] > 0.5f ? 255 : 0);
  return bytes;
}

// One iteration: a bare harness configuration, then a shadowlab one, each end to end (passes,
// readback, count or compare). Iteration time: shadowlab's.
void harnessVsBare(benchmark::State& state, const std::string& sceneName, Filter filter, bool full) {
  const Scene& s = goalScene(sceneName);
  const Frame& ref = referenceOf(s);
  const std::vector<uint8_t> refBytes = referenceBytes(s, ref);
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
    // Per configuration: the full frame's passes (the lookup not counted), or on demand
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

// The 100 configurations of compare/SWEEPS.md's speed case (sphere_on_plane at 1920x1080, map.size
// 256..4096 x bias.slope 0..12 x filter none, pcf), planned by planSweep as `shadowlab sweep` plans
// them: the same scene, methods and order (filter fastest, then bias.slope, map.size slowest).
SweepPlan speedCasePlan() {
  SweepSpec spec;
  spec.scenes = {"sphere_on_plane"};
  spec.grid.push_back(parseGridArgument("map.size=256,512,1024,2048,4096"));
  spec.grid.push_back(parseGridArgument("bias.slope=0,0.5,1,1.5,2,3,4,6,8,12"));
  spec.grid.push_back(parseGridArgument("filter=none,pcf"));
  spec.fixed.push_back(parseSetArgument("scene:/camera/width=1920"));
  spec.fixed.push_back(parseSetArgument("scene:/camera/height=1080"));
  return planSweep(spec);
}

// One pass of the bare harness over the plan: sums over its configurations.
struct BareSweepPass {
  double wallS = 0, shadowGpuS = 0, cameraGpuS = 0, readbackS = 0, countS = 0;
  int shadowPasses = 0;
  std::vector<size_t> wrong;  // per configuration: the pixels whose decision disagrees with the reference
  // Adds another pass's sums (the shadow passes are per pass: the same in every one).
  void add(const BareSweepPass& o) {
    wallS += o.wallS, shadowGpuS += o.shadowGpuS, cameraGpuS += o.cameraGpuS, readbackS += o.readbackS,
        countS += o.countS, shadowPasses = o.shadowPasses;
  }
  // Its counters, each sum divided by `n` (the passes added), named prefix + what.
  void counters(benchmark::State& state, const std::string& prefix, double n) const {
    state.counters[prefix + "sweep_s"] = wallS / n;
    state.counters[prefix + "shadow_gpu_s"] = shadowGpuS / n;
    state.counters[prefix + "camera_gpu_s"] = cameraGpuS / n;
    state.counters[prefix + "readback_s"] = readbackS / n;
    state.counters[prefix + "count_s"] = countS / n;
    state.counters[prefix + "shadow_passes"] = shadowPasses;
  }
};

// The bare harness over every configuration of the plan, in its order, each end to end: the map
// made again when its size changes, the depth-only shadow pass with the row's depth bias (drawn
// every row, or with keepMaps only when the map size or the bias changed: shadowlab keeps its maps
// over the filter axis), the camera pass (one comparison, or pcf 3x3's nine), the 1-byte readback
// and the CPU count against the reference's bytes.
BareSweepPass bareSweepPass(BareProgram& bare, const SweepPlan& plan, const std::vector<uint8_t>& refBytes,
                            bool keepMaps) {
  BareSweepPass out;
  std::vector<uint8_t> bytes;
  int lastSize = 0;
  float lastConstant = 0, lastSlope = 0, lastClamp = 0;
  const auto wall0 = std::chrono::steady_clock::now();
  for (const SweepJob& job : plan.jobs) {
    const Method& m = plan.configs[job.configIndex].method;
    if (m.filter != Filter::None && m.filter != Filter::Pcf) throw std::logic_error("bare sweep: none or pcf only");
    if (m.filter == Filter::Pcf && m.filterSize != 3) throw std::logic_error("bare sweep: pcf 3x3 only");
    BareFrame f;
    f.lookup = m.filter == Filter::Pcf ? BareFrame::Lookup::Pcf3Facing : BareFrame::Lookup::NearestFacing;
    f.biasConstant = m.biasConstant, f.biasSlope = m.biasSlope, f.biasClamp = m.biasClamp;
    f.drawShadow = !keepMaps || m.mapSize != lastSize || m.biasConstant != lastConstant || m.biasSlope != lastSlope ||
                   m.biasClamp != lastClamp;
    lastSize = m.mapSize, lastConstant = m.biasConstant, lastSlope = m.biasSlope, lastClamp = m.biasClamp;
    bare.setMapSize(m.mapSize);
    const BareTimes t = bare.frame(f);
    auto t0 = std::chrono::steady_clock::now();
    bare.readback(bytes);
    out.readbackS += msSince(t0) * 1e-3;
    t0 = std::chrono::steady_clock::now();
    size_t wrong = 0;
    for (size_t i = 0; i < bytes.size(); ++i) wrong += (bytes[i] >= 128) != (refBytes[i] >= 128);
    out.countS += msSince(t0) * 1e-3;
    out.wrong.push_back(wrong);
    out.shadowGpuS += t.shadowGpuMs * 1e-3, out.cameraGpuS += t.cameraGpuMs * 1e-3;
    out.shadowPasses += f.drawShadow ? 1 : 0;
  }
  out.wallS = msSince(wall0) * 1e-3;
  return out;
}

// One pass of shadowlab over the plan through the sweep's own runner (makePipelineRunner: the
// reference held in memory, Rasterizer::render with evidence on demand through the disagreement
// selector, compareFrames through a CompareContext per evidence group, recycle): sums of the rows'
// timings as results.json has them.
struct ShadowlabSweepPass {
  double wallS = 0, shadowGpuS = 0, lookupGpuS = 0, evidenceGpuS = 0, readbackS = 0, compareS = 0, renderWallS = 0;
  double retimeS = 0;  // the rows near the front timed again (part of wallS)
  size_t retimedRows = 0;
  std::vector<double> errors;  // per configuration: the metrics' error pixel count
};

ShadowlabSweepPass shadowlabSweepPass(SweepRunner& runner, const SweepPlan& plan) {
  ShadowlabSweepPass out;
  const auto wall0 = std::chrono::steady_clock::now();
  std::vector<ResultRow> rows;
  for (const SweepJob& job : plan.jobs) {
    const SweepRunOutput row =
        runner.run(plan.variants[job.variantIndex], plan.configs[job.configIndex].method, job.light, "");
    auto sum = [&](double& to, const char* key) { to += row.timings.value(key, 0.0) * 1e-3; };
    sum(out.shadowGpuS, "shadow_gpu_ms"), sum(out.lookupGpuS, "lookup_gpu_ms"),
        sum(out.evidenceGpuS, "evidence_gpu_ms");
    sum(out.readbackS, "readback_ms"), sum(out.compareS, "compare_ms"), sum(out.renderWallS, "render_wall_ms");
    out.errors.push_back(row.metrics.value("errors", 0.0));
    ResultRow r;
    r.scene = job.sceneName;
    r.metrics = row.metrics;
    r.timings = row.timings;
    rows.push_back(std::move(r));
  }
  // The default timing, as runSweep does it: the rows near the front timed again to a median.
  const auto retime0 = std::chrono::steady_clock::now();
  std::vector<const ResultRow*> ptrs;
  for (const ResultRow& r : rows) ptrs.push_back(&r);
  for (size_t i : jobsWhoseTimeDecides(plan, ptrs)) {
    const SweepJob& job = plan.jobs[i];
    runner.timeAgain(plan.variants[job.variantIndex], plan.configs[job.configIndex].method, job.light,
                     kDefaultTimingRepetitions - 1);
    ++out.retimedRows;
  }
  out.retimeS = msSince(retime0) * 1e-3;
  out.wallS = msSince(wall0) * 1e-3;
  return out;
}

// bareSweep: the yardstick of the 100-configuration sweep's 5 s goal (compare/SWEEPS.md). One iteration: the
// bare harness over the 100 configurations with the shadow pass drawn every row (bare_sweep_s),
// again with the maps kept over the filter axis as shadowlab keeps them (bare_kept_sweep_s), then
// the same 100 configurations through shadowlab's sweep runner (shadowlab_sweep_s: its loop, what
// results.json's loop_wall_seconds measures less the journal and progress, ~0.1 ms a row). The
// references are traced and each program's pipelines compiled in a first pass before timing
// (*_first_pass_s: a sweep's first rows pay those compiles); the counters are means over the
// iterations. Stage sums: the bare passes' GPU timestamps, its readback and count (CPU); shadowlab's
// the rows' timings as results.json has them (shadowlab_shadow_gpu_s counts a kept map's time on
// every row that uses it, as the sweep's rows do; bare_shadow_gpu_s draws it every row).
// Iteration time: the bare sweep's. The answers: bare_wrong_sum (pixels whose bare decision
// disagrees with the reference, over the 100 rows) beside shadowlab_errors_sum (the metrics' error
// pixels), and the largest difference of one configuration.
void bareSweep(benchmark::State& state) {
  const SweepPlan plan = speedCasePlan();
  const Scene& s = plan.variants.at(plan.jobs.front().variantIndex);
  for (const SweepJob& job : plan.jobs)
    if (job.variantIndex != plan.jobs.front().variantIndex) throw std::logic_error("bare sweep: one scene variant");
  const Frame& ref = referenceOf(s);
  const std::vector<uint8_t> refBytes = referenceBytes(s, ref);
  BareProgram bare(bareContext());
  bare.setScene(s);
  bare.useShadowlabFit(s, plan.configs.front().method);
  namespace fs = std::filesystem;
  const fs::path cache = fs::temp_directory_path() / ("shadowlab_bare_sweep_cache_" + std::to_string(::getpid()));
  std::unique_ptr<SweepRunner> runner = makePipelineRunner(cache.string(), 1);

  const BareSweepPass bareFirst = bareSweepPass(bare, plan, refBytes, false);
  const auto first0 = std::chrono::steady_clock::now();
  shadowlabSweepPass(*runner, plan);
  const double oursFirstS = msSince(first0) * 1e-3;  // with the reference's trace and its cache file
  BareSweepPass drawn, kept;
  ShadowlabSweepPass ours;
  size_t bareWrong = 0, maxDiff = 0;
  double oursErrors = 0;
  for (auto _ : state) {
    const BareSweepPass d = bareSweepPass(bare, plan, refBytes, false);
    const BareSweepPass k = bareSweepPass(bare, plan, refBytes, true);
    const ShadowlabSweepPass o = shadowlabSweepPass(*runner, plan);
    state.SetIterationTime(d.wallS);
    drawn.add(d);
    kept.add(k);
    ours.wallS += o.wallS, ours.shadowGpuS += o.shadowGpuS, ours.lookupGpuS += o.lookupGpuS;
    ours.evidenceGpuS += o.evidenceGpuS, ours.readbackS += o.readbackS, ours.compareS += o.compareS;
    ours.renderWallS += o.renderWallS, ours.retimeS += o.retimeS, ours.retimedRows = o.retimedRows;
    if (d.wrong != k.wrong) {
      state.SkipWithError("bare sweep: keeping the maps changed a configuration's count");
      break;
    }
    bareWrong = 0, oursErrors = 0, maxDiff = 0;
    for (size_t i = 0; i < d.wrong.size(); ++i) {
      bareWrong += d.wrong[i], oursErrors += o.errors[i];
      const double diff = std::fabs(double(d.wrong[i]) - o.errors[i]);
      maxDiff = std::max(maxDiff, size_t(diff));
    }
  }
  const double n = double(std::max<int64_t>(1, state.iterations()));
  state.counters["configurations"] = double(plan.jobs.size());
  state.counters["bare_first_pass_s"] = bareFirst.wallS;
  state.counters["shadowlab_first_pass_s"] = oursFirstS;
  drawn.counters(state, "bare_", n);
  kept.counters(state, "bare_kept_", n);
  state.counters["shadowlab_sweep_s"] = ours.wallS / n;
  state.counters["shadowlab_shadow_gpu_s"] = ours.shadowGpuS / n;
  state.counters["shadowlab_lookup_gpu_s"] = ours.lookupGpuS / n;
  state.counters["shadowlab_evidence_gpu_s"] = ours.evidenceGpuS / n;
  state.counters["shadowlab_readback_s"] = ours.readbackS / n;
  state.counters["shadowlab_compare_s"] = ours.compareS / n;
  state.counters["shadowlab_render_wall_s"] = ours.renderWallS / n;
  state.counters["shadowlab_retime_s"] = ours.retimeS / n;  // the rows near the front timed again
  state.counters["shadowlab_retimed_rows"] = double(ours.retimedRows);
  state.counters["ratio"] = ours.wallS / drawn.wallS;      // shadowlab's loop / the bare loop drawing every map
  state.counters["ratio_kept"] = ours.wallS / kept.wallS;  // / the bare loop keeping maps as shadowlab does
  state.counters["bare_wrong_sum"] = double(bareWrong);
  state.counters["shadowlab_errors_sum"] = oursErrors;
  state.counters["max_config_wrong_diff"] = double(maxDiff);
  state.SetLabel(runner->deviceName());
  runner.reset();
  std::error_code ignored;
  fs::remove_all(cache, ignored);
}

}  // namespace

BENCHMARK(bareSweep)->UseManualTime()->Unit(benchmark::kSecond)->Iterations(2);
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
