// fabatlas/pipeline/artifact_of.h — the artifact of a job whose sampling
// finished (docs/artifact.md), before its cache (cache_assembly.h AddCache).
//
// The artifact is a pure function of the job bundle, the sampled form and
// the subtrees the samples evaluated (costed by a deterministic model),
// never of measured times, worker count or faults, so the same job always
// publishes the same bytes, in process or on a cluster.
#pragma once

#include <string>

#include "fabatlas/cache/starting_points.h"
#include "fabatlas/sampling/form.h"
#include "fabatlas/sampling/job_file.h"
#include "fabatlas/artifact/artifact.h"
#include "fabatlas/v1/job.pb.h"

namespace fabatlas::pipeline {

// The job's inputs as the artifact stores them.
artifact::JobBundle PlainBundle(const v1::JobBundle& bundle);
// And back (e.g. to protocol::Materialize an artifact's bundle).
v1::JobBundle ProtoBundle(const artifact::JobBundle& bundle);

// The artifact of a job whose sampling finished: manifest (design name and
// hash, code version, sampling parameters, statistics), the form and the
// bundle, and the starting points (AddStartingPoints). No cache: AddCache
// adds it when the samples' subtrees are known.
artifact::Artifact ArtifactOf(const v1::JobBundle& bundle, const std::string& design_name, const sampling::JobFile& job,
                              const sampling::Form& form);

// Fab Forms Sec. 7.4 starting points of the artifact's form
// (cache::ChooseStartingPoints).
void AddStartingPoints(artifact::Artifact& artifact, const cache::StartingPointOptions& options = {});

// "<design name>.fabatlas", with characters other than [A-Za-z0-9._-] as '_'.
std::string ArtifactFileName(const std::string& design_name);

}  // namespace fabatlas::pipeline
