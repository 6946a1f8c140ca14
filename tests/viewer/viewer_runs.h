// The runs the viewer tests read: directories `fabatlas run` published into
// (fixtures viewer_tube_run and viewer_peg_run, tests/viewer/CMakeLists.txt),
// named by FABATLAS_VIEWER_RUN and FABATLAS_VIEWER_PEG_RUN, else the build's
// test-fixtures/.
#pragma once

#include <numbers>

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

// The tube run's design (tests/viewer/data): a tube of height 20 mm, valid
// where the wall is at least 1 + 0.01 r^2 and leaves a bore of 2 mm; its
// closed-form validity and volume (mm^3), the numbers the viewer tests
// check the runtime against.
inline bool TrulyValid(double radius, double wall) { return wall >= 1 + 0.01 * radius * radius && radius - wall >= 2; }
inline double TubeVolume(double r, double w) { return std::numbers::pi * (r * r - (r - w) * (r - w)) * 20.0; }

}  // namespace fabatlas::viewer_test
