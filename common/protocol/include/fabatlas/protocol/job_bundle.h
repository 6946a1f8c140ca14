// fabatlas/protocol/job_bundle.h — a job file with its design and the files
// the design references, as one content-addressed message (v1::JobBundle).
#pragma once

#include <filesystem>
#include <string>

#include "fabatlas/v1/job.pb.h"

namespace fabatlas::protocol {

// Reads the job file, the design it names and every file a node argument of
// the design (or of one of its objects) names that exists relative to the
// design (meshes, .scad files, prototype programs), including files up to two
// directories above it; the design's file name then keeps that many of its
// parent directories ("designs/sofa_bunk.yaml") so references still resolve.
// Throws InputError (one line naming the file) when a file is unreadable or
// the job file is invalid.
v1::JobBundle MakeJobBundle(const std::filesystem::path& job_file);

// Canonical bytes of a bundle (deterministic protobuf serialization).
std::string BundleBytes(const v1::JobBundle& bundle);
// Digest of what evaluation depends on: the design file and its files (not
// the sampling options), the input of every task key.
std::string EvaluationDigest(const v1::JobBundle& bundle);

struct MaterializedBundle {
  std::filesystem::path job_file;     // DIR/job/<job file name>
  std::filesystem::path design_file;  // DIR/design/<design file name>
};
// Writes the bundle's files under dir (created). Paths that would leave dir
// ("..", absolute) are an InputError.
MaterializedBundle Materialize(const v1::JobBundle& bundle, const std::filesystem::path& dir);

}  // namespace fabatlas::protocol
