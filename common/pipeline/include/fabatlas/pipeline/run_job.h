// fabatlas/pipeline/run_job.h — a precompute job from its files to its
// outputs: the one pipeline that `fabatlas sample` (LocalExecutor) and the
// coordinator's job driver (its remote executor) both run.
//
//   1. the form: sampling::SampleDesignSpace (Fab Forms Sec. 5) over the
//      executor's sample and ΔG tasks;
//   2. form.json, statistics.json, validity maps (precompute::WriteFormOutputs);
//   3. swept volumes of carve_swept nodes (swept_volumes.h), as executor tasks;
//   4. the artifact (artifact_of.h); when the job file asks for a cache (or
//      RunOptions::cache), the subtrees (Executor::CacheSubtrees), the plan
//      (Executor::RunCachePlan) and its entries (cache_assembly.h AddCache);
//   5. <design>.fabatlas (artifact::WriteArtifact), atomically.
// Every output is a pure function of the job and the task results, so the
// same job gives the same bytes on every executor.
#pragma once

#include <filesystem>
#include <string>

#include "fabatlas/design/design.h"
#include "fabatlas/pipeline/cache_assembly.h"
#include "fabatlas/pipeline/executor.h"
#include "fabatlas/sampling/adaptive_sampler.h"
#include "fabatlas/sampling/job_file.h"
#include "fabatlas/artifact/artifact.h"
#include "fabatlas/v1/job.pb.h"

namespace fabatlas::pipeline {

// A job's inputs, loaded.
struct Job {
  v1::JobBundle bundle;    // its bytes: stored in the artifact, its evaluation digest is the design hash
  sampling::JobFile file;  // the job file
  design::Design design;   // the design it names
};

// The job file at `path` (as the user typed it, for messages), its design and
// their bundle (protocol::MakeJobBundle). Throws InputError naming the file.
Job ReadJob(const std::filesystem::path& path);
// A bundle's job, its files written under dir (protocol::Materialize).
// Throws InputError naming the materialized file.
Job JobOfBundle(v1::JobBundle bundle, const std::filesystem::path& dir);

struct RunOptions {
  std::filesystem::path out_dir;  // created when missing
  // Plan a geometry cache even when the job file asks for none
  // (`fabatlas sample --cache`).
  bool cache = false;
};

struct RunSummary {
  sampling::SamplingSummary sampling;
  bool form_json = false;         // form.json was written
  std::string artifact_file;      // its name in out_dir (ArtifactFileName)
  std::size_t swept_volumes = 0;  // carve_swept nodes published
  bool cache = false;             // a cache was planned
  CacheAssemblySummary cache_added;
  artifact::CacheSummary cache_manifest;  // the artifact's manifest.cache
  artifact::ArtifactWriteSummary written;
};

// Runs the job's pipeline (above) on `executor` and writes its outputs into
// options.out_dir. Bad cache options throw InputError before any task runs.
// Throws what the executor throws (the job driver's cancellation included).
RunSummary RunJob(const Job& job, Executor& executor, const RunOptions& options);

}  // namespace fabatlas::pipeline
