#pragma once
// Each subcommand lives in app/cmd_<name>.cpp and registers itself with a static Registrar:
//
//   static shadowlab::app::Registrar reg{"reference", [](CLI::App& app) {
//     auto* sub = app.add_subcommand("reference", "Trace the Embree ground truth");
//     auto opts = std::make_shared<Options>();
//     sub->add_option(...);
//     return std::function<int()>([opts] { return run(*opts); });
//   }};
//
// The returned function runs when that subcommand was chosen; it returns the exit code.
// It throws InputError (-> 2) or DriverError (-> 3); main prints what() and maps the code.
// Exit codes: 0 ok, 1 gate failed, 2 bad input or usage, 3 internal/driver failure.
#include <functional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

namespace shadowlab::app {

using Setup = std::function<std::function<int()>(CLI::App&)>;

struct CommandEntry {
  std::string name;
  Setup setup;
};

std::vector<CommandEntry>& commandRegistry();

struct Registrar {
  Registrar(const std::string& name, Setup setup) { commandRegistry().push_back({name, std::move(setup)}); }
};

}  // namespace shadowlab::app
