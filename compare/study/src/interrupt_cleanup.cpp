// The registry of interrupt_cleanup.h: a mutex-guarded set, read once by the thread that handles
// the signal.
#include "shadowlab/compare/interrupt_cleanup.h"

#include <filesystem>
#include <mutex>
#include <set>

namespace shadowlab {
namespace {

std::mutex& registryMutex() {
  static std::mutex m;
  return m;
}
std::set<std::string>& registry() {
  static std::set<std::string> paths;
  return paths;
}

}  // namespace

void registerInterruptPath(const std::string& path) {
  std::lock_guard<std::mutex> lock(registryMutex());
  registry().insert(path);
}

void unregisterInterruptPath(const std::string& path) {
  std::lock_guard<std::mutex> lock(registryMutex());
  registry().erase(path);
}

int removeInterruptPaths() {
  std::lock_guard<std::mutex> lock(registryMutex());
  int removed = 0;
  for (const std::string& path : registry()) {
    std::error_code ec;
    if (std::filesystem::remove_all(path, ec) > 0 && !ec) ++removed;
  }
  registry().clear();
  return removed;
}

}  // namespace shadowlab
