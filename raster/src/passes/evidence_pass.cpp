#include "passes/evidence_pass.h"

#include <algorithm>
#include <chrono>
#include <cstring>
#include <iterator>
#include <thread>

#include "shadowlab/scenes/io.h"
#include "vk/check.h"

namespace shadowlab::raster {

namespace {
// The evidence pass's compact targets: listed pixel k at (k % width, k / width).
constexpr int kCompactWidth = 256;
// Listed pixels from which partialFrame scatters the evidence on two threads (a thread's start
// costs ~50 us; 64k pixels' scatter ~1.5 ms).
constexpr size_t kParallelScatter = 65536;

double msSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// Sorted pixel indices (y * width + x) as x | y << 16 into `out` (images are at most 65535 wide).
void packPixels(const std::vector<uint32_t>& sorted, uint32_t width, uint32_t* out) {
  uint32_t y = 0, rowStart = 0;
  for (uint32_t i : sorted) {
    while (i - rowStart >= width) {
      rowStart += width;
      ++y;
    }
    *out++ = (i - rowStart) | (y << 16);
  }
}

// The lookup's bytes into the frame's vis plane (1 at 255, 0 elsewhere; the fractional pixels get
// their floats from the evidence pass afterwards) and the sorted list of the fractional bytes
// (1..254), in one pass over the bytes, 8 at a time. `held` holds the bytes that `plane` already
// encodes (a plane recycle() handed back): only the words that differ are written; `full` (no
// such plane) writes every pixel. `held` then holds `bytes`.
void visFromBytes(const uint8_t* bytes, size_t n, bool full, uint8_t* held, float* plane,
                  std::vector<uint32_t>& fractional) {
  constexpr uint64_t kLow = 0x0101010101010101ull;
  auto encode = [&](size_t i, size_t count) {
    for (size_t j = 0; j < count; ++j) plane[i + j] = bytes[i + j] == 255 ? 1.0f : 0.0f;
  };
  fractional.clear();
  size_t i = 0;
  for (; i + 8 <= n; i += 8) {
    uint64_t w, h;
    std::memcpy(&w, bytes + i, 8);
    std::memcpy(&h, held + i, 8);
    if (full || w != h) {
      encode(i, 8);
      std::memcpy(held + i, &w, 8);
    }
    // A byte is 0 or 255 exactly where it equals its top bit spread over the byte.
    uint64_t frac = w ^ (((w >> 7) & kLow) * 0xFF);
    while (frac) {
      const int byte = __builtin_ctzll(frac) / 8;
      fractional.push_back(uint32_t(i) + uint32_t(byte));
      frac &= ~(uint64_t(0xFF) << (8 * byte));
    }
  }
  for (; i < n; ++i) {
    if (full || bytes[i] != held[i]) encode(i, 1), held[i] = bytes[i];
    if (bytes[i] != 0 && bytes[i] != 255) fractional.push_back(uint32_t(i));
  }
}
}  // namespace

std::string footprintKey(const std::string& cameraKey, const abi::Params& p, const ResolveSpecialization& spec) {
  const int lightLayers = std::clamp(p.sizes.y, 0, abi::kMaxLightLayers);
  uint64_t h = fnv1a64(p.texFromWorld, sizeof(glm::mat4) * size_t(lightLayers));
  h = fnv1a64(p.layerInfo, sizeof(glm::vec4) * size_t(lightLayers), h);
  for (const glm::vec4* v : {&p.lightPosType, &p.lightDirCos, &p.cameraOrigin, &p.rayX, &p.rayY, &p.rayC,
                             &p.cascadeView, &p.cascadeFar[0], &p.cascadeFar[1], &p.lightDepth})
    h = fnv1a64(v, sizeof(glm::vec4), h);
  const float splits[2] = {p.cascadeInfo.y, p.cascadeInfo.z};  // not x: the blend band
  h = fnv1a64(splits, sizeof(splits), h);
  const int32_t sizes[2] = {p.sizes.x, p.sizes.y};
  h = fnv1a64(sizes, sizeof(sizes), h);
  for (int k : {abi::kSpecLightType, abi::kSpecCascaded, abi::kSpecAffine, abi::kSpecLightDepth})
    h = fnv1a64(&spec[size_t(k)], 4, h);
  return cameraKey + "/" + hashHex(h);
}

EvidencePass::EvidencePass(const vk::Context& context) {
  pixels_ = vk::Buffer(context, 4096 * sizeof(uint32_t), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT);
  VkQueryPoolCreateInfo q{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
  q.queryType = VK_QUERY_TYPE_TIMESTAMP;
  q.queryCount = 2;
  VkQueryPool pool;
  VK_CHECK(vkCreateQueryPool(context.device(), &q, nullptr, &pool));
  queries_ = vk::QueryPool(context.device(), pool);
}

EvidencePass::Footprint* EvidencePass::kept(const std::string& camera, const std::string& group) {
  if (cameraPlanes_.key != camera || cameraPlanes_.hit.empty()) return nullptr;
  for (auto it = footprints_.begin(); it != footprints_.end(); ++it)
    if (it->key == group) {
      footprints_.splice(footprints_.begin(), footprints_, it);
      Footprint* f = &footprints_.front();
      return f->m.empty() ? nullptr : f;  // empty: lent to a frame not handed back
    }
  return nullptr;
}

EvidencePass::Footprint& EvidencePass::keepPlanes(const vk::Context& context, const SceneGpu& scene,
                                                  const VisibilityPass& visibility, const vk::Image& planes,
                                                  const std::string& key, const std::string& camera, int width,
                                                  int height) {
  const size_t n = size_t(width) * size_t(height);
  visibility.ids().invalidate(context);
  planes.invalidate(context);
  const bool cameraToo = cameraPlanes_.key != camera || cameraPlanes_.hit.empty();
  if (cameraPlanes_.key != camera) footprints_.clear();  // of another camera: never found again
  if (cameraToo) {
    cameraPlanes_.key.clear();
    cameraPlanes_.hit.resize(n);
    cameraPlanes_.objectId.resize(n);
    cameraPlanes_.primId.resize(n);
  }
  footprints_.remove_if([&](const Footprint& f) { return f.key == key; });  // one whose planes are lent
  while (footprints_.size() >= kKeptFootprints) footprints_.pop_back();
  Footprint f{key, std::vector<float>(n), std::vector<float>(n)};
  auto split = [&](size_t y0, size_t y1) {
    for (int y = int(y0); y < int(y1); ++y) {
      const size_t o = size_t(y) * size_t(width);
      if (cameraToo)
        visibility.cameraRow(scene, y, cameraPlanes_.hit.data() + o, cameraPlanes_.objectId.data() + o,
                             cameraPlanes_.primId.data() + o);
      const float* a = mappedRow<float>(planes, size_t(y));  // m, 2 * cascade + in_map
      for (int x = 0; x < width; ++x) {
        f.m[o + size_t(x)] = a[4 * x];
        f.cascade[o + size_t(x)] = float(int(a[4 * x + 1]) >> 1);
      }
    }
  };
  inTwoHalves(size_t(height), split);
  if (cameraToo) cameraPlanes_.key = camera;
  footprints_.push_front(std::move(f));
  return footprints_.front();
}

EvidencePass::Pipelines EvidencePass::pipelines(const PassContext& pc, ResolvePipelines& resolve,
                                                const ResolveSpecialization& spec,
                                                const ResolveSpecialization& lookupSpec, bool light) {
  // The resolve over the listed pixels only, no projectors; the lookup over those listed for the
  // occluder alone.
  Pipelines p;
  ResolveSpecialization compactSpec = spec;
  compactSpec[abi::kSpecCompact] = 1u;
  compactSpec[abi::kSpecProjectorCount] = 0u;
  p.evidence = resolve.pipeline(pc, compactSpec);
  p.firstUse = warmed_.insert({compactSpec, resolve.techniqueKey()}).second;
  if (light) {
    ResolveSpecialization occluderSpec = lookupSpec;
    occluderSpec[abi::kSpecCompact] = 1u;
    p.occluder = resolve.pipeline(pc, occluderSpec);
    p.firstUse = warmed_.insert({occluderSpec, resolve.techniqueKey()}).second || p.firstUse;
  }
  return p;
}

Frame EvidencePass::partialFrame(const FrameInputs& in, const Scene& sc, const Light& light, const Method& method,
                                 const EvidenceSelector& select, Footprint& footprint, const Pipelines& pipes,
                                 std::vector<std::vector<float>>& spare, RasterTimings& t) {
  const vk::Context& context = *in.pc->context;
  const int width = sc.camera.width, height = sc.camera.height;
  const size_t n = size_t(width) * size_t(height);
  auto t0 = std::chrono::steady_clock::now();
  const uint8_t* vis8 = in.lookup->bytes(context);
  // The vis plane: the one handed back (only the changed bytes rewritten), else a spare one.
  std::vector<float> visPlane;
  const bool visFull = visKept_.plane.size() != n || visKept_.bytes.size() != n;
  if (!visFull) {
    visPlane = std::move(visKept_.plane);
  } else if (!spare.empty()) {
    visPlane = std::move(spare.back());
    spare.pop_back();
  }
  visKept_.plane.clear();
  visPlane.resize(n);
  visKept_.bytes.resize(n);
  // Two threads: the vis plane and the fractional bytes beside the selector.
  std::thread visHelper(visFromBytes, vis8, n, visFull, visKept_.bytes.data(), visPlane.data(), std::ref(fractional_));
  asked_.full.clear();
  asked_.occluder.clear();
  try {
    select(vis8, width, height, asked_);
  } catch (...) {
    visHelper.join();
    throw;
  }
  visHelper.join();
  // The listed pixels, each sorted, once, below n: those asked for every channel, then those whose
  // map texel's evidence alone is asked for and the fractional ones (their exact vis), less the
  // first list's.
  auto sortedOnce = [n](std::vector<uint32_t>& v) {
    if (!std::is_sorted(v.begin(), v.end())) std::sort(v.begin(), v.end());
    v.erase(std::unique(v.begin(), v.end()), v.end());
    v.erase(std::lower_bound(v.begin(), v.end(), uint32_t(n)), v.end());
  };
  sortedOnce(asked_.full);
  sortedOnce(asked_.occluder);
  std::vector<uint32_t> listed = std::move(asked_.full);
  occluderOrFractional_.clear();
  std::set_union(fractional_.begin(), fractional_.end(), asked_.occluder.begin(), asked_.occluder.end(),
                 std::back_inserter(occluderOrFractional_));
  occluderListed_.clear();
  std::set_difference(occluderOrFractional_.begin(), occluderOrFractional_.end(), listed.begin(), listed.end(),
                      std::back_inserter(occluderListed_));
  const size_t fullCount = listed.size(), occluderCount = occluderListed_.size(), count = fullCount + occluderCount;
  const int attachments = resolveAttachments(method.filter);
  double readMs = msSince(t0);

  // ---- Pass 5: the evidence of the listed pixels ----
  double evidenceMs = 0;
  int compactWidth = kCompactWidth;
  if (count > 0) {
    const size_t bytes = count * sizeof(uint32_t);
    if (pixels_.size() < bytes) {
      pixels_ = vk::Buffer(context, std::max<size_t>(bytes, 2 * pixels_.size()), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT);
      in.writeDescriptors();
    }
    // One buffer: the full list, then the occluder's (the second draw starts at `first`), each
    // pixel as x | y << 16 (the shader then needs no integer division, which SIMD lanes lack).
    uint32_t* packed = static_cast<uint32_t*>(pixels_.mapped());
    packPixels(listed, uint32_t(width), packed);
    packPixels(occluderListed_, uint32_t(width), packed + fullCount);
    // kCompactWidth wide, wider when a list needs more rows than the device's largest image.
    const int maxSize = in.maxImageSize;
    const size_t longest = std::max(fullCount, occluderCount);
    while ((longest + size_t(compactWidth) - 1) / size_t(compactWidth) > size_t(maxSize)) compactWidth *= 2;
    auto rowsOf = [&](size_t k) { return int((k + size_t(compactWidth) - 1) / size_t(compactWidth)); };
    // A compact target of at least `rows` rows (made anew when short, at least twice as tall).
    auto ensureCompact = [&](vk::Image& image, VkFormat format, int rows) {
      if (image.height() >= rows && image.width() == compactWidth) return;
      const int allocRows = std::min(maxSize, std::max(rows, image.width() == compactWidth ? 2 * image.height() : 0));
      image = vk::Image();  // released first
      image = vk::Image(context, compactWidth, allocRows, 1, format, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT,
                        VK_IMAGE_ASPECT_COLOR_BIT, true);
    };
    if (fullCount > 0)
      for (int i = 0; i < attachments; ++i) ensureCompact(out_[i], kResolveFormats[i], rowsOf(fullCount));
    if (occluderCount > 0) ensureCompact(occluderOut_, kResolveFormats[0], rowsOf(occluderCount));
    const VkPipelineLayout layout = in.pc->layout;
    for (int run = 0; run < (pipes.firstUse ? 2 : 1); ++run) {
      VkCommandBuffer cmd = in.commands->begin();
      VkQueryPool pool = queries_.get();
      vkCmdResetQueryPool(cmd, pool, 0, 2);
      vkCmdWriteTimestamp2(cmd, VK_PIPELINE_STAGE_2_TOP_OF_PIPE_BIT, pool, 0);
      VkDescriptorSet set = in.set;
      vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, layout, 0, 1, &set, 0, nullptr);
      // One draw per list: `targets` images, `k` pixels from `first` on, through `pipeline`.
      auto drawList = [&](vk::Image* targets, int targetCount, size_t first, size_t k, VkPipeline pipeline) {
        VkRenderingAttachmentInfo colors[kResolveAttachments];
        for (int i = 0; i < targetCount; ++i) {
          vk::transition(cmd, targets[i], VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL,
                         VK_PIPELINE_STAGE_2_HOST_BIT, 0, VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
                         VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
          colors[i] = overwrittenColor(targets[i].layerView(0), VK_IMAGE_LAYOUT_GENERAL);
        }
        drawFullscreen(
            cmd, colors, uint32_t(targetCount), uint32_t(compactWidth), uint32_t(rowsOf(k)), pipeline,
            [&] {
              // count, the compact width, the list's start (resolve.frag's push block)
              DrawPush push{glm::mat4(1.0f), uint32_t(k), uint32_t(compactWidth), uint32_t(first), 0};
              vkCmdPushConstants(cmd, layout, VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT, 0,
                                 sizeof(push), &push);
            },
            pipes.firstUse && run == 0);
      };
      if (fullCount > 0) drawList(out_, attachments, 0, fullCount, pipes.evidence);
      if (occluderCount > 0) drawList(&occluderOut_, 1, fullCount, occluderCount, pipes.occluder);
      barrierToHost(cmd, VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
      vkCmdWriteTimestamp2(cmd, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, pool, 1);
      in.commands->submitAndWait();
    }
    uint64_t stamps[2] = {};
    VK_CHECK(vkGetQueryPoolResults(context.device(), queries_.get(), 0, 2, sizeof(stamps), stamps, sizeof(uint64_t),
                                   VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT));
    evidenceMs = double(stamps[1] - stamps[0]) * context.properties().limits.timestampPeriod * 1e-6;
    if (fullCount > 0)
      for (int i = 0; i < attachments; ++i) out_[i].invalidate(context);
    if (occluderCount > 0) occluderOut_.invalidate(context);
  }

  // ---- The frame: the full readback's channels, in its order ----
  auto t1 = std::chrono::steady_clock::now();
  const bool momentChannels = isMomentFilter(method.filter);
  Frame frame;
  frame.width = width;
  frame.height = height;
  frame.names = {"hit", "object_id", "prim_id"};
  const std::string p = "light." + light.name + ".";
  for (const char* name : {"vis", "receiver_depth", "map_depth", "m", "bias_depth", "bias_world", "occluder_id",
                           "occluder_prim", "in_map", "cascade"})
    frame.names.push_back(p + name);
  if (momentChannels)
    for (const char* name : {"moment_mean", "moment_variance", "moment_bound"}) frame.names.push_back(p + name);
  frame.data.resize(frame.names.size());
  // Planes: 0 hit, 1 object_id, 2 prim_id, 3 vis, 4 receiver_depth, 5 map_depth, 6 m, 7 bias_depth,
  // 8 bias_world, 9 occluder_id, 10 occluder_prim, 11 in_map, 12 cascade, 13.. the moments'.
  // The kept ones are lent to the frame, vis is the plane filled from the bytes above, the
  // evidence planes come zeroed from zeroSpare_ when a frame handed them back, the rest from spare.
  std::vector<float>* kept[13] = {&cameraPlanes_.hit, &cameraPlanes_.objectId, &cameraPlanes_.primId};
  kept[6] = &footprint.m;
  kept[12] = &footprint.cascade;
  if (!zeroSpare_.empty() && zeroSpare_.front().size() != n) zeroSpare_.clear();
  lent_ = Lent();
  lent_.footprintKey = footprint.key;
  std::vector<uint8_t> zeroed(frame.data.size(), 0);
  bool toFill = false;
  for (size_t c = 0; c < frame.data.size(); ++c) {
    std::vector<float>* from = c < 13 ? kept[c] : nullptr;
    if (from) {
      frame.data[c] = std::move(*from);
      from->clear();
      lent_.kept[c == 6 ? 3 : c == 12 ? 4 : c] = frame.data[c].data();
      continue;
    }
    if (c == 3) {
      frame.data[c] = std::move(visPlane);  // filled above
      lent_.vis = frame.data[c].data();
      continue;
    }
    std::vector<std::vector<float>>& pool = !zeroSpare_.empty() ? zeroSpare_ : spare;
    zeroed[c] = &pool == &zeroSpare_;
    toFill = toFill || !zeroed[c];
    if (!pool.empty()) {
      frame.data[c] = std::move(pool.back());
      pool.pop_back();
    }
  }
  spare.clear();
  auto fill = [&](size_t first, size_t step) {
    for (size_t c = first; c < frame.data.size(); c += step) {
      std::vector<float>& plane = frame.data[c];
      if ((c < 13 && kept[c]) || zeroed[c] || c == 3) continue;
      plane.assign(n, 0.0f);
    }
  };
  if (toFill) {  // evidence planes not handed back zeroed
    std::thread helper(fill, 1, 2);
    fill(0, 2);
    helper.join();
  }
  for (size_t c = 4; c < frame.data.size(); ++c)
    if (c != 6 && c != 12) lent_.zeroed.push_back(frame.data[c].data());
  const SceneGpu& scene = *in.scene;
  const std::vector<uint32_t>& objectIds = scene.objectIds;
  // The stencil ids hold the object index + 1 (the primitive stays unresolved: occluder_prim 0).
  const bool stencilIds = in.stencilIds;
  // The occluder's channels of a listed pixel from its id in the map (exact up to 2^24) and
  // 2 * cascade + in_map (the cascade is kept).
  auto putOccluder = [&](size_t i, float id, float cascadeInMap) {
    const uint32_t occluder = uint32_t(id);
    if (occluder != 0 && stencilIds) frame.data[9][i] = float(objectIds[occluder - 1]);
    else idsOf(scene, occluder, frame.data[9][i], frame.data[10][i]);
    frame.data[11][i] = float(int(cascadeInMap) & 1);
  };
  // Each listed pixel's channels into the planes: distinct pixels, so two threads take half a
  // list each where it is long (a row with acne everywhere lists a third of the frame).
  auto scatter = [&](size_t k0, size_t k1) {
    for (size_t k = k0; k < k1; ++k) {
      const size_t i = listed[k];
      const size_t y = k / size_t(compactWidth), x = k % size_t(compactWidth);
      const float* a = mappedRow<float>(out_[0], y) + 4 * x;
      const float* b = mappedRow<float>(out_[1], y) + 4 * x;
      frame.data[3][i] = a[0];
      frame.data[4][i] = a[1];
      frame.data[5][i] = a[2];
      frame.data[7][i] = b[0];
      frame.data[8][i] = b[1];
      putOccluder(i, b[2], b[3]);
      if (momentChannels) {
        const float* c = mappedRow<float>(out_[2], y) + 4 * x;
        for (int j = 0; j < 3; ++j) frame.data[size_t(13 + j)][i] = c[j];
      }
    }
  };
  auto scatterOccluder = [&](size_t k0, size_t k1) {
    for (size_t k = k0; k < k1; ++k) {
      const size_t i = occluderListed_[k];
      const float* a = mappedRow<float>(occluderOut_, k / size_t(compactWidth)) + 4 * (k % size_t(compactWidth));
      frame.data[3][i] = a[0];
      putOccluder(i, a[1], a[2]);
    }
  };
  if (fullCount >= kParallelScatter) inTwoHalves(fullCount, scatter);
  else scatter(0, fullCount);
  if (occluderCount >= kParallelScatter) inTwoHalves(occluderCount, scatterOccluder);
  else scatterOccluder(0, occluderCount);
  // Both lists: recycle() sets these pixels of the planes back.
  listed.insert(listed.end(), occluderListed_.begin(), occluderListed_.end());
  lent_.listed = std::move(listed);
  t.evidenceGpuMs = evidenceMs;
  t.evidencePixels = count;
  t.partialEvidence = true;
  t.readbackMs = readMs + msSince(t1);
  return frame;
}

void EvidencePass::recycle(Frame&& frame, std::vector<std::vector<float>>& spare) {
  const size_t n = frame.pixelCount();
  Footprint* footprint = nullptr;
  for (Footprint& f : footprints_)
    if (f.key == lent_.footprintKey) footprint = &f;
  std::vector<float>* home[5] = {&cameraPlanes_.hit, &cameraPlanes_.objectId, &cameraPlanes_.primId,
                                 footprint ? &footprint->m : nullptr, footprint ? &footprint->cascade : nullptr};
  for (std::vector<float>& plane : frame.data) {
    if (plane.size() != n || n == 0) continue;
    const float* data = plane.data();
    bool back = false;
    for (int k = 0; k < 5 && !back; ++k)
      if (data == lent_.kept[k] && home[k] && home[k]->empty()) {
        *home[k] = std::move(plane);  // the kept plane, lent to this frame
        lent_.kept[k] = nullptr;
        back = true;
      }
    if (back) continue;
    if (data == lent_.vis && visKept_.plane.empty() && visKept_.bytes.size() == n) {
      for (uint32_t i : lent_.listed) plane[i] = visKept_.bytes[i] == 255 ? 1.0f : 0.0f;  // the evidence's floats
      visKept_.plane = std::move(plane);
      lent_.vis = nullptr;
      continue;
    }
    if (std::find(lent_.zeroed.begin(), lent_.zeroed.end(), data) != lent_.zeroed.end() && zeroSpare_.size() < 16) {
      for (uint32_t i : lent_.listed) plane[i] = 0.0f;  // the only non-zero values
      zeroSpare_.push_back(std::move(plane));
    } else {
      spare.push_back(std::move(plane));
    }
  }
  lent_.zeroed.clear();
  frame = Frame();
}

}  // namespace shadowlab::raster
