// tests/mesh/test_paths.h — the shared test paths, under the names the mesh
// tests and benchmarks use.
#pragma once

#include "fabatlas/testing/paths.h"

namespace fabatlas::mesh::testing {

using fabatlas::testing::SharedDir;
using fabatlas::testing::SourceDir;

}  // namespace fabatlas::mesh::testing
