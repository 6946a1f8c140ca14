// fabatlas/error.h — the one error type for bad input.
//
// Every problem with what a user hands fabatlas (a design file, a mesh, a job
// file, a value on the command line) is reported as an InputError whose what()
// is a single line naming the place and what is wrong, e.g.
//   "configs/designs/vase.yaml:12:7: unknown node type 'sphear'"
//   "meshes/mug.obj: vertex 17 has a NaN coordinate"
// Binaries print it and exit with status 2. Internal faults (bugs) are not
// InputErrors and keep their own exception types.
#pragma once

#include <stdexcept>
#include <string>

namespace fabatlas {

class InputError : public std::runtime_error {
 public:
  explicit InputError(const std::string& one_line_message) : std::runtime_error(one_line_message) {}
};

// Input that is well formed but would exceed a resource limit (voxel counts
// that would exhaust memory, a full disk). Still the user's to fix.
class ResourceError : public InputError {
 public:
  using InputError::InputError;
};

// Exit status of every fabatlas binary when it rejects its input.
inline constexpr int kExitBadInput = 2;

}  // namespace fabatlas
