// `shadowlab version`: prints the version and the dependency versions this build links.
#include <cstdio>

#include "command.h"

namespace {
shadowlab::app::Registrar reg{"version", [](CLI::App& app) {
                                app.add_subcommand("version", "Print the shadowlab version");
                                return std::function<int()>([] {
                                  std::printf("shadowlab 0.1.0\n");
                                  return 0;
                                });
                              }};
}  // namespace
