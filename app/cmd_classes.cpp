// `shadowlab classes [--json]`: the pixel classes compare assigns (compare/classify/.../classes.h),
// as a table for people or as the JSON the sweep's chart script reads (classes.json).
#include <cstdio>
#include <memory>

#include "command.h"
#include "shadowlab/compare/compare.h"

namespace cmd_classes {
namespace {

using namespace shadowlab;

int run(bool json) {
  if (json) {
    std::printf("%s\n", pixelClassesJson().dump(2).c_str());
    return 0;
  }
  std::printf("%-4s %-18s %-6s %-18s %-14s %-8s %s\n", "code", "key", "error", "count metric", "rate metric", "color",
              "meaning");
  for (const PixelClassInfo& c : kPixelClasses) {
    std::printf("%-4d %-18s %-6s %-18s %-14s #%06x  %s\n", int(c.cls), c.key, c.error ? "yes" : "no",
                c.countMetric ? c.countMetric : "-", c.rateMetric ? c.rateMetric : "-", unsigned(c.rgbLit), c.help);
  }
  return 0;
}

shadowlab::app::Registrar reg{
    "classes", [](CLI::App& app) {
      auto json = std::make_shared<bool>(false);
      auto* sub = app.add_subcommand("classes", "List the pixel classes compare assigns (code, key, metrics, colour)");
      sub->add_flag("--json", *json, "Print the class table as JSON (what the sweep writes as classes.json)");
      return std::function<int()>([json] { return run(*json); });
    }};

}  // namespace
}  // namespace cmd_classes
