#include "fabatlas/viewer/failure_reason.h"

#include <limits>

#include "fabatlas/design/evaluate_sample.h"
#include "fabatlas/error.h"
#include "fabatlas/precompute/design_evaluator.h"
#include "leaf_search.h"

namespace fabatlas::viewer {

std::optional<FailureReason> ReasonAt(const Customiser& c, const sampling::Form& shown,
                                      const std::vector<PropertyLimit>& limits, const std::vector<double>& u) {
  const auto x = internal::KeyCoordinates(c.space(), u);
  if (!x) throw InputError("point outside the design space (or wrong number of coordinates)");
  if (!c.source().design) return std::nullopt;
  const auto& samples = shown.samples;
  std::vector<std::int64_t> candidates;
  for (const internal::LeafHit& leaf : internal::LeavesTouching(shown, c.space(), *x))
    for (const std::int64_t id : sampling::CornerSampleIds(shown, *leaf.node))
      if (!samples[id].outcome.valid) candidates.push_back(id);
  if (candidates.empty())
    for (std::size_t id = 0; id < samples.size(); ++id)
      if (!samples[id].outcome.valid) candidates.push_back(static_cast<std::int64_t>(id));
  std::int64_t best = -1;
  double best_d = std::numeric_limits<double>::infinity();
  for (const std::int64_t id : candidates) {
    double d2 = 0;
    for (int d = 0; d < c.dimension_count(); ++d) {
      const auto& dim = c.space().dimension(d);
      const double t = (samples[id].u[d] - u[d]) / (dim.hi > dim.lo ? dim.hi - dim.lo : 1.0);
      d2 += t * t;
    }
    if (d2 < best_d || (d2 == best_d && id < best)) best_d = d2, best = id;
  }
  if (best < 0) return std::nullopt;
  FailureReason out;
  out.sample = best;
  out.u = samples[best].u;
  if (samples[best].outcome.failure_type.rfind(kLimitFailurePrefix, 0) == 0) {
    out.check = "limits";
    out.failure = samples[best].outcome.failure_type;
    out.reason = LimitReason(samples[best].outcome.properties, limits, c.source().materials);
    return out;
  }
  const design::Design& design = *c.source().design;
  const design::SampleResult r =
      design::EvaluateSample(design, precompute::DesignPointOf(design, samples[best].u), design::EvaluateOptions{});
  out.failure = r.failure.empty() ? samples[best].outcome.failure_type : r.failure;
  out.reason = r.failure_reason;
  for (const auto& check : r.checks)
    if (!check.passed) {
      out.check = check.name;
      if (out.reason.empty()) out.reason = check.reason;
      break;
    }
  if (out.reason.empty()) out.reason = out.failure;  // e.g. a failure the checks no longer reproduce
  return out;
}

}  // namespace fabatlas::viewer
