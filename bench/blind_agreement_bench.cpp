// How good the blind classes are (compare/METRICS.md "Frames from other renderers"): every
// configuration of a sweep file (default: the main job's, compare/report/default_sweep.json) on
// every scene it runs on, rastered by shadowlab, classified with all its evidence and as a frame
// from another renderer would come (its vis alone, with the light layers and map size declared),
// and the wrong pixels counted by both classes. Prints the confusion matrix (Markdown), the share
// on the diagonal and the worst confused pair; with --per-scene one line per scene too.
//
//   build/bench/blind_agreement_bench [--sweep FILE] [--scale S] [--scenes a,b] [--per-scene]
//
// --scale multiplies each scene's camera size (default 0.5: 480x270 for the 960x540 scenes).
// Not a Google Benchmark: it measures agreement, not time.
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <set>
#include <sstream>
#include <string>

#include "shadowlab/compare/blind_agreement.h"
#include "shadowlab/compare/sweep.h"
#include "shadowlab/raster/raster.h"
#include "shadowlab/reference/reference.h"
#include "shadowlab/scenes/error.h"

using namespace shadowlab;

int main(int argc, char** argv) {
  std::string sweepFile = std::string(SHADOWLAB_SOURCE_DIR) + "/compare/report/default_sweep.json";
  double scale = 0.5;
  bool perScene = false;
  std::set<std::string> only;
  for (int a = 1; a < argc; ++a) {
    const std::string arg = argv[a];
    if (arg == "--sweep" && a + 1 < argc) {
      sweepFile = argv[++a];
    } else if (arg == "--scale" && a + 1 < argc) {
      scale = std::atof(argv[++a]);
    } else if (arg == "--scenes" && a + 1 < argc) {
      std::stringstream ss(argv[++a]);
      for (std::string s; std::getline(ss, s, ',');) only.insert(s);
    } else if (arg == "--per-scene") {
      perScene = true;
    } else {
      std::fprintf(stderr, "usage: %s [--sweep FILE] [--scale S] [--scenes a,b] [--per-scene]\n", argv[0]);
      return 2;
    }
  }
  if (!(scale > 0.0 && scale <= 4.0)) {
    std::fprintf(stderr, "--scale: expected 0 < S <= 4\n");
    return 2;
  }
  try {
    SweepSpec spec;
    loadSweepFile(sweepFile, spec);
    const SweepPlan plan = planSweep(spec);
    Rasterizer rasterizer;
    ClassConfusion total;
    std::map<std::string, ClassConfusion> byScene;
    std::map<std::string, ClassConfusion> byFilter;
    size_t lastVariant = size_t(-1);
    std::string lastLight;
    Scene scene;
    Frame truth;
    int rows = 0;
    for (const SweepJob& job : plan.jobs) {
      if (!only.empty() && !only.count(job.sceneName)) continue;
      if (job.variantIndex != lastVariant || job.light != lastLight) {
        scene = plan.variants[job.variantIndex];
        scene.camera.width = std::max(1, int(scene.camera.width * scale + 0.5));
        scene.camera.height = std::max(1, int(scene.camera.height * scale + 0.5));
        ReferenceOptions ro;
        ro.channels = ReferenceChannels::All;
        ro.spp = spec.spp;
        ro.lightSamples = spec.lightSamples;
        truth = renderReference(scene, ro);
        lastVariant = job.variantIndex;
        lastLight = job.light;
      }
      const Method& method = plan.configs[job.configIndex].method;
      const Frame raster = rasterizer.render(scene, method, job.light);
      CompareOptions options;
      options.light = job.light;
      ClassConfusion one;
      addBlindAgreement(truth, raster, declaredByRaster(rasterizer, method), one, options);
      total.add(one);
      byScene[job.sceneName].add(one);
      byFilter[toString(method.filter)].add(one);
      ++rows;
    }
    auto share = [](const ClassConfusion& c) {
      return c.wrong() ? 100.0 * double(c.agreeing()) / double(c.wrong()) : 100.0;
    };
    std::printf("%d rows, %llu wrong pixels, %.1f %% the same class\n\n", rows, (unsigned long long)total.wrong(),
                share(total));
    std::printf("%s\n", total.markdown().c_str());
    PixelClass f = PixelClass::Other, b = PixelClass::Other;
    const double worst = total.worstConfusion(&f, &b);
    std::printf("worst: %s read as %s on %.1f %% of its pixels\n", classInfo(f).key, classInfo(b).key, 100.0 * worst);
    if (perScene) {
      std::printf("\n");
      for (const auto& [name, c] : byScene) {
        std::printf("%-22s %9llu wrong  %5.1f %% same  worst %.1f %%\n", name.c_str(), (unsigned long long)c.wrong(),
                    share(c), 100.0 * c.worstConfusion());
      }
      for (const auto& [name, c] : byFilter) {
        std::printf("filter %-15s %9llu wrong  %5.1f %% same  worst %.1f %%\n", name.c_str(),
                    (unsigned long long)c.wrong(), share(c), 100.0 * c.worstConfusion());
      }
      for (const auto& [name, c] : byScene) std::printf("\n%s\n%s", name.c_str(), c.markdown().c_str());
      for (const auto& [name, c] : byFilter) std::printf("\nfilter %s\n%s", name.c_str(), c.markdown().c_str());
    }
    return 0;
  } catch (const InputError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 2;
  }
}
