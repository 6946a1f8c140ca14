// The subtrees of a cluster job's valid samples, for its geometry cache plan
// (pipeline::Executor::CacheSubtrees on the cluster).
#pragma once

#include <string>

#include "fabatlas/design/design.h"
#include "fabatlas/pipeline/cache_assembly.h"
#include "fabatlas/sampling/form.h"

namespace fabatlas::storage {
class JobStore;
class BlobStore;
}  // namespace fabatlas::storage

namespace fabatlas::coordinator {

// Every subtree the workers reported for the job's accepted sample results
// (JobStore::Subtrees, SampleSubtreeKeys), the valid samples' roots in
// sample-id order, and geometry from the blobs the workers uploaded; a chosen
// subtree without a blob (its measured time was under the upload threshold)
// is computed here by re-evaluating a valid sample that lists it (geometry is
// deterministic, so the artifact does not depend on which worker measured
// what). The cache plan keeps only subtrees below valid samples' roots, and a
// sample lists every descendant of each subtree it lists (a cache hit is
// recorded with its descendants), so some valid sample always lists a kept
// subtree; one that none gives back is left out of the artifact and counted
// (log event cache_entries_left_out). `grid_of` keeps references to store,
// blobs, design and form.
pipeline::CacheAssembly CollectSubtreesFromStore(storage::JobStore& store, storage::BlobStore& blobs,
                                                 const std::string& job_id, const design::Design& design,
                                                 const sampling::Form& form);

}  // namespace fabatlas::coordinator
