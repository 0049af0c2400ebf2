#pragma once
// A loaded Scene as a glTF 2.0 binary (.glb) that an outside engine loads and renders, and that
// shadowlab loads back into the same scene: the same triangles in the same order (positions bit
// for bit), the same object names and ids, materials, lights and camera (scenes/FORMAT.md,
// "Exporting a scene as glTF"). What glTF cannot carry is named in `notes`, never dropped silently.
#include <string>
#include <vector>

#include "shadowlab/scenes/scene.h"

namespace shadowlab {

struct GltfExport {
  std::string glb;                 // the whole .glb file (header, JSON chunk, BIN chunk)
  std::vector<std::string> notes;  // one line each: what the file does not carry (also in asset.extras)
};

// `generator` is asset.generator ("shadowlab 0.1.0 (git ...)"). Throws InputError where the scene
// cannot be written at all (a glTF file is limited to 4 GiB).
GltfExport exportGlb(const Scene& scene, const std::string& generator);

// True for a path ending in .glb (any case).
bool isGlbPath(const std::string& path);

}  // namespace shadowlab
