#pragma once
// What an outside renderer says it used to draw a frame: the renderer JSON given beside a frame
// from another program (scenes/FRAME-CONTRACT.md). Every field is optional. A renderer that declares
// nothing is scored from the truth's own evidence alone; a declared light matrix and map size add
// the map's coverage (in or out of the map) and the texel footprint `m`.
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

namespace shadowlab {

struct DeclaredRenderer {
  std::string name;  // the renderer, free text ("three.js 0.187 PCFSoft"); "" when not declared
  // Per shadow-map layer (a cascade, a cube face; one for a plain directional or spot map): the
  // light's clip space from world space, column-major as glm keeps it. Inside the map the divided
  // coordinates x/w and y/w lie in [-1, 1] and w > 0. The y direction and the depth range (OpenGL's
  // -1..1 or Vulkan's 0..1) are the renderer's own: nothing read from the matrix depends on them.
  std::vector<glm::mat4> lightClipFromWorld;
  int mapSize = 0;  // texels along each side of a layer; 0: not declared
  // World-space offset along the surface normal applied before the lookup (three.js normalBias,
  // Unity's normal bias); absent when not declared.
  std::optional<double> normalBiasWorld;
  // The depth bias in the renderer's own units (three.js `shadow.bias`), kept as declared: it is
  // reported, not converted, since its unit depends on the renderer's depth convention.
  std::optional<double> depthBias;
  std::string filter;  // the renderer's filter name as it calls it ("PCFSoft"); "" when not declared
  std::optional<double> frameMs;  // the renderer's own time for this frame, milliseconds
  // The renderer's settings as it names them (every key it was given): they make the frame's
  // configuration name, so that `gate` matches a frame to the baseline row of the same settings.
  nlohmann::json settings = nlohmann::json::object();

  bool declaresMap() const { return !lightClipFromWorld.empty() && mapSize > 0; }
};

}  // namespace shadowlab
