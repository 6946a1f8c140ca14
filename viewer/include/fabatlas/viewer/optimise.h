// fabatlas/viewer/optimise.h — the best design for an objective inside the
// valid region (Schulz et al. 2017, "Interactive design space exploration and
// optimization for CAD models": optimising over the precomputed space
// instead of evaluating the design; docs/references.md).
//
// The objective is a weighted sum of stored properties, Σ w_i p_i, minimised
// or maximised: a recorded property ("volume", "bbox_z", ...), weight /
// cost in a material derived from "volume" ("weight:PLA", also spelled
// "weight_PLA"), or a parameter ("height"; ResolveQuantity in
// property_limits.h). Runtime limits are applied by passing
// the limited form (Customiser::LimitedForm): its samples outside the
// limits are invalid, so the answer meets them.
//
// What is searched. Between samples the runtime knows a property only by
// interpolation, and the multilinear interpolant of a k-d leaf's corners
// takes its extremes at corners. So:
//   - Nothing held: the answer is the best valid sample (every sample is a
//     corner of some leaf, and a valid corner is a valid point). Exact on
//     the samples; points inside leaves are never better than their
//     corners under interpolation, and are not evaluated.
//   - Parameters held at values: the slice of the space at those values
//     crosses leaves; in each leaf the slice is a box whose corners lie on
//     the leaf's edges and faces. Each such slice corner is a candidate
//     when it is valid by the runtime rule (IsValidPoint: the corners of the
//     smallest leaf face containing it are all valid), its value the
//     multilinear interpolation, along the held dimensions, of those
//     corners' values. When a held value is a sample coordinate the
//     candidates are samples and the value is exact. Interpolated values
//     are not confirmed by evaluating the design (that costs a full
//     evaluation, seconds; `fabatlas export --at` does it, with every check);
//     `sample` says which case the answer is.
// Ties go to the candidate met first: lower sample id (nothing held), else
// trees and leaves in form order. Single-threaded, thread-safe.
//
// Cost: nothing held, O(samples) property look-ups; held, O(leaves met by the
// slice x 2^n) plus the same look-ups.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "fabatlas/sampling/form.h"
#include "fabatlas/sampling/job_file.h"
#include "fabatlas/viewer/leaf_corners.h"

namespace fabatlas::viewer {

struct ObjectiveTerm {
  std::string property;  // a property or parameter, as ResolveQuantity accepts it
  double weight = 1;
};

struct HeldParameter {
  int dimension = -1;  // index into form.dimensions
  double value = 0;    // parameter value (enumerated: the value index)
};

struct OptimiseOptions {
  std::vector<ObjectiveTerm> terms;  // the objective Σ weight * property; at least one
  bool maximise = false;             // default: minimise
  std::vector<HeldParameter> hold;   // parameters fixed at a value; default none
};

struct OptimiseResult {
  bool found = false;                   // false: no valid point (under the limits, on the hold)
  std::vector<double> u;                // the answer, parameter values in the form's order
  double objective = 0;                 // Σ weight * value at u
  std::vector<double> values;           // each term's value at u, in the order of `terms`
  std::vector<std::string> properties;  // each term's canonical property name
  // The sample at u, or -1 when u is a slice corner inside a leaf edge or
  // face (held parameters) and `values` are interpolated from `corners`.
  std::int64_t sample = -1;
  std::vector<std::int64_t> corners;  // the samples interpolated (just `sample` when exact)
  std::int64_t candidates = 0;        // points compared
};

// The best point of the valid region of `form` for the objective (see
// above). `corners` must be built from `form` or a form with the same trees
// (LeafCorners::Fits). Throws InputError for no terms, a non-finite weight,
// an unknown property (ResolveQuantity), a held dimension out of range,
// held twice or a held value outside its range.
OptimiseResult Optimise(const sampling::Form& form, const LeafCorners& corners,
                        const std::vector<sampling::Material>& materials, const OptimiseOptions& options);

// "volume" (one term, weight 1) or "volume=1,weight:PLA=-2" (a weighted
// sum). Throws InputError for an empty item, a missing name, or a weight
// that is not a finite number.
std::vector<ObjectiveTerm> ParseObjective(const std::string& text);

// "height=45,head=8": parameter names of `space` and values (enumerated: a
// value's name or its index). Throws InputError naming the item for an
// unknown parameter, a value that is not a number (or value name), outside
// the parameter's range, not whole for an integer parameter, or a parameter
// held twice.
std::vector<HeldParameter> ParseHolds(const std::string& text, const sampling::DesignSpace& space);

}  // namespace fabatlas::viewer
