#pragma once
// The end of runTune (tune.cpp): tuned.json, tune.json, tune.html, the verdict, and results.json /
// results.csv / report.html through the sweep's own writer.
#include "shadowlab/compare/tune.h"

namespace shadowlab {

// j[key] where it is a number, else NaN (the rows of tune.json read back).
double numberAt(const nlohmann::json& j, const char* key);

void writeTuneOutputs(TunePlan& plan, SweepRunner& runner, const TuneOptions& options, TuneResult& result);

}  // namespace shadowlab
