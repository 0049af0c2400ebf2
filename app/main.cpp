// shadowlab: builds the CLI from the registered subcommands, parses, dispatches.
#include <algorithm>
#include <cstdio>
#include <exception>
#include <map>

#include <malloc.h>

#include <unistd.h>

#include "command.h"
#include "shadowlab/raster/raster.h"
#include "shadowlab/scenes/error.h"

namespace shadowlab::app {
std::vector<CommandEntry>& commandRegistry() {
  static std::vector<CommandEntry> registry;
  return registry;
}
}  // namespace shadowlab::app

int main(int argc, char** argv) {
  using namespace shadowlab;
  // A render hands out ~100 MB of channel planes (1080p) that are freed soon after: keep freed
  // memory in the heap for the next frame instead of returning it to the OS, where each reuse
  // page-faults every 4 KiB back in (~40 ms at 1080p). Process-wide, so the program sets it,
  // not the rasterizer library.
  mallopt(M_MMAP_THRESHOLD, 32 << 20), mallopt(M_TRIM_THRESHOLD, 1 << 30);
  CLI::App cli{"shadowlab: how wrong are your shadow maps, and why"};
  cli.require_subcommand(1);
  auto& registry = app::commandRegistry();
  // Registration order follows static initialisation order: sort for stable help text.
  std::sort(registry.begin(), registry.end(),
            [](const app::CommandEntry& a, const app::CommandEntry& b) { return a.name < b.name; });
  std::map<std::string, std::function<int()>> runners;
  for (auto& entry : registry) runners[entry.name] = entry.setup(cli);
  try {
    cli.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    int code = cli.exit(e);
    return code == 0 ? 0 : 2;
  }
  const int code = [&] {
    try {
      for (auto* sub : cli.get_subcommands()) return runners.at(sub->get_name())();
      return 2;
    } catch (const InputError& e) {
      std::fprintf(stderr, "%s\n", e.what());
      return 2;
    } catch (const DriverError& e) {
      std::fprintf(stderr, "shadowlab: internal error: %s\n", e.what());
      return 3;
    } catch (const std::exception& e) {
      std::fprintf(stderr, "shadowlab: internal error: %s\n", e.what());
      return 3;
    }
  }();
  // A device still running a shader that never returned (--gpu-timeout-s): the driver's exit
  // handlers would wait for its threads forever, so the process ends here, its outputs written or
  // removed already (every output is atomic).
  if (shadowlab::rasterDeviceHung()) {
    std::fflush(stdout);
    std::fflush(stderr);
    _exit(code);
  }
  return code;
}
