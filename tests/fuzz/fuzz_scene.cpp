// Scene files: the JSON with everything it names. The folder holds a small OBJ with an MTL whose
// map_d is a PNG, and a projector image, so a mutated scene can reach every asset loader.
#include <filesystem>

#include "fuzz_support.h"
#include "shadowlab/scenes/loader.h"

using namespace shadowlab;

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  const std::filesystem::path data = std::filesystem::path(SHADOWLAB_SOURCE_DIR) / "scenes/data";
  std::filesystem::create_directories(fuzz::workDir() / "assets");
  fuzz::writeFile("assets/tri.obj",
                  "mtllib tri.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nusemtl leaf\nf 1/1 2/2 3/3\n");
  fuzz::writeFile("assets/tri.mtl", "newmtl leaf\nKd 0.5 0.5 0.5\nmap_d alpha.png\n");
  std::filesystem::copy_file(data / "fence_alpha.png", fuzz::workDir() / "assets/alpha.png");
  std::filesystem::copy_file(data / "projector_image.png", fuzz::workDir() / "projector_image.png");
  std::filesystem::copy_file(data / "fence_alpha.png", fuzz::workDir() / "fence_alpha.png");
  fuzz::requireGoodSetup("scenes/data/projector.json", [&] { loadScene((data / "projector.json").string()); });
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = fuzz::writeFile("scene.json", std::string(reinterpret_cast<const char*>(data), size));
  fuzz::expectOnlyInputErrors([&] { loadScene(path); });
  return 0;
}
