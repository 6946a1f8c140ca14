// Internal: finding the k-d tree leaves that touch a point or a line, in key
// coordinates (sampling/design_space.h). Shared by valid_region.cc and snap.cc.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "fabatlas/sampling/form.h"

namespace fabatlas::viewer::internal {

// u in key coordinates, with coordinates within 1e-9 of a bootstrap cell of
// an integer key snapped onto it. nullopt for the wrong arity, a non-finite
// value or a point outside the bounded space.
std::optional<std::vector<double>> KeyCoordinates(const sampling::DesignSpace& space, const std::vector<double>& u);

// A leaf found by LeavesTouching: the node and where it is in form.trees.
struct LeafHit {
  const sampling::FormNode* node = nullptr;
  int tree = -1;
  int index = -1;  // in form.trees[tree].nodes
};

// Every leaf whose closed box contains x (key coordinates). With
// free_dimension >= 0, the leaves whose closed box meets the whole line
// through x along that dimension.
std::vector<LeafHit> LeavesTouching(const sampling::Form& form, const sampling::DesignSpace& space,
                                    const std::vector<double>& x, int free_dimension = -1);

// Every leaf whose closed box meets the affine subspace through x that is
// free along each dimension d with free[d] (free.size() == dimensions): the
// leaves a slice at held parameter values crosses.
std::vector<LeafHit> LeavesMeeting(const sampling::Form& form, const sampling::DesignSpace& space,
                                   const std::vector<double>& x, const std::vector<bool>& free);

// True if the corners of `leaf` on the smallest face containing x are all
// valid; the face is free along free_dimension (if >= 0) and along every
// dimension where x is strictly inside the leaf. corners: the leaf's 2^n
// sample ids (LeafCorners::of). Appends the failure types of invalid corners
// of that face to *failures when given.
bool FaceAllValid(const sampling::Form& form, const sampling::FormNode& leaf, const std::int32_t* corners,
                  const std::vector<double>& x, int free_dimension, std::vector<std::string>* failures = nullptr);

}  // namespace fabatlas::viewer::internal
