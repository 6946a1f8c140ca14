// fabatlas/coordinator/publish.h — the published artifact of a finished job
// (DESIGN.md "Artifact", docs/artifact.md): what the coordinator writes as
// OUT/<design>.fabatlas beside form.json when a job's sampling finishes.
//
// The artifact is a pure function of the job bundle and the sampled form (and
// later the chosen cache), never of measured times, worker count or faults, so
// the same job always publishes the same bytes.
#pragma once

#include <string>

#include "fabatlas/sampling/adaptive_sampler.h"
#include "fabatlas/sampling/job_file.h"
#include "fabatlas/storage/artifact.h"
#include "fabatlas/v1/job.pb.h"

namespace fabatlas::coordinator {

// The job's inputs as the artifact stores them.
storage::JobBundle PlainBundle(const v1::JobBundle& bundle);
// And back (e.g. to protocol::Materialize an artifact's bundle).
v1::JobBundle ProtoBundle(const storage::JobBundle& bundle);

// The artifact of a job whose sampling finished: manifest (design name and
// hash, code version, sampling parameters, statistics), the form and the
// bundle. No cache entries yet (docs/artifact.md: cache.strategy is empty).
storage::Artifact ArtifactOf(const v1::JobBundle& bundle, const std::string& design_name,
                             const sampling::JobFile& job, const sampling::Form& form);

// "<design name>.fabatlas", with characters other than [A-Za-z0-9._-] as '_'.
std::string ArtifactFileName(const std::string& design_name);

}  // namespace fabatlas::coordinator
