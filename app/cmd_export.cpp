// `shadowlab export SCENE -o FILE.glb [--set scene:/pointer=value ...]`: writes the loaded scene (a
// bundled name, a JSON scene file or a glTF file) as a glTF 2.0 binary that an outside engine
// renders and that shadowlab loads back into the same truth (scenes/FORMAT.md, "Exporting a scene
// as glTF"). What glTF cannot carry is printed, one line each, and written into asset.extras.
#include <cstdio>
#include <filesystem>
#include <memory>

#include "command.h"
#include "shadowlab/compare/set_arguments.h"
#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/gltf_export.h"
#include "shadowlab/scenes/io.h"
#include "shadowlab/scenes/loader.h"

namespace cmd_export {
namespace {

struct Options {
  std::string scene;
  std::string out;
  std::vector<std::string> sets;
};

int run(const Options& options) {
  namespace fs = std::filesystem;
  // Every argument is checked before the scene is loaded or anything is written.
  if (!shadowlab::isGlbPath(options.out))
    throw shadowlab::InputError("shadowlab export: error: -o " + options.out +
                                ": expected a .glb file name (glTF 2.0 binary)");
  std::error_code ec;
  const fs::path parent = fs::path(options.out).parent_path();
  if (!parent.empty() && !fs::is_directory(parent, ec))
    throw shadowlab::InputError("shadowlab export: error: -o " + options.out + ": the folder " + parent.string() +
                                " does not exist; expected an existing folder");
  if (fs::is_directory(options.out, ec))
    throw shadowlab::InputError("shadowlab export: error: -o " + options.out + " is a folder; expected a file name");
  for (const std::string& s : options.sets)
    if (s.rfind("scene:", 0) != 0)
      throw shadowlab::InputError("--set: error: got \"" + s +
                                  "\"; expected scene:/json/pointer=value (export takes no method keys)");
  const shadowlab::SetArguments set = shadowlab::applySetArguments("", options.sets);
  const shadowlab::Scene scene = shadowlab::loadScene(shadowlab::resolveScenePath(options.scene), set.sceneOverrides);
  const shadowlab::GltfExport exported = shadowlab::exportGlb(scene, shadowlab::app::versionString());
  shadowlab::writeFileAtomic(options.out, exported.glb);
  for (const std::string& note : exported.notes)
    std::fprintf(stderr, "%s: note: %s\n", options.out.c_str(), note.c_str());
  std::printf("export: %s: %zu objects, %zu triangles, %zu lights -> %s (%zu bytes)\n", scene.name.c_str(),
              scene.objects.size(), scene.triangleCount(), scene.lights.size(), options.out.c_str(),
              exported.glb.size());
  return 0;
}

shadowlab::app::Registrar reg{
    "export", [](CLI::App& app) {
      auto* sub = app.add_subcommand("export", "Write a scene as a glTF 2.0 binary (.glb) an engine loads");
      auto options = std::make_shared<Options>();
      sub->add_option("scene", options->scene,
                      "bundled scene name (see `shadowlab scenes`), a scene .json, or a .gltf/.glb file")
          ->required();
      sub->add_option("-o,--out", options->out, "output file, FILE.glb")->required();
      sub->add_option("--set", options->sets, "scene:/json/pointer=value: override one scene value (repeatable)")
          ->allow_extra_args(false);
      return std::function<int()>([options] { return run(*options); });
    }};

}  // namespace
}  // namespace cmd_export
