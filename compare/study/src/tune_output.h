#pragma once
// The end of runTune (tune.cpp): tuned.json, tune.json, tune.html, the verdict, and results.json /
// results.csv / report.html through the sweep's own writer.
#include "shadowlab/compare/tune.h"

namespace shadowlab {

void writeTuneOutputs(TunePlan& plan, SweepRunner& runner, const TuneOptions& options, TuneResult& result);

}  // namespace shadowlab
