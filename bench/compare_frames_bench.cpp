// compareFrames at 1920x1080 (goal: <= 20 ms on the 2-core machine; a memory-bound pass).
// Synthetic frames with every channel the renderers write: a plane with a disk-shaped reference
// shadow; the raster's shadow is the same disk sampled on a coarse "map" grid (jagged edges:
// aliasing candidates for the distance transform) plus acne stripes in part of the lit area.
//   ./compare_frames_bench --benchmark_min_time=1
#include <cmath>
#include <filesystem>

#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include "shadowlab/compare/compare.h"
#include "shadowlab/raster/raster.h"
#include "shadowlab/reference/reference.h"
#include "shadowlab/scenes/frame.h"
#include "shadowlab/scenes/loader.h"

namespace {

using shadowlab::Frame;

struct Pair {
  Frame reference, raster;
};

Pair makeFrames(int width, int height, float texelPx) {
  Pair p;
  for (Frame* f : {&p.reference, &p.raster}) {
    f->width = width;
    f->height = height;
    f->meta["scene_hash"] = "0123456789abcdef";
    f->meta["lights"] = {"sun"};
    for (const char* c : {"hit", "object_id", "prim_id", "light.sun.vis"}) f->add(c, 0.0f);
  }
  p.raster.meta["light"] = "sun";
  for (const char* c : {"P.x", "P.y", "P.z", "N.x", "N.y", "N.z", "light.sun.occluder_dist"}) p.reference.add(c, 0.0f);
  for (const char* c :
       {"receiver_depth", "map_depth", "occluder_id", "occluder_prim", "in_map", "m", "bias_depth", "bias_world"})
    p.raster.add(std::string("light.sun.") + c, 0.0f);
  const float cx = width * 0.5f, cy = height * 0.55f, radius = height * 0.3f;
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const size_t i = size_t(y) * width + x;
      const bool sky = y < height / 8;  // top rows: background
      const bool refShadow = std::hypot(x + 0.5f - cx, y + 0.5f - cy) < radius;
      // The raster decides at the center of its coarse texel.
      const float tx = (std::floor((x + 0.5f) / texelPx) + 0.5f) * texelPx;
      const float ty = (std::floor((y + 0.5f) / texelPx) + 0.5f) * texelPx;
      bool rasShadow = std::hypot(tx - cx, ty - cy) < radius;
      const bool acne = !rasShadow && x < width / 4 && (y % 9) < 3;
      rasShadow = rasShadow || acne;
      for (Frame* f : {&p.reference, &p.raster}) {
        f->get("hit")[i] = sky ? 0.0f : 1.0f;
        f->get("object_id")[i] = sky ? 0.0f : 1.0f;
        f->get("prim_id")[i] = sky ? 0.0f : float(x & 1);
      }
      if (sky) continue;
      p.reference.get("light.sun.vis")[i] = refShadow ? 0.0f : 1.0f;
      p.raster.get("light.sun.vis")[i] = rasShadow ? 0.0f : 1.0f;
      p.reference.get("light.sun.occluder_dist")[i] = refShadow ? 2.0f : -1.0f;
      p.raster.get("light.sun.receiver_depth")[i] = 0.6f;
      p.raster.get("light.sun.map_depth")[i] = rasShadow && !acne ? 0.3f : 0.5999f;
      p.raster.get("light.sun.occluder_id")[i] = rasShadow && !acne ? 2.0f : 1.0f;
      p.raster.get("light.sun.in_map")[i] = x < width - 16 ? 1.0f : 0.0f;
      p.raster.get("light.sun.m")[i] = texelPx * (0.5f + float(y) / height);
      p.raster.get("light.sun.bias_depth")[i] = 0.0005f;
      p.raster.get("light.sun.bias_world")[i] = 0.01f;
    }
  }
  return p;
}

void BM_CompareFrames(benchmark::State& state) {
  const int width = int(state.range(0)), height = int(state.range(1));
  const float texelPx = float(state.range(2));
  const Pair p = makeFrames(width, height, texelPx);
  shadowlab::Classification c;
  shadowlab::Metrics m;
  for (auto _ : state) {
    m = shadowlab::compareFrames(p.reference, p.raster, {}, &c);
    benchmark::DoNotOptimize(m);
  }
  state.counters["pixels"] = double(m.pixelsCompared);
  state.counters["error_rate"] = m.errorRate;
  state.counters["aliasing"] = double(m.count(shadowlab::PixelClass::Aliasing));
  state.counters["acne"] = double(m.count(shadowlab::PixelClass::Acne));
  state.counters["Mpix/s"] =
      benchmark::Counter(double(width) * height * state.iterations() * 1e-6, benchmark::Counter::kIsRate);
}
// 1080p with a fine map (2 px per texel) and a very coarse one (32 px per texel, like a 32^2 map).
BENCHMARK(BM_CompareFrames)
    ->Args({1920, 1080, 2})
    ->Args({1920, 1080, 32})
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime()
    ->UseRealTime();

// The same on one thread: the work itself, independent of how busy the other core is.
void BM_CompareFramesOneThread(benchmark::State& state) {
  tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
  BM_CompareFrames(state);
}
BENCHMARK(BM_CompareFramesOneThread)->Args({1920, 1080, 2})->Args({1920, 1080, 32})->Unit(benchmark::kMillisecond);

