// Image files a scene names: the input is the bytes of a projector image and of an alpha texture
// (map_d), read through the same path the loader uses for both.
#include <filesystem>

#include "fuzz_support.h"
#include "shadowlab/scenes/loader.h"

using namespace shadowlab;

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  fuzz::writeFile("m.obj",
                  "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nusemtl a\nf 1/1 2/2 3/3\n");
  fuzz::writeFile("m.mtl", "newmtl a\nmap_d image.png\n");
  fuzz::writeFile("projector.json",
                  R"({"camera": {"position": [0, 2, 5], "look_at": [0, 0, 0], "vfov_deg": 45, "width": 8, "height": 6},
  "objects": [{"type": "plane", "size": [4, 4]}],
  "projectors": [{"name": "p", "position": [0, 3, 3], "look_at": [0, 0, 0], "fov_deg": 40, "image": "image.png"}]})");
  fuzz::writeFile("alpha.json",
                  R"({"camera": {"position": [0, 2, 5], "look_at": [0, 0, 0], "vfov_deg": 45, "width": 8, "height": 6},
  "objects": [{"type": "obj", "path": "m.obj"}],
  "lights": [{"type": "directional", "elevation_deg": 45}]})");
  std::filesystem::copy_file(std::filesystem::path(SHADOWLAB_SOURCE_DIR) / "scenes/data/fence_alpha.png",
                             fuzz::workDir() / "image.png");
  fuzz::requireGoodSetup("projector.json", [] { loadScene((fuzz::workDir() / "projector.json").string()); });
  fuzz::requireGoodSetup("alpha.json", [] { loadScene((fuzz::workDir() / "alpha.json").string()); });
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  fuzz::writeFile("image.png", std::string(reinterpret_cast<const char*>(data), size));
  fuzz::expectOnlyInputErrors([&] { loadScene((fuzz::workDir() / "projector.json").string()); });
  fuzz::expectOnlyInputErrors([&] { loadScene((fuzz::workDir() / "alpha.json").string()); });
  return 0;
}
