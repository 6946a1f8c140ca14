// The runs the viewer tests read: directories `fabatlas run` published into
// (fixtures viewer_tube_run and viewer_peg_run, tests/viewer/CMakeLists.txt),
// named by FABATLAS_VIEWER_RUN and FABATLAS_VIEWER_PEG_RUN, else the build's
// test-fixtures/.
#pragma once

#include <cstdlib>
#include <filesystem>

#include "fabatlas/testing/paths.h"

namespace fabatlas::viewer_test {

// The tube job's run (tests/viewer/data/tube_wall_2d.yaml).
inline std::filesystem::path RunDir() {
  const char* dir = std::getenv("FABATLAS_VIEWER_RUN");
  return dir ? std::filesystem::path(dir) : testing::BinDir().parent_path() / "test-fixtures" / "viewer-tube";
}

// The peg rail's run (an integer and an enumerated parameter).
inline std::filesystem::path PegRunDir() {
  const char* dir = std::getenv("FABATLAS_VIEWER_PEG_RUN");
  return dir ? std::filesystem::path(dir) : testing::BinDir().parent_path() / "test-fixtures" / "viewer-peg";
}

}  // namespace fabatlas::viewer_test
