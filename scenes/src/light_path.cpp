// Light paths (light_path.h): a directional light's angles moved frame by frame.
#include "shadowlab/scenes/light_path.h"

#include <algorithm>
#include <cmath>

#include "shadowlab/scenes/camera_path.h"
#include "shadowlab/scenes/error.h"

namespace shadowlab {

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

std::vector<SceneOverride> lightPathOverrides(const nlohmann::json& doc, const Scene& scene,
                                              const std::string& lightName, const std::vector<LightPathAxis>& axes,
                                              int k) {
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
    throw InputError(
        formatError(scene.path, "/lights", "no light named \"" + lightName + "\"; expected the light to move"));
  const Light& light = scene.lights[index];
  const std::string ptr = "/lights/" + std::to_string(index);
  if (light.type != LightType::Directional)
    throw InputError(formatError(scene.path, ptr,
                                 "light \"" + lightName +
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
