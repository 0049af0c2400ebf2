// Which rows' time decides something (sweep.h, rowsWhoseTimeDecides; compare/TIMINGS.md, "Timed
// repetitions").
#include <algorithm>
#include <cmath>
#include <map>

#include "json_number.h"
#include "shadowlab/compare/method_cost.h"
#include "shadowlab/compare/sweep.h"
#include "shadowlab/compare/timings.h"

namespace shadowlab {

std::vector<size_t> rowsWhoseTimeDecides(const std::vector<const ResultRow*>& rows, const std::vector<double>& modelMs,
                                         double noiseFactor) {
  auto errorOf = [&](size_t i) { return numberAt(rows[i]->metrics, "error_rate"); };
  std::map<std::string, std::vector<size_t>> byScene;  // the rankable rows of each scene
  for (size_t i = 0; i < rows.size(); ++i)
    if (comparedSomething(*rows[i]) && std::isfinite(errorOf(i)) && std::isfinite(methodMs(*rows[i])))
      byScene[rows[i]->scene].push_back(i);
  auto model = [&](size_t i) { return i < modelMs.size() ? modelMs[i] : NAN; };
  std::vector<size_t> out;
  for (const auto& [scene, idx] : byScene)
    for (size_t r : idx) {
      const double er = errorOf(r), tr = methodMs(*rows[r]);
      bool beaten = false;
      for (size_t s : idx) {
        if (s == r) continue;
        const double es = errorOf(s), ts = methodMs(*rows[s]);
        // Of two rows of one error, the first stands for both where neither is faster beyond the noise.
        if (es > er || (es == er && s > r && !(ts * noiseFactor < tr))) continue;
        // Faster beyond the noise, or of the same modelled cost and not slower beyond the noise:
        // configurations the cost model cannot tell apart (a bias axis: the same passes) measure
        // alike but for noise, and a median would not order them either. Where the model tells
        // two apart it decides nothing: the measurement does.
        const bool sameCost = std::isfinite(model(s)) && model(s) == model(r);
        if (ts * noiseFactor < tr || (sameCost && !(tr * noiseFactor < ts))) {
          beaten = true;
          break;
        }
      }
      if (!beaten) out.push_back(r);
    }
  std::sort(out.begin(), out.end());
  return out;
}

nlohmann::json withMedianTiming(const nlohmann::json& timings, const std::vector<MethodSample>& more) {
  if (more.empty()) return timings;
  auto ms = [&](const char* key) { return numberAt(timings, key, 0.0); };
  std::vector<MethodSample> runs = more;
  runs.push_back({ms(timing::kShadowGpuMs), ms(timing::kLookupGpuMs), ms(timing::kMomentsGpuMs), ms(timing::kSdsmGpuMs)});
  std::stable_sort(runs.begin(), runs.end(),
                   [](const MethodSample& a, const MethodSample& b) { return a.methodGpuMs() < b.methodGpuMs(); });
  // The lower middle of an even count: a run, never an average of two, so its parts sum up.
  const MethodSample& median = runs[(runs.size() - 1) / 2];
  nlohmann::json out = timings;
  out[timing::kShadowGpuMs] = median.shadowGpuMs;
  out[timing::kLookupGpuMs] = median.lookupGpuMs;
  out[timing::kMomentsGpuMs] = median.momentsGpuMs;
  if (timings.contains(timing::kSdsmGpuMs)) out[timing::kSdsmGpuMs] = median.sdsmGpuMs;
  out[timing::kMethodGpuMs] = median.methodGpuMs();
  out[timing::kMethodGpuMsMin] = runs.front().methodGpuMs();
  out[timing::kMethodGpuMsMax] = runs.back().methodGpuMs();
  return out;
}

std::vector<size_t> jobsWhoseTimeDecides(const SweepPlan& plan, const std::vector<const ResultRow*>& rows) {
  std::vector<const ResultRow*> present;
  std::vector<double> modelMs;
  std::vector<size_t> jobOf;
  for (size_t i = 0; i < plan.jobs.size() && i < rows.size(); ++i) {
    if (!rows[i]) continue;
    const SweepJob& job = plan.jobs[i];
    present.push_back(rows[i]);
    jobOf.push_back(i);
    modelMs.push_back(
        estimateMethodCost(plan.variants[job.variantIndex], plan.configs[job.configIndex].method, job.light)
            .estimatedMs);
  }
  std::vector<size_t> out;
  for (size_t k : rowsWhoseTimeDecides(present, modelMs)) out.push_back(jobOf[k]);
  return out;
}

}  // namespace shadowlab
