// A job as a worker holds it: its design's evaluator, the subtrees it
// uploads, its shelf of root solids. One per job bundle digest, loaded on
// the job's first lease (task_execution.cc ContextFor).
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "fabatlas/design/evaluate_sample.h"
#include "fabatlas/precompute/design_evaluator.h"
#include "fabatlas/v1/job.pb.h"
#include "solid_shelf.h"
#include "subtree_uploads.h"

namespace fabatlas::worker {

struct JobContext {
  std::unique_ptr<precompute::DesignSampleEvaluator> evaluator;
  std::string error;                 // set when the job could not be loaded
  double min_subtree_seconds = 0.1;  // job file cache.min_subtree_seconds
  std::mutex mu;
  // Subtree key -> seconds its root took when this worker last computed it
  // (cache hits report 0; tasks.proto SubtreeRecord.seconds wants this).
  std::map<std::string, double> last_seconds;
  // The subtree geometry waiting for its key's second use, and the digests
  // of the blobs uploaded (UploadReusedSubtrees).
  SubtreeUploads subtree_uploads;
  std::function<std::string(const std::string& bytes)> upload;  // as LoadJobContext was given it
  // Warnings of the model's evaluation (OpenSCAD's rules where input is
  // odd) already written to this worker's log: each once per job, not per
  // sample.
  std::set<std::string> logged_warnings;
  SolidShelf shelf;
};

// Uploads bytes as a blob; its digest, or "" when the upload failed.
using UploadBlob = std::function<std::string(const std::string& bytes)>;

// The job of a bundle, its files written under dir (protocol::Materialize),
// with the memory budget of WorkerOptions::memory_mb (MiB) split as
// worker.h documents: half of it for geometry, shared by the subtree cache
// (at most 1/8), root solids compressed on the shelf (at most 5/16; a level
// set is compressed onto it when the evaluator's memory drops it, not
// before) and root solids as level sets in the evaluator's memory (at least
// 1/16, and whatever the other two leave). The subtree cache keeps every
// subtree the evaluator computes whose root took at least the job file's
// cache.min_subtree_seconds (faster ones cost more memory than computing
// them again saves); the same subtrees wait in subtree_uploads (sharing
// the cache's memory, at most 1/16 beyond it) for their key's second use,
// when UploadReusedSubtrees uploads them with `upload`. Throws InputError
// for a job that does not load (the job file or design's one-line message).
std::shared_ptr<JobContext> LoadJobContext(const v1::JobBundle& bundle, const std::filesystem::path& dir,
                                           std::int64_t memory_mb, UploadBlob upload);

// Counts the uses of one evaluation's subtree records on this worker and
// uploads, with the job's `upload`, the geometry of each key at its second
// use (subtree_uploads.h; tasks.proto SubtreeRecord.blob_digest). Call after
// the evaluation and before reporting its records, so a reported digest
// names a finished blob; blocks for the uploads, holding no lock.
void UploadReusedSubtrees(JobContext& ctx, const std::vector<design::SubtreeRecord>& records);

// The root solid of the valid sample at `key` as blob bytes
// (protocol/solid_blob.h), if this worker holds it: compressed now from the
// evaluator's memory, else from the shelf. For sharing (worker.proto
// ShareSolids).
std::optional<std::string> HeldSolidBlob(JobContext& ctx, const sampling::PointKey& key);

}  // namespace fabatlas::worker
