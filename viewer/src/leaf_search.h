// Internal: finding the k-d tree leaves that touch a point or a line, in key
// coordinates (sampling/design_space.h). Shared by valid_region.cc and snap.cc.
#pragma once

#include <optional>
#include <vector>

#include "fabatlas/sampling/form.h"

namespace fabatlas::viewer::internal {

// u in key coordinates, with coordinates within 1e-9 of a bootstrap cell of
// an integer key snapped onto it. nullopt for the wrong arity, a non-finite
// value or a point outside the bounded space.
std::optional<std::vector<double>> KeyCoordinates(const sampling::DesignSpace& space, const std::vector<double>& u);

// Every leaf whose closed box contains x (key coordinates). With
// free_dimension >= 0, the leaves whose closed box meets the whole line
// through x along that dimension.
std::vector<const sampling::FormNode*> LeavesTouching(const sampling::Form& form, const sampling::DesignSpace& space,
                                                      const std::vector<double>& x, int free_dimension = -1);

// True if the corners of `leaf` on the smallest face containing x are all
// valid; the face is free along free_dimension (if >= 0) and along every
// dimension where x is strictly inside the leaf. Appends the failure types of
// invalid corners of that face to *failures when given.
bool FaceAllValid(const sampling::Form& form, const sampling::FormNode& leaf, const std::vector<double>& x,
                  int free_dimension, std::vector<std::string>* failures = nullptr);

}  // namespace fabatlas::viewer::internal
