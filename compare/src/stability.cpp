// Temporal stability: camera paths and the shimmer / per-frame error metrics (stability.h).
#include "shadowlab/compare/stability.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "shadowlab/scenes/error.h"

namespace shadowlab {

namespace {

const float* plane(const Frame& f, const std::string& name, const char* which) {
  if (!f.has(name))
    throw InputError(std::string("stability: error: the ") + which + " frame has no channel " + name);
  const std::vector<float>& p = f.get(name);
  if (p.size() != f.pixelCount())
    throw InputError(std::string("stability: error: channel ") + name + " of the " + which +
                     " frame has the wrong size");
  return p.data();
}

}  // namespace

double decisionFlipRate(const Frame& reference, const Frame& rasterA, const Frame& rasterB,
                        const std::string& light, uint64_t* pixelsCompared) {
  if (reference.width != rasterA.width || reference.height != rasterA.height || rasterA.width != rasterB.width ||
      rasterA.height != rasterB.height)
    throw InputError("stability: error: frame sizes differ; expected every frame from the same camera");
  const std::string vis = "light." + light + ".vis";
  const float* refHit = plane(reference, "hit", "reference");
  const float* refObj = plane(reference, "object_id", "reference");
  const float* aHit = plane(rasterA, "hit", "raster");
  const float* aObj = plane(rasterA, "object_id", "raster");
  const float* aVis = plane(rasterA, vis, "raster");
  const float* bHit = plane(rasterB, "hit", "raster");
  const float* bObj = plane(rasterB, "object_id", "raster");
  const float* bVis = plane(rasterB, vis, "raster");
  uint64_t compared = 0, flips = 0;
  for (size_t i = 0, n = reference.pixelCount(); i < n; ++i) {
    // Compared as in compareFrames, in both frames: the same surface in all three.
    if (!(refHit[i] >= 0.5f && aHit[i] >= 0.5f && bHit[i] >= 0.5f)) continue;
    if (refObj[i] != aObj[i] || refObj[i] != bObj[i]) continue;
    ++compared;
    // The same decision threshold as compare (vis >= 0.5 is lit); NaN counts as shadowed in both.
    if ((aVis[i] >= 0.5f) != (bVis[i] >= 0.5f)) ++flips;
  }
  if (pixelsCompared) *pixelsCompared = compared;
  return compared ? double(flips) / double(compared) : 0.0;  // no pixel: nothing flipped, no NaN
}

StabilityStream::StabilityStream(const Frame& reference, CompareOptions options)
    : reference_(reference), options_(std::move(options)) {}

Frame StabilityStream::add(Frame raster) {
  if (frames_ == 0) light_ = resolveCompareLight(reference_, raster, options_);
  if (frames_ > 0) {
    uint64_t px = 0;
    metrics_.flipRatePerPair.push_back(decisionFlipRate(reference_, previous_, raster, light_, &px));
    metrics_.pixelsComparedPerPair.push_back(px);
  }
  errors_.push_back(compareFrames(reference_, raster, options_).errorRate);
  ++frames_;
  std::swap(previous_, raster);
  return raster;
}

StabilityMetrics StabilityStream::result() const {
  if (frames_ < 2)
    throw InputError("stability: error: got " + std::to_string(frames_) +
                     " raster frame(s); expected at least 2 to measure change between frames");
  StabilityMetrics s = metrics_;
  double sum = 0;
  for (double r : s.flipRatePerPair) sum += r;
  s.shimmerRate = sum / double(s.flipRatePerPair.size());
  setErrorStatistics(s, errors_);
  return s;
}

StabilityMetrics measureStability(const Frame& reference, const std::vector<Frame>& rasters,
                                  const CompareOptions& options) {
  StabilityStream stream(reference, options);
  for (const Frame& f : rasters) stream.add(f);
  return stream.result();
}

void setErrorStatistics(StabilityMetrics& s, const std::vector<double>& e) {
  if (e.empty()) throw InputError("stability: error: no frames; expected at least one error rate");
  for (double v : e)
    if (!std::isfinite(v)) throw InputError("stability: error: a frame's error rate is not finite; expected a rate");
  s.frames = int(e.size());
  s.errorRatePerFrame = e;
  double sum = 0, emax = e.front(), jump = 0;
  for (size_t k = 0; k < e.size(); ++k) {
    sum += e[k];
    emax = std::max(emax, e[k]);
    if (k + 1 < e.size()) jump = std::max(jump, std::fabs(e[k + 1] - e[k]));
  }
  s.errorRateMean = sum / double(e.size());
  double var = 0;
  for (double v : e) var += (v - s.errorRateMean) * (v - s.errorRateMean);
  s.errorRateStd = std::sqrt(var / double(e.size()));
  s.errorRateMax = emax;
  s.errorJumpMax = jump;
}

nlohmann::json StabilityMetrics::toJson() const {
  nlohmann::json j = gateMetrics();
  if (hasShimmer()) {
    j["flip_rate_per_pair"] = flipRatePerPair;
    j["pixels_compared_per_pair"] = pixelsComparedPerPair;
  }
  j["error_rate_per_frame"] = errorRatePerFrame;
  return j;
}

nlohmann::json StabilityMetrics::gateMetrics() const {
  nlohmann::json j = {{"frames", frames},
                      {"error_rate_mean", errorRateMean},
                      {"error_rate_max", errorRateMax},
                      {"error_rate_std", errorRateStd},
                      {"error_jump_max", errorJumpMax}};
  if (hasShimmer()) j["shimmer_rate"] = shimmerRate;
  return j;
}

LightPathAxis parseLightPath(const std::string& text) {
  auto bad = [&](const std::string& what) { return InputError("--light-path " + text + ": error: " + what); };
  const std::string form = "KEY=FROM:TO:FRAMES, e.g. elevation_deg=60:10:11";
  const auto eq = text.find('=');
  if (eq == std::string::npos) throw bad("no '=' found; expected " + form);
  LightPathAxis a;
  a.key = text.substr(0, eq);
  if (a.key != "elevation_deg" && a.key != "azimuth_deg")
    throw bad("unknown key \"" + a.key + "\"; expected elevation_deg or azimuth_deg (a directional light's angles)");
  std::vector<std::string> parts;
  std::string rest = text.substr(eq + 1);
  for (size_t start = 0;;) {
    const auto colon = rest.find(':', start);
    parts.push_back(rest.substr(start, colon == std::string::npos ? std::string::npos : colon - start));
    if (colon == std::string::npos) break;
    start = colon + 1;
  }
  if (parts.size() != 3) throw bad("got " + std::to_string(parts.size()) + " field(s) after '='; expected 3: " + form);
  auto number = [&](const std::string& p, const char* what) {
    size_t used = 0;
    double v = 0;
    try {
      v = std::stod(p, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (p.empty() || used != p.size() || !std::isfinite(v))
      throw bad(std::string(what) + " is \"" + p + "\"; expected a finite number of degrees");
    return v;
  };
  a.from = number(parts[0], "FROM");
  a.to = number(parts[1], "TO");
  size_t used = 0;
  long frames = -1;
  try {
    frames = std::stol(parts[2], &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (parts[2].empty() || used != parts[2].size() || frames < 2 || frames > kMaxPathFrames)
    throw bad("FRAMES is \"" + parts[2] + "\"; expected an integer 2.." + std::to_string(kMaxPathFrames));
  a.frames = int(frames);
  if (a.key == "elevation_deg" && (std::fabs(a.from) > 90 || std::fabs(a.to) > 90))
    throw bad("an elevation outside -90..90 degrees; expected elevations in -90..90");
  return a;
}

std::vector<SceneOverride> lightPathOverrides(const nlohmann::json& doc, const Scene& scene, const std::string& lightName,
                                              const std::vector<LightPathAxis>& axes, int k) {
  if (axes.empty()) throw InputError("--light-path: error: no axis; expected KEY=FROM:TO:FRAMES");
  for (size_t i = 0; i < axes.size(); ++i)
    for (size_t j = i + 1; j < axes.size(); ++j) {
      if (axes[i].key == axes[j].key)
        throw InputError("--light-path " + axes[j].key + ": error: given twice; expected each angle once");
      if (axes[i].frames != axes[j].frames)
        throw InputError("--light-path: error: " + axes[i].key + " has " + std::to_string(axes[i].frames) +
                         " frames and " + axes[j].key + " " + std::to_string(axes[j].frames) +
                         "; expected the same number of frames");
    }
  size_t index = scene.lights.size();
  for (size_t i = 0; i < scene.lights.size(); ++i)
    if (scene.lights[i].name == lightName) index = i;
  if (index == scene.lights.size())
    throw InputError(formatError(scene.path, "/lights", "no light named \"" + lightName + "\"; expected the light to move"));
  const Light& light = scene.lights[index];
  const std::string ptr = "/lights/" + std::to_string(index);
  if (light.type != LightType::Directional)
    throw InputError(formatError(scene.path, ptr, "light \"" + lightName +
                                                      "\" is not directional; expected a directional light for "
                                                      "--light-path (elevation_deg and azimuth_deg move a sun)"));
  const nlohmann::json* declared = nullptr;
  if (doc.is_object() && doc.contains("lights") && doc["lights"].is_array() && doc["lights"].size() > index)
    declared = &doc["lights"][index];
  const bool byAngles = declared && declared->is_object() && !declared->contains("direction");
  std::vector<SceneOverride> out;
  if (byAngles) {
    for (const LightPathAxis& a : axes) out.push_back({ptr + "/" + a.key, a.value(k)});
    return out;
  }
  // Declared by direction: its angles from the direction to the light (the inverse of the loader's
  // (cos e sin a, sin e, cos e cos a)), the moved ones replaced, written back as a direction.
  constexpr double kDeg = 3.14159265358979323846 / 180.0;
  const glm::dvec3 toLight = -glm::dvec3(light.direction);
  double elevation = std::asin(std::clamp(toLight.y, -1.0, 1.0)) / kDeg;
  double azimuth = std::atan2(toLight.x, toLight.z) / kDeg;
  for (const LightPathAxis& a : axes) (a.key == "elevation_deg" ? elevation : azimuth) = a.value(k);
  const double e = elevation * kDeg, az = azimuth * kDeg;
  const glm::dvec3 d = -glm::dvec3(std::cos(e) * std::sin(az), std::sin(e), std::cos(e) * std::cos(az));
  out.push_back({ptr + "/direction", nlohmann::json::array({d.x, d.y, d.z})});
  return out;
}

}  // namespace shadowlab
