// fabatlas/viewer/snap.h — snapping a point to the closest valid sample for
// preview (Fab Forms, Sec. 7.3 "3D Model Preview Generation").
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "fabatlas/sampling/form.h"

namespace fabatlas::viewer {

struct Snap {
  std::int64_t sample = -1;  // id into form.samples
  double distance = 0;       // ΔG-weighted distance from u (see SnapToValidSample)
  bool inside_leaf = true;   // false when the fallback below was used
};

// "We find the leaf hypercube containing u and snap to the closest valid
// vertex, using a linear approximation of the distance inside the hypercube
// based on the ΔG values computed along its edges." With t in [0,1]^n the
// position of u in the leaf and corner c in {0,1}^n, the distance is
//   D(u, c) = sum_d |t_d - c_d| * (ΔG(c, c xor e_d) + 1e-6),
// the ΔG of the leaf edge leaving c along d weighting the fraction of that
// edge travelled (the 1e-6 breaks ties between ΔG = 0 edges by position).
// Every leaf touching u is considered (u on a face belongs to several).
// Ties go to the lower sample id. When no leaf touching u has a valid corner,
// falls back to the valid sample nearest in parameter space normalised by
// each dimension's range (inside_leaf = false). nullopt if u is outside the
// space, has the wrong arity, or the form has no valid sample.
std::optional<Snap> SnapToValidSample(const sampling::Form& form, const sampling::DesignSpace& space,
                                      const std::vector<double>& u);

// ΔG of two samples as cached by the sampler; by convention 0 for a sample
// with itself, and 1 when the pair was never computed.
double CachedGeometryChange(const sampling::Form& form, std::int64_t a, std::int64_t b);

}  // namespace fabatlas::viewer
