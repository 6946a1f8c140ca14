// fabatlas/viewer/valid_region.h — runtime validity lookups on a sampled form
// (Fab Forms, Sec. 7.2 "Local Validity Ranges").
//
// The valid region is the union of the k-d tree leaves whose 2^n corner
// samples are all valid, plus the faces and edges of any leaf whose corners
// on that face/edge are all valid ("any point u is considered valid if it lies
// inside a valid hypercube, or on an all-valid face or edge"). Lookups work
// on the raw k-d trees and read leaf corners from a LeafCorners table built
// once per form (leaf_corners.h); it must fit the form (LeafCorners::Fits),
// else std::invalid_argument. Single-threaded per call, thread-safe.
//
// Points u are parameter values in the order of form.dimensions (enumerated:
// the value index). A coordinate within 1e-9 of a bootstrap cell's width of
// a sample key counts as lying on it, so interval ends returned here are
// valid when passed back.
#pragma once

#include <string>
#include <vector>

#include "fabatlas/sampling/form.h"
#include "fabatlas/viewer/leaf_corners.h"

namespace fabatlas::viewer {

// True if u lies in the estimated valid region (see above). False outside
// the bounded space or for the wrong number of coordinates.
bool IsValidPoint(const sampling::Form& form, const sampling::DesignSpace& space, const LeafCorners& corners,
                  const std::vector<double>& u);

// Why u is outside the valid region: the distinct failure types (sorted) of
// the invalid corners of the smallest faces containing u of the leaves
// touching it. Empty if u is valid or outside the space.
std::vector<std::string> FailuresAt(const sampling::Form& form, const sampling::DesignSpace& space,
                                    const LeafCorners& corners, const std::vector<double>& u);

// One stretch of the line through u along a dimension.
struct Stretch {
  double lo = 0, hi = 0;  // parameter values, lo <= hi (a single valid point has lo == hi)
  bool valid = false;
  // Invalid stretches: the distinct failure types of the invalid samples at
  // the corners of the leaf faces the stretch crosses (the samples bounding
  // it), sorted by name.
  std::vector<std::string> failures;
};

// The whole line through u along `dimension`, from the dimension's lower to
// upper bound, as alternating valid / invalid stretches in increasing order
// (Fab Forms Sec. 7.2: the line is traced through every cut made along the
// direction and the points between them, so non-convex regions give several
// valid intervals). Stretches are closed for valid ones; an invalid stretch
// is the open gap between its neighbours. Throws fabatlas::InputError if u is
// outside the bounded space or has the wrong arity.
std::vector<Stretch> LineStretches(const sampling::Form& form, const sampling::DesignSpace& space,
                                   const LeafCorners& corners, const std::vector<double>& u, int dimension);

// Only the valid stretches of LineStretches.
std::vector<Stretch> ValidIntervals(const sampling::Form& form, const sampling::DesignSpace& space,
                                    const LeafCorners& corners, const std::vector<double>& u, int dimension);

}  // namespace fabatlas::viewer
