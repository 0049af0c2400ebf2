// The deterministic method cost model (method_cost.h). The coefficients were fit once to measured
// lavapipe GPU timestamps on the 2-core VM (compare/TUNE.md, "The cost model", has the data):
// they put the estimate on a millisecond scale, but only the ranking matters to tune.
#include "shadowlab/compare/method_cost.h"

namespace shadowlab {
namespace {

// Shadow pass (depth only, as an engine draws it): per texel written (clear + fill, whatever the
// geometry covers) and per triangle drawn, per layer. Fit on shadow_gpu_ms of grazing, contact and
// thin_wall at map.size 1024..4096 (1.2-2.5 ms at 1024^2, 26-57 ms at 4096^2: ~1.5-2 ns a texel)
// and bunny / four bunnies (28k / 111k triangles) at 2048^2 (11.1 / 27 ms: ~0.19 us a triangle).
constexpr double kNsPerTexel = 1.5;
constexpr double kNsPerTriangle = 190.0;
// Lookup pass: one comparison per camera pixel in a bare forward pass (bench/raster_bare_bench:
// 21 ms at 1920x1080, ~10 ns a pixel), plus each filter's extra taps: textureGather-ed texels
// (bilinear4, pcf) ~1.9 ns each (pcf 3x3 .. 11x11 at 960x540: ~1.0 ms per extra texel), Poisson
// taps (one fetch each) ~5.8 ns (poisson 4 .. 64 taps: ~3.0 ms per tap). hw2x2 is one hardware
// fetch, measured as fast as `none`.
constexpr double kNsPerPixel = 10.0;
constexpr double kNsPerGatherTexel = 1.9;
constexpr double kNsPerPoissonTap = 5.8;
// Filterable maps (vsm, evsm2 with 2 moments; evsm4, msm with 4): a moments pass over every texel
// of every layer, then the separable Gaussian (2 passes of 2 * filter.blur + 1 taps). One
// calibration point, bench/raster_passes_bench on the loaded VM (bunny, 1080p, map 2048, blur 2):
// shadow pass 27 ms for none, 355 for vsm, 492 for msm, i.e. ~78 / ~111 ns a texel at 10 blur
// taps; split as a per-texel base plus a per-tap cost. The lookup reads one bilinear moments texel.
constexpr double kNsPerMomentTexel2 = 30.0, kNsPerBlurTap2 = 4.8;
constexpr double kNsPerMomentTexel4 = 45.0, kNsPerBlurTap4 = 6.6;

double bytesPerTexel(DepthFormat f) { return f == DepthFormat::D16 ? 2.0 : 4.0; }

}  // namespace

nlohmann::json MethodCost::toJson() const {
  return {{"estimated_ms", estimatedMs},    {"shadow_ms", shadowMs}, {"lookup_ms", lookupMs},
          {"map_bytes", mapBytes},          {"layers", layers},      {"texels_written", texelsWritten},
          {"taps_per_pixel", tapsPerPixel}, {"pixels", pixels}};
}

MethodCost estimateMethodCost(const Scene& scene, const Method& method, const std::string& lightName) {
  MethodCost c;
  if (!method.renderer.empty()) return c;  // an outside renderer's cost is its measured renderer_frame_ms
  const Light* light = scene.findLight(scene.lightOrDefault(lightName));
  int layers = 1;
  if (light) {
    if (light->type == LightType::Point) layers = 6;
    else if (light->type == LightType::Directional && isCascadedFit(method.fit)) layers = method.cascadeCount;
  }
  layers += int(scene.projectors.size());  // each projector's depth map
  double triangles = 0;
  for (const auto& o : scene.objects)
    if (o.castsShadow) triangles += double(o.triangles.size());
  const double texels = double(method.mapSize) * double(method.mapSize);
  c.layers = layers;
  c.texelsWritten = texels * layers;
  c.mapBytes = c.texelsWritten * bytesPerTexel(method.mapFormat);
  c.shadowMs = layers * (texels * kNsPerTexel + triangles * kNsPerTriangle) * 1e-6;
  int moments = 0;
  switch (effectiveFilter(method)) {  // a technique file's moments line: that map's moments pass
    case Filter::Vsm:
    case Filter::Evsm2: moments = 2; break;
    case Filter::Evsm4:
    case Filter::Msm: moments = 4; break;
    default: break;
  }
  if (moments > 0) {
    const double blurTaps = method.filterBlur > 0 ? 2.0 * (2 * method.filterBlur + 1) : 0.0;
    const double perTexel = moments == 2 ? kNsPerMomentTexel2 + blurTaps * kNsPerBlurTap2
                                         : kNsPerMomentTexel4 + blurTaps * kNsPerBlurTap4;
    c.shadowMs += c.texelsWritten * perTexel * 1e-6;
    c.mapBytes += c.texelsWritten * 4.0 * moments;  // RG32F / RGBA32F moments
  }

  double taps = 1, extraNs = 0;
  switch (method.filter) {
    case Filter::None:
    case Filter::Hw2x2: break;
    case Filter::Bilinear4:
      taps = 4;
      extraNs = 4 * kNsPerGatherTexel;
      break;
    case Filter::Pcf:
      taps = double(method.filterSize) * method.filterSize;
      extraNs = taps * kNsPerGatherTexel;
      break;
    case Filter::Poisson:
      taps = method.filterTaps;
      extraNs = taps * kNsPerPoissonTap;
      break;
    case Filter::Pcss:
      // The blocker search and the PCF, one fetch per Poisson tap each (every pixel pays for the
      // search; the PCF only where blockers were found, counted in full: the SIMD lanes run it).
      taps = double(method.pcssBlockerTaps) + method.pcssFilterTaps;
      extraNs = taps * kNsPerPoissonTap;
      break;
    case Filter::Dpcf:
      taps = method.dpcfTaps;  // one kernel: the search's taps are the filter's
      extraNs = taps * kNsPerPoissonTap;
      break;
    case Filter::Vsm:
    case Filter::Evsm2:
    case Filter::Evsm4:
    case Filter::Msm:
      taps = 1;  // one bilinear fetch of the (pre-filtered) moments
      extraNs = 4 * kNsPerGatherTexel;
      break;
  }
  c.tapsPerPixel = taps;
  c.pixels = double(scene.camera.width) * double(scene.camera.height);
  c.lookupMs = c.pixels * (kNsPerPixel + extraNs) * 1e-6;
  c.estimatedMs = c.shadowMs + c.lookupMs;
  return c;
}

}  // namespace shadowlab
