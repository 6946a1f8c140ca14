// fabatlas/vec3.h — a point or vector in space (x, y, z) and in the plane
// (x, y), as plain arrays of doubles. Units are the caller's (millimetres
// throughout fabatlas). The one definition that geometry, fem and swept share;
// their headers re-export it as geometry::Vec3, fem::Vec3 and swept::Vec3.
#pragma once

#include <array>

namespace fabatlas {

using Vec3 = std::array<double, 3>;
using Vec2 = std::array<double, 2>;

}  // namespace fabatlas