// compareFrames through a CompareContext (compare.h) made once from the same pair, as a sweep
// keeps one per evidence group: per frame only the raster vis and the disagreeing pixels'
// evidence are read. Checks the metrics equal compareFrames' before timing.
void BM_CompareFramesContext(benchmark::State& state) {
  const int width = int(state.range(0)), height = int(state.range(1));
  const float texelPx = float(state.range(2));
  Pair p = makeFrames(width, height, texelPx);
  p.raster.meta["evidence_group"] = "bench";
  const shadowlab::CompareContext context(p.reference, p.raster);
  if (!context.appliesTo(p.reference, p.raster) || shadowlab::compareFrames(context, p.reference, p.raster).toJson() !=
                                                       shadowlab::compareFrames(p.reference, p.raster).toJson()) {
    state.SkipWithError("the context does not apply, or gives other metrics");
    return;
  }
  shadowlab::Metrics m;
  for (auto _ : state) {
    m = shadowlab::compareFrames(context, p.reference, p.raster);
    benchmark::DoNotOptimize(m);
  }
  state.counters["pixels"] = double(m.pixelsCompared);
  state.counters["Mpix/s"] =
      benchmark::Counter(double(width) * height * state.iterations() * 1e-6, benchmark::Counter::kIsRate);
}
BENCHMARK(BM_CompareFramesContext)
    ->Args({1920, 1080, 2})
    ->Args({1920, 1080, 32})
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime()
    ->UseRealTime();

void BM_CompareFramesContextOneThread(benchmark::State& state) {
  tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
  BM_CompareFramesContext(state);
}
BENCHMARK(BM_CompareFramesContextOneThread)
    ->Args({1920, 1080, 2})
    ->Args({1920, 1080, 32})
    ->Unit(benchmark::kMillisecond);

// Real frames: the bundled bunny scene rendered at 1920x1080 by both renderers (2048^2 map),
// once, then compared repeatedly. Skipped when there is no Vulkan device.
void BM_CompareBunny1080p(benchmark::State& state) {
  static Pair frames;
  static std::string error;
  if (frames.reference.width == 0 && error.empty()) {
    try {
      const shadowlab::Scene scene = shadowlab::loadScene(shadowlab::resolveScenePath("bunny"),
                                                          {{"/camera/width", 1920}, {"/camera/height", 1080}});
      frames.reference = shadowlab::renderReference(scene, {});
      shadowlab::Rasterizer rasterizer;
      frames.raster = rasterizer.render(scene, shadowlab::Method{});
    } catch (const std::exception& e) {
      error = e.what();
    }
  }
  if (!error.empty()) {
    state.SkipWithError(error.c_str());
    return;
  }
  shadowlab::Classification c;
  shadowlab::Metrics m;
  for (auto _ : state) {
    m = shadowlab::compareFrames(frames.reference, frames.raster, {}, &c);
    benchmark::DoNotOptimize(m);
  }
  state.counters["pixels"] = double(m.pixelsCompared);
  state.counters["errors"] = double(m.errors);
}
BENCHMARK(BM_CompareBunny1080p)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();

void BM_ErrorsPicture(benchmark::State& state) {
  const Pair p = makeFrames(1920, 1080, 8);
  shadowlab::Classification c;
  shadowlab::compareFrames(p.reference, p.raster, {}, &c);
  for (auto _ : state) {
    int w = 0, h = 0;
    auto rgb = shadowlab::errorsPicture(c, &w, &h);
    benchmark::DoNotOptimize(rgb);
  }
}
BENCHMARK(BM_ErrorsPicture)->Unit(benchmark::kMillisecond)->UseRealTime();

// The errors picture's PNG written with libpng's adaptive row filters (arg 0, every PNG before
// PngRows existed) and without (arg 1, what errors.png and the triptychs use now): the same
// pixels, side by side. The file sizes are reported as counters.
void BM_ErrorsPng(benchmark::State& state) {
  const Pair p = makeFrames(1920, 1080, 8);
  shadowlab::Classification c;
  shadowlab::compareFrames(p.reference, p.raster, {}, &c);
  int w = 0, h = 0;
  const std::vector<uint8_t> rgb = shadowlab::errorsPicture(c, &w, &h);
  const auto rows = state.range(0) ? shadowlab::PngRows::Unfiltered : shadowlab::PngRows::Adaptive;
  const std::string path = "/tmp/shadowlab_bench_errors_" + std::to_string(state.range(0)) + ".png";
  for (auto _ : state) shadowlab::writeRgbPng(path, w, h, rgb, rows);
  state.counters["bytes"] = double(std::filesystem::file_size(path));
  std::filesystem::remove(path);
}
BENCHMARK(BM_ErrorsPng)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();

// A whole 1080p triptych as the sweep report writes it (three panels, legend, PNG).
void BM_TriptychPng(benchmark::State& state) {
  const Pair p = makeFrames(1920, 1080, 8);
  shadowlab::Classification c;
  shadowlab::compareFrames(p.reference, p.raster, {}, &c);
  const std::string path = "/tmp/shadowlab_bench_triptych.png";
  for (auto _ : state) shadowlab::writeTriptychPng(path, p.reference, p.raster, c);
  state.counters["bytes"] = double(std::filesystem::file_size(path));
  std::filesystem::remove(path);
}
BENCHMARK(BM_TriptychPng)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
