#include "shadowlab/scenes/error.h"

namespace shadowlab {

std::string formatError(const std::string& file, const std::string& place, const std::string& what) {
  std::string out = file;
  if (!place.empty()) out += ": " + place;
  out += ": error: " + what;
  return out;
}

}  // namespace shadowlab
