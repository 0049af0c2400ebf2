// The alignment check of outside frames (outside_alignment.h).
#include "shadowlab/compare/outside_alignment.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>

#include "shadowlab/compare/config_name.h"
#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/json_reader.h"
#include "shadowlab/scenes/number_text.h"

namespace shadowlab {
namespace {

// What a candidate camera sees: per pixel whether a surface is hit and whether it is lit.
struct Pattern {
  std::vector<uint8_t> hit, lit;
};

Pattern patternOf(const Frame& f, const std::string& light) {
  const std::vector<float>& hit = f.get("hit");
  const std::vector<float>& vis = f.get("light." + light + ".vis");
  Pattern p;
  p.hit.resize(hit.size());
  p.lit.resize(hit.size());
  for (size_t i = 0; i < hit.size(); ++i) {
    p.hit[i] = hit[i] >= 0.5f;
    p.lit[i] = vis[i] >= 0.5f;  // compare's own decision (classify.h)
  }
  return p;
}

Pattern flipped(const Pattern& p, int width, int height) {
  Pattern out = p;
  for (int y = 0; y < height; ++y) {
    const size_t from = size_t(height - 1 - y) * size_t(width), to = size_t(y) * size_t(width);
    std::copy_n(p.hit.begin() + long(from), width, out.hit.begin() + long(to));
    std::copy_n(p.lit.begin() + long(from), width, out.lit.begin() + long(to));
  }
  return out;
}

std::string ratioText(int width, int height) {
  const int g = std::gcd(width, height);
  char text[64];
  std::snprintf(text, sizeof text, "%d:%d (%.4g)", width / g, height / g, double(width) / double(height));
  return text;
}

// Four significant digits: the candidate's value, rounded as a person would state it.
std::string roundedText(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.4g", v);
  return text;
}

}  // namespace

void checkOutsideSize(int width, int height, const Camera& camera, const std::string& file) {
  if (width == camera.width && height == camera.height) return;
  const std::string sizes = "the frame is " + std::to_string(width) + "x" + std::to_string(height) +
                            " where the scene's camera is " + std::to_string(camera.width) + "x" +
                            std::to_string(camera.height);
  // Same aspect: cross-multiplied, exact.
  if (int64_t(width) * camera.height == int64_t(camera.width) * height) {
    throw InputError(formatError(file, "",
                                 "looks rendered at another size: " + sizes +
                                     " (the same aspect); expected a frame of the camera's size, pixel for pixel"));
  }
  throw InputError(formatError(file, "",
                               "looks rendered with another aspect: " + sizes + ", aspect " + ratioText(width, height) +
                                   " against " + ratioText(camera.width, camera.height) +
                                   "; expected a frame of the camera's size, pixel for pixel"));
}

nlohmann::json AlignmentCheck::toJson() const {
  nlohmann::json j = {{"verdict", verdict}, {"edge_pixels", edgePixels}, {"compared_pixels", comparedPixels}};
  nlohmann::json c = nlohmann::json::object();
  for (const auto& candidate : candidates) c[candidate.name] = candidate.disagreements;
  j["disagreements"] = c;
  return j;
}

AlignmentCheck checkOutsideAlignment(const Scene& scene, const Frame& truth, const Frame& outside, bool coverageGiven,
                                     const std::string& light, const std::string& file,
                                     const ReferenceOptions& traceOptions) {
  const int width = truth.width, height = truth.height;
  const size_t pixels = truth.pixelCount();
  struct Candidate {
    std::string name;
    std::string message;  // what the frame looks like, when this candidate explains it
    Pattern pattern;
  };
  std::vector<Candidate> candidates;
  candidates.push_back({"identity", "", patternOf(truth, light)});
  candidates.push_back({"flip",
                        "looks upside down (rows bottom-up: OpenGL's glReadPixels / WebGL's readPixels order); flip "
                        "it vertically so that row 0 is the top of the image",
                        flipped(candidates[0].pattern, width, height)});

  ReferenceOptions options = traceOptions;
  options.spp = 1;
  options.channels = ReferenceChannels::Compare;
  options.progress = nullptr;
  const struct {
    float dx, dy;
    const char* name;
  } shifts[] = {{-0.5f, 0.0f, "shift_x-0.5"}, {0.5f, 0.0f, "shift_x+0.5"},    {0.0f, -0.5f, "shift_y-0.5"},
                {0.0f, 0.5f, "shift_y+0.5"},  {-0.5f, -0.5f, "shift_xy-0.5"}, {0.5f, 0.5f, "shift_xy+0.5"}};
  for (const auto& s : shifts) {
    options.pixelOffset = glm::vec2(s.dx, s.dy);
    const std::string axis = s.dx != 0 && s.dy != 0 ? "in x and y" : s.dx != 0 ? "in x" : "in y";
    auto at = [](float base, float d) { return numberText(base + d); };
    const std::string message = "looks shifted by half a pixel " + axis +
                                ": its pixel (i, j) shows the camera ray through (i + " + at(0.5f, s.dx) + ", j + " +
                                at(0.5f, s.dy) +
                                ") rather than the pixel center (i + 0.5, j + 0.5); render with pixel centers at "
                                "(i + 0.5, j + 0.5) (no half-pixel offset in the projection)";
    candidates.push_back({s.name, message, patternOf(renderReference(scene, options), light)});
  }
  options.pixelOffset = glm::vec2(0.0f);
  for (const float sign : {1.0f, -1.0f}) {
    Scene other = scene;
    Camera& camera = other.camera;
    std::string what;
    if (camera.orthographic()) {
      camera.orthoHeight *= 1.0f + sign * kFovScale;
      what = "view height about " + roundedText(camera.orthoHeight) + " where the scene's camera has " +
             numberText(scene.camera.orthoHeight);
    } else {
      camera.vfovDeg *= 1.0f + sign * kFovScale;
      what = "vertical field of view about " + roundedText(camera.vfovDeg) + " degrees where the scene's camera has " +
             numberText(scene.camera.vfovDeg);
    }
    const std::string percent = (sign > 0 ? "+" : "-") + roundedText(kFovScale * 100.0) + "%";
    const std::string message = std::string("looks rendered with a ") + (sign > 0 ? "wider" : "narrower") +
                                " field of view (" + percent + ": " + what +
                                "); render with the scene camera's field of view (vfov_deg is vertical, in degrees)";
    candidates.push_back({"fov" + percent, message, patternOf(renderReference(other, options), light)});
  }

  // The observed pattern and the pixels where lit/shadowed is compared: where every candidate and
  // the frame itself see a surface, so that each candidate is counted over the same pixels.
  const Pattern observed = patternOf(outside, light);
  std::vector<uint8_t> inSet(pixels, 1);
  for (size_t i = 0; i < pixels; ++i) {
    for (const auto& c : candidates) inSet[i] &= c.pattern.hit[i];
    if (coverageGiven) inSet[i] &= observed.hit[i];
  }
  AlignmentCheck check;
  check.comparedPixels = uint64_t(std::count(inSet.begin(), inSet.end(), uint8_t(1)));
  // Edge pixels of the truth's pattern: a right or lower neighbour that differs (coverage where it
  // was given, lit/shadowed inside the set).
  const Pattern& truthPattern = candidates[0].pattern;
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const size_t i = size_t(y) * size_t(width) + size_t(x);
      bool edge = false;
      for (const size_t n : {x + 1 < width ? i + 1 : i, y + 1 < height ? i + size_t(width) : i}) {
        if (n == i) continue;
        if (coverageGiven && truthPattern.hit[i] != truthPattern.hit[n]) edge = true;
        if (inSet[i] && inSet[n] && truthPattern.lit[i] != truthPattern.lit[n]) edge = true;
      }
      check.edgePixels += edge;
    }
  }
  for (const auto& c : candidates) {
    uint64_t d = 0;
    for (size_t i = 0; i < pixels; ++i) {
      if (coverageGiven) d += c.pattern.hit[i] != observed.hit[i];
      if (inSet[i]) d += c.pattern.lit[i] != observed.lit[i];
    }
    check.candidates.push_back({c.name, d});
  }
  if (check.edgePixels < kMinEdgePixels) {
    check.verdict = "cannot tell";
    return check;
  }
  size_t best = 0;
  for (size_t c = 1; c < check.candidates.size(); ++c)
    if (check.candidates[c].disagreements < check.candidates[best].disagreements) best = c;
  const uint64_t identity = check.candidates[0].disagreements, explained = check.candidates[best].disagreements;
  const uint64_t minGain = std::max(kMinGainPixels, check.edgePixels / kGainEdgeDivisor);
  if (best != 0 && double(explained) <= kExplainedShare * double(identity) && identity - explained >= minGain) {
    throw InputError(formatError(file, "",
                                 "the frame " + candidates[best].message +
                                     " (the frame disagrees with the scene's camera at " + std::to_string(identity) +
                                     " pixels and with this explanation at " + std::to_string(explained) +
                                     "); refusing to score a misaligned frame"));
  }
  check.verdict = "aligned";
  return check;
}

