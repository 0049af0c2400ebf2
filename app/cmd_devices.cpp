// `shadowlab devices [--json]`: the Vulkan devices this machine offers, what `--device NAME` (a
// substring of the name) picks among; the default one (empty --device) is marked.
#include <cstdio>

#include <nlohmann/json.hpp>

#include "command.h"
#include "shadowlab/raster/devices.h"

namespace cmd_devices {
namespace {

using namespace shadowlab;

int run(bool json) {
  const std::vector<RasterDeviceInfo> devices = listRasterDevices();
  if (json) {
    nlohmann::json out = nlohmann::json::array();
    for (const auto& d : devices)
      out.push_back({{"name", d.name},
                     {"type", d.type},
                     {"driver", d.driver},
                     {"driver_info", d.driverInfo},
                     {"api_version", d.apiVersion},
                     {"vulkan13", d.vulkan13},
                     {"default", d.isDefault}});
    std::printf("%s\n", out.dump(2).c_str());
    return 0;
  }
  if (devices.empty()) std::printf("no Vulkan device\n");
  for (const auto& d : devices)
    std::printf("%s %s  [%s, driver %s %s, Vulkan %s%s]\n", d.isDefault ? "*" : "-", d.name.c_str(), d.type.c_str(),
                d.driver.empty() ? "?" : d.driver.c_str(), d.driverInfo.c_str(), d.apiVersion.c_str(),
                d.vulkan13 ? "" : ": too old, shadowlab needs 1.3");
  return 0;
}

app::Registrar reg{"devices", [](CLI::App& app) {
                     auto* sub = app.add_subcommand(
                         "devices", "List the Vulkan devices (--device NAME picks one by a substring; * = default)");
                     auto json = std::make_shared<bool>(false);
                     sub->add_flag(
                         "--json", *json,
                         "Print a JSON array (name, type, driver, driver_info, api_version, vulkan13, default)");
                     return std::function<int()>([json] { return run(*json); });
                   }};

}  // namespace
}  // namespace cmd_devices
