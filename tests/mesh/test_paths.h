// tests/mesh/test_paths.h — where the tests find the repository and the shared
// reference data: the CTest environment (FABATLAS_SOURCE_DIR,
// FABATLAS_SHARED_DIR) when set, else the paths compiled in by
// tests/mesh/CMakeLists.txt.
#pragma once

#include <cstdlib>
#include <filesystem>

namespace fabatlas::mesh::testing {

inline std::filesystem::path SourceDir() {
  const char* dir = std::getenv("FABATLAS_SOURCE_DIR");
  return dir ? dir : FABATLAS_MESH_TEST_SOURCE_DIR;
}

inline std::filesystem::path SharedDir() {
  const char* dir = std::getenv("FABATLAS_SHARED_DIR");
  return dir ? dir : FABATLAS_MESH_TEST_SHARED_DIR;
}

}  // namespace fabatlas::mesh::testing
