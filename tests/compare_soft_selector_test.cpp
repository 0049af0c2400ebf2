// Evidence on demand under a sized light (compare/METRICS.md "Soft shadows"), without a renderer:
// a raster frame made partial as the rasterizer makes it (every evidence channel zero but at the
// pixels the selector lists; the map texel's evidence, in_map and occluder_id, also at every
// fractional pixel) must give the full frame's metrics bit for bit. Under a soft truth an error may
// lie where the decisions agree (a raster 1 over a truth of 0.5): disagreementSelector lists those
// too, or their in_map of 0 would read as coverage.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "shadowlab/compare/classify.h"
#include "shadowlab/compare/compare.h"
#include "shadowlab/compare/run_pipeline.h"
#include "shadowlab/raster/raster.h"

namespace compare_soft_selector_test {

using namespace shadowlab;

namespace {

constexpr float kPlane = 1, kCaster = 2;

// The lookup pass's byte (raster/shaders/resolve.frag): 0 and 255 only for 0 and 1 exactly, the
// decision kept (128..255 exactly where vis >= 0.5).
uint8_t lookupByte(float v) {
  v = clampVisibility(v);
  if (v > 0.0f && v < 1.0f)
    v = v >= 0.5f ? std::clamp(v, 128.0f / 255, 254.0f / 255) : std::clamp(v, 1.0f / 255, 127.0f / 255);
  return uint8_t(std::lround(v * 255.0f));
}

Frame frame(int w, int h) {
  Frame f;
  f.width = w;
  f.height = h;
  f.meta["lights"] = {"sun"};
  for (const char* c : {"hit", "object_id", "light.sun.vis"}) f.add(c, 0.0f);
  return f;
}

const char* const kEvidence[] = {"in_map", "occluder_id", "receiver_depth", "map_depth", "bias_depth", "bias_world"};

// The partial frame the rasterizer would return for `full` with this selector.
Frame partial(const Frame& full, const EvidenceSelector& select) {
  const size_t n = full.pixelCount();
  std::vector<uint8_t> bytes(n);
  const std::vector<float>& vis = full.get("light.sun.vis");
  for (size_t i = 0; i < n; ++i) bytes[i] = lookupByte(vis[i]);
  EvidenceRequest request;
  select(bytes.data(), full.width, full.height, request);
  std::vector<uint8_t> level(n, 0);  // 2 every channel, 1 the map texel's
  for (uint32_t i : request.occluder) level[i] = std::max<uint8_t>(level[i], 1);
  for (size_t i = 0; i < n; ++i)
    if (bytes[i] != 0 && bytes[i] != 255) level[i] = std::max<uint8_t>(level[i], 1);
  for (uint32_t i : request.full) level[i] = 2;
  Frame out = full;
  for (const char* c : kEvidence) {
    std::vector<float>& plane = out.get(std::string("light.sun.") + c);
    const bool texel = std::string(c) == "in_map" || std::string(c) == "occluder_id";
    for (size_t i = 0; i < n; ++i)
      if (level[i] < (texel ? 1 : 2)) plane[i] = 0.0f;
  }
  return out;
}

TEST(SoftSelector, PartialFramesGiveTheFullFramesMetrics) {
  const int w = 80, h = 60;
  Frame reference = frame(w, h), raster = frame(w, h);
  reference.add("light.sun.vis_sigma");
  reference.add("light.sun.occluder_dist", -1.0f);
  // After the last add: add() may move every plane.
  std::vector<float>& sigma = reference.get("light.sun.vis_sigma");
  for (const char* c : kEvidence) raster.add(std::string("light.sun.") + c);
  raster.add("light.sun.m", 2.0f);
  std::mt19937 rng(9);
  auto u = [&] { return float(rng() % 100000) / 100000.0f; };
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const size_t i = size_t(y) * w + x;
      // A soft edge across x = 40, 16 pixels wide, sigma up to 0.05 inside it.
      const float truth = std::clamp((float(x) - 32.0f) / 16.0f, 0.0f, 1.0f);
      for (Frame* f : {&reference, &raster}) {
        f->get("hit")[i] = 1;
        f->get("object_id")[i] = kPlane;
      }
      reference.get("light.sun.vis")[i] = truth;
      sigma[i] = truth > 0 && truth < 1 ? 0.05f * u() : 0.0f;
      reference.get("light.sun.occluder_dist")[i] = truth < 1 ? 0.02f : -1.0f;
      raster.get("light.sun.in_map")[i] = x < 2 ? 0.0f : 1.0f;
      raster.get("light.sun.occluder_id")[i] = (x + y) % 4 == 0 ? kPlane : kCaster;
      raster.get("light.sun.receiver_depth")[i] = 0.5f;
      raster.get("light.sun.map_depth")[i] = 0.4995f;
      raster.get("light.sun.bias_depth")[i] = 0.001f;
      raster.get("light.sun.bias_world")[i] = 0.05f;
    }
  uint64_t agreeingHardRaster = 0;
  const EvidenceSelector select = disagreementSelector(reference, "sun");
  ASSERT_TRUE(bool(select));
  for (unsigned config = 0; config < 4; ++config) {
    Frame ras = raster;
    std::vector<float>& v = ras.get("light.sun.vis");
    const std::vector<float>& r = reference.get("light.sun.vis");
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const size_t i = size_t(y) * w + x;
        // The hard edge of a plain map, shifted per row and configuration; a blurred one; noise.
        const float edge = 36.0f + float((y * 3 + int(config) * 5) % 9);
        if (config == 0) v[i] = x >= edge ? 1.0f : 0.0f;
        else if (config == 1) v[i] = std::clamp((float(x) - edge) / 30.0f + 0.5f, 0.0f, 1.0f);
        else if (config == 2) v[i] = std::clamp(r[i] + (u() - 0.5f) * 0.6f, 0.0f, 1.0f);
        else v[i] = u() < 0.5f ? std::round(r[i] + (u() - 0.5f) * 0.5f) : r[i];
      }
    Classification full, fromPartial;
    const Metrics a = compareFrames(reference, ras, {}, &full);
    const Metrics b = compareFrames(reference, partial(ras, select), {}, &fromPartial);
    EXPECT_EQ(a.toJson().dump(), b.toJson().dump()) << config;
    EXPECT_TRUE(full.classes == fromPartial.classes) << config;
    EXPECT_GT(a.errors, 0u) << config;
    for (size_t i = 0; i < v.size(); ++i)
      agreeingHardRaster +=
          isErrorClass(full.classes[i]) && (v[i] == 0.0f || v[i] == 1.0f) && litDecision(r[i]) == litDecision(v[i]);
  }
  // Errors where the decisions agree and the raster is 0 or 1 (a byte the rasterizer does not list
  // by itself): the soft rule's own pixels.
  EXPECT_GT(agreeingHardRaster, 50u);
}

}  // namespace

}  // namespace compare_soft_selector_test
