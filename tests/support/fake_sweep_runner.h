#pragma once
// A SweepRunner without a renderer, for the tests of the sweep loop (resume, shards, merge): its
// metrics are a known function of the scene and the method, so a row can be checked against its
// configuration, and it counts what it ran.
#include <atomic>
#include <map>
#include <string>

#include "shadowlab/compare/sweep.h"

namespace shadowlab::testing {

// error_rate of a configuration: 1 / map.size + 0.001 * bias.slope, plus 0.5 on the contact scene
// (so two scenes' rows of one configuration differ).
inline double fakeErrorRate(const std::string& scene, const Method& m) {
  return 1.0 / m.mapSize + 0.001 * m.biasSlope + (scene == "contact" ? 0.5 : 0.0);
}

class FakeSweepRunner : public SweepRunner {
 public:
  std::map<std::string, int> runs;  // "scene|map.size|bias.slope|light" -> times run
  int total = 0;                    // runs in all
  // When set: stopAfter becomes true during run number stopAfterRuns, as if Ctrl-C came then.
  std::atomic<bool>* stopAfter = nullptr;
  int stopAfterRuns = -1;
  std::string device;  // what deviceName() reports

  SweepRunOutput run(const Scene& scene, const Method& m, const std::string& light, const std::string&) override {
    ++runs[scene.name + "|" + std::to_string(m.mapSize) + "|" + std::to_string(m.biasSlope) + "|" + light];
    ++total;
    if (stopAfter && total == stopAfterRuns) stopAfter->store(true);
    SweepRunOutput out;
    out.metrics = {{"error_rate", fakeErrorRate(scene.name, m)},
                   {"acne_rate", 0.0},
                   {"leak_rate", 0.001 * m.biasSlope},
                   {"aliasing_rate", 1.0 / m.mapSize},
                   {"coverage_rate", 0.0},
                   {"m_median", 1.0},
                   {"m_p95", 2.0},
                   {"m_max", 3.0}};
    out.timings = {
        {"shadow_gpu_ms", m.mapSize / 100.0}, {"camera_gpu_ms", 1.0}, {"readback_ms", 0.5}, {"compare_ms", 0.25}};
    return out;
  }
  // When set: timeAgain() answers as a renderer would (each run 0.9 of the row's time, and its
  // first 0.1 ms more) and counts its calls per configuration, as `runs` does.
  bool timesAgain = false;
  std::map<std::string, int> retimes;
  std::vector<MethodSample> timeAgain(const Scene& scene, const Method& m, const std::string& light,
                                      int runs) override {
    if (!timesAgain || runs < 1) return {};
    ++retimes[scene.name + "|" + std::to_string(m.mapSize) + "|" + std::to_string(m.biasSlope) + "|" + light];
    std::vector<MethodSample> out(size_t(runs), MethodSample{0.9 * m.mapSize / 100.0, 0, 0});
    out[0].shadowGpuMs += 0.1;
    return out;
  }
  bool writeTriptych(const Scene&, const Method&, const std::string&, const std::string&) override { return false; }
  std::string deviceName() override { return device; }
};

}  // namespace shadowlab::testing
