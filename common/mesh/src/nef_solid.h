// nef_solid.h — NefSolid (exact_solid.h): CGAL's Nef polyhedron of the exact
// kernel. Internal; only the files that need Nef polyhedra include it
// (Nef_polyhedron_3 is the heaviest CGAL header fabatlas compiles).
#pragma once

#include <CGAL/Nef_polyhedron_3.h>

#include "exact_solid.h"

namespace fabatlas::mesh::internal {

using Nef = CGAL::Nef_polyhedron_3<Kernel>;

struct NefSolid {
  Nef nef;
};

}  // namespace fabatlas::mesh::internal
