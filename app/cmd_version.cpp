// `shadowlab version`: prints the version line, as `shadowlab --version` (-V) does.
#include <cstdio>

#include "command.h"

namespace cmd_version {
namespace {
shadowlab::app::Registrar reg{"version", [](CLI::App& app) {
                                app.add_subcommand("version", "Print the shadowlab version (as --version)");
                                return std::function<int()>([] {
                                  std::printf("%s\n", shadowlab::app::versionString().c_str());
                                  return 0;
                                });
                              }};
}  // namespace
}  // namespace cmd_version
