#pragma once
// Failure frontiers of a sweep (compare/SWEEPS.md, "Failure frontiers"): for each scene, each swept
// scene: parameter and each method configuration, walk the parameter's values from easy to hard
// and find the first value where a metric (error_rate by default) exceeds a threshold.
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "shadowlab/compare/results.h"
#include "shadowlab/compare/sweep.h"

namespace shadowlab {

struct Frontier {
  bool holds = true;      // no value exceeds the threshold
  size_t breakIndex = 0;  // when !holds: the first index whose metric > threshold
  bool recovers = false;  // when !holds: a later value is back at or under the threshold (non-monotone)
};

// `metrics` are in walking order (easy to hard) and finite. A value breaks when it is strictly
// greater than `threshold`.
Frontier findFrontier(const std::vector<double>& metrics, double threshold);

// Every frontier of the sweep, as results.json's "frontiers" array (empty when no scene: key is swept
// with at least two values). Walking order of a parameter: when it is the scene's declared "failure"
// pointer, from the declaration's first value towards its last (scenes/FORMAT.md: easy to hard),
// numerically; otherwise the grid's order. Rows whose metric is missing or not finite are left out
// of the walk (listed in "missing").
nlohmann::json computeFrontiers(const SweepPlan& plan, const std::vector<ResultRow>& rows, const std::string& metric,
                                double threshold);

}  // namespace shadowlab