std::string outsideConfigName(const DeclaredRenderer& declared) {
  std::vector<std::string> parts;
  if (!declared.name.empty()) parts.push_back("renderer=" + declared.name);
  std::vector<std::string> settings;
  for (auto it = declared.settings.begin(); it != declared.settings.end(); ++it)
    settings.push_back(it.key() + "=" + canonicalValueText(it.value()));
  std::sort(settings.begin(), settings.end());
  parts.insert(parts.end(), settings.begin(), settings.end());
  if (parts.empty()) return "outside";
  std::string out;
  for (const auto& p : parts) out += (out.empty() ? "" : ",") + p;
  return out;
}

nlohmann::json outsideMethodJson(const DeclaredRenderer& declared, const Frame& outside,
                                 const AlignmentCheck& alignment) {
  nlohmann::json j = nlohmann::json::object();
  j["frame"] = "outside";
  j["renderer"] = declared.name;
  auto meta = [&](const char* key, const char* fallback) {
    auto it = outside.meta.find(key);
    return it != outside.meta.end() && it->is_string() ? it->get<std::string>() : std::string(fallback);
  };
  j["coverage"] = meta("coverage", "assumed");
  j["boundary_band"] = meta("boundary_band", "pixels");
  j["alignment"] = alignment.toJson();
  if (!declared.filter.empty()) j["filter"] = declared.filter;
  if (declared.mapSize > 0) j["map_size"] = declared.mapSize;
  if (!declared.lightClipFromWorld.empty()) j["map_layers"] = declared.lightClipFromWorld.size();
  if (declared.depthBias) j["depth_bias"] = *declared.depthBias;
  if (declared.normalBiasWorld) j["normal_bias_world"] = *declared.normalBiasWorld;
  if (declared.frameMs) j["frame_ms"] = *declared.frameMs;
  j["settings"] = declared.settings;
  return j;
}

}  // namespace shadowlab
