// glTF 2.0 files as a scene: the input is the file itself, written as m.glb when it starts with the
// GLB magic ("glTF"), else as m.gltf; beside it lie m.bin (a 96-byte buffer) and alpha.png (an RGBA
// checker) for the URIs a mutated file may name.
#include <filesystem>

#include "fuzz_support.h"
#include "shadowlab/scenes/loader.h"

using namespace shadowlab;

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  std::filesystem::copy_file(std::filesystem::path(SHADOWLAB_SOURCE_DIR) / "scenes/data/gltf_checker_alpha.png",
                             fuzz::workDir() / "alpha.png");
  fuzz::writeFile("m.bin", std::string(96, '\0'));
  const std::string good =
      R"({"asset": {"version": "2.0"}, "buffers": [{"uri": "m.bin", "byteLength": 96}],
  "bufferViews": [{"buffer": 0, "byteLength": 36}], "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
  "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"}],
  "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}]})";
  fuzz::writeFile("m.gltf", good);
  // Three zero vertices make one (degenerate) triangle: the setup itself must load.
  fuzz::requireGoodSetup("m.gltf", [] { loadScene((fuzz::workDir() / "m.gltf").string()); });
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const bool binary = size >= 4 && data[0] == 'g' && data[1] == 'l' && data[2] == 'T' && data[3] == 'F';
  const std::string name = binary ? "m.glb" : "m.gltf";
  fuzz::writeFile(name, std::string(reinterpret_cast<const char*>(data), size));
  fuzz::expectOnlyInputErrors([&] { loadScene((fuzz::workDir() / name).string()); });
  return 0;
}
