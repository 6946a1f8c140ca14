// fabatlas/viewer/failure_reason.h — why a point is not fabricable, in words
// (Fab Forms Sec. 7.2 shows invalid stretches; its user study asked why).
// The form stores each sample's failure type only, so the reason is
// recomputed on demand from the design.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "fabatlas/viewer/customiser.h"
#include "fabatlas/viewer/property_limits.h"

namespace fabatlas::viewer {

struct FailureReason {
  std::int64_t sample = -1;  // the invalid sample whose checks were re-run
  std::vector<double> u;     // its point
  std::string check;         // the check that failed first, e.g. "constraints", "thin_parts"
  std::string failure;       // its failure type
  std::string reason;        // e.g. "constraint 'wall >= 1 + 0.01 * radius^2' stays violated by 8.41"
};

// Among the invalid corner samples of the leaves touching u (the samples
// that make u invalid; if there are none, every invalid sample), the one
// nearest u in range-normalised parameter space (ties: lower id) is
// evaluated again with all checks at the design's voxel size, exactly as
// sampling did, and its first failed check reported. nullopt when the form
// has no invalid sample or no design. Throws InputError for a u outside the
// space. Costs one full evaluation (checks included) on the calling thread.
//
// `shown` is the form whose validity the user sees: the customiser's own, or
// it under the user's limits (ApplyLimits); a sample invalid only by a limit
// gets check "limits" and LimitReason's words, without evaluation.
std::optional<FailureReason> ReasonAt(const Customiser& customiser, const sampling::Form& shown,
                                      const std::vector<PropertyLimit>& limits, const std::vector<double>& u);

}  // namespace fabatlas::viewer
