#pragma once
// A number read back from a row's metrics or timings (results.json, the journal, tune's rows):
// j[key] where it is a JSON number, else `fallback`. Internal to shadowlab_study.
#include <cmath>

#include <nlohmann/json.hpp>

namespace shadowlab {

inline double numberAt(const nlohmann::json& j, const char* key, double fallback = NAN) {
  const auto it = j.find(key);
  return it != j.end() && it->is_number() ? it->get<double>() : fallback;
}

}  // namespace shadowlab
