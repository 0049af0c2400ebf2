// `shadowlab scenes`: lists the bundled scenes, or validates scene files (--check).
#include <cstdio>
#include <memory>

#include "command.h"
#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/io.h"
#include "shadowlab/scenes/json_reader.h"
#include "shadowlab/scenes/loader.h"

namespace cmd_scenes {
namespace {

struct Options {
  bool namesOnly = false;
  std::vector<std::string> check;
};

// The one-line description is the scene file's "description" value; reading it does not load
// the geometry, so listing stays instant even when an asset is missing.
std::string describeScene(const std::string& path) {
  try {
    const nlohmann::json doc = shadowlab::readJsonFile(path);
    if (doc.is_object() && doc.contains("description") && doc["description"].is_string())
      return doc["description"].get<std::string>();
  } catch (const std::exception&) {
  }
  return "";
}

int run(const Options& opts) {
  using namespace shadowlab;
  if (!opts.check.empty()) {
    for (const auto& f : opts.check) {
      Scene s = loadScene(resolveScenePath(f));
      std::printf("%s: ok: %zu objects, %zu triangles, %zu lights, %zu projectors, %dx%d, hash %s\n", f.c_str(),
                  s.objects.size(), s.triangleCount(), s.lights.size(), s.projectors.size(), s.camera.width,
                  s.camera.height, s.hash.c_str());
    }
    return 0;
  }
  auto names = bundledSceneNames();
  if (names.empty()) throw InputError(formatError(bundledScenesDir(), "", "no bundled scenes found"));
  size_t width = 0;
  for (const auto& n : names) width = std::max(width, n.size());
  for (const auto& n : names) {
    if (opts.namesOnly) std::printf("%s\n", n.c_str());
    else std::printf("%-*s  %s\n", int(width), n.c_str(), describeScene(resolveScenePath(n)).c_str());
  }
  return 0;
}

shadowlab::app::Registrar reg{
    "scenes", [](CLI::App& app) {
      auto* sub = app.add_subcommand("scenes", "List the bundled scenes, or validate scene files with --check");
      auto opts = std::make_shared<Options>();
      sub->add_flag("--names", opts->namesOnly, "Print only the scene names, one per line");
      sub->add_option("--check", opts->check,
                      "Load and validate these scene files (or bundled names); exit 2 on the first bad one")
          ->expected(1, -1);
      return std::function<int()>([opts] { return run(*opts); });
    }};

}  // namespace
}  // namespace cmd_scenes
