// OBJ and MTL files as a scene names them: the input is the OBJ, then a line "#--MTL--", then the
// MTL it names as "mtllib m.mtl" (the MTL may name "alpha.png" as map_d).
#include <filesystem>

#include "fuzz_support.h"
#include "shadowlab/scenes/loader.h"

using namespace shadowlab;

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  std::filesystem::copy_file(std::filesystem::path(SHADOWLAB_SOURCE_DIR) / "scenes/data/fence_alpha.png",
                             fuzz::workDir() / "alpha.png");
  fuzz::writeFile("scene.json",
                  R"({"camera": {"position": [0, 2, 5], "look_at": [0, 0, 0], "vfov_deg": 45, "width": 8, "height": 6},
  "objects": [{"type": "obj", "path": "m.obj"}],
  "lights": [{"type": "directional", "elevation_deg": 45}]})");
  fuzz::writeFile("m.obj",
                  "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nusemtl a\nf 1/1 2/2 3/3\n");
  fuzz::writeFile("m.mtl", "newmtl a\nmap_d alpha.png\n");
  fuzz::requireGoodSetup("scene.json", [] { loadScene((fuzz::workDir() / "scene.json").string()); });
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::vector<std::string> parts = fuzz::split(data, size, "\n#--MTL--\n");
  fuzz::writeFile("m.obj", parts[0]);
  fuzz::writeFile("m.mtl", parts.size() > 1 ? parts[1] : std::string());
  fuzz::expectOnlyInputErrors([&] { loadScene((fuzz::workDir() / "scene.json").string()); });
  return 0;
}
