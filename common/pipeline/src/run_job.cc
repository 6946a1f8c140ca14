// A precompute job from its files to its outputs (see run_job.h).
#include "fabatlas/pipeline/run_job.h"

#include "fabatlas/pipeline/artifact_of.h"
#include "fabatlas/pipeline/cache_options.h"
#include "fabatlas/pipeline/swept_volumes.h"
#include "fabatlas/precompute/design_evaluator.h"
#include "fabatlas/precompute/form_outputs.h"
#include "fabatlas/protocol/job_bundle.h"

namespace fabatlas::pipeline {

Job ReadJob(const std::filesystem::path& path) {
  Job job;
  job.file = sampling::ReadJobFile(path.string());
  job.design = design::LoadDesign(job.file.design_path);
  job.bundle = protocol::MakeJobBundle(path);
  return job;
}

Job JobOfBundle(v1::JobBundle bundle, const std::filesystem::path& dir) {
  Job job;
  const protocol::MaterializedBundle files = protocol::Materialize(bundle, dir);
  job.file = sampling::ParseJobFile(bundle.job_file(), files.job_file.string());
  job.design = design::LoadDesign(files.design_file);
  job.bundle = std::move(bundle);
  return job;
}

RunSummary RunJob(const Job& job, Executor& executor, const RunOptions& options) {
  // Bad input before the work.
  const bool wants_cache = options.cache || WantsCache(job.file);
  const cache::CacheOptions cache_options = CacheOptionsOf(job.file);
  const bool store_rfree = StoresRfree(job.file);

  RunSummary summary;
  // 1. The form (Fab Forms Sec. 5).
  const sampling::DesignSpace space = precompute::DesignSpaceOf(job.design, job.file.subdivisions);
  precompute::DesignSampleEvaluator evaluator(job.design);
  summary.sampling = sampling::SampleDesignSpace(space, evaluator, executor, job.file.sampling);
  executor.SamplingFinished();
  const sampling::Form& form = summary.sampling.form;

  // 2. Form outputs.
  summary.form_json = precompute::WritesFormJson(job.file, form.samples.size());
  precompute::WriteFormOutputs(job.design, summary.sampling, options.out_dir, summary.form_json);

  // 3. Swept volumes.
  const std::vector<SweptVolumeTask> swept = SweptVolumeTasks(job.design, space);
  if (!swept.empty()) WriteSweptVolumes(space, swept, executor.RunSweptVolumeTasks(swept), options.out_dir);
  summary.swept_volumes = swept.size();

  // 4. The artifact (docs/artifact.md), with the geometry cache (Fab Forms
  // Sec. 6) when asked for.
  artifact::Artifact artifact = ArtifactOf(job.bundle, job.design.name, job.file, form);
  if (wants_cache) {
    CacheAssembly assembly = executor.CacheSubtrees(form);
    assembly.options = cache_options;
    assembly.store_rfree = store_rfree;
    assembly.stream_geometry = true;  // one entry's geometry in memory at a time
    summary.cache = true;
    summary.cache_added = AddCache(artifact, assembly, executor.RunCachePlan(CachePlanInputOf(assembly)));
    summary.cache_manifest = artifact.manifest.cache;
    // 5. Written while assembly.grid_of still serves the entries' geometry.
    summary.artifact_file = ArtifactFileName(job.design.name);
    summary.written = artifact::WriteArtifact(artifact, options.out_dir / summary.artifact_file);
    return summary;
  }
  summary.artifact_file = ArtifactFileName(job.design.name);
  summary.written = artifact::WriteArtifact(artifact, options.out_dir / summary.artifact_file);
  return summary;
}

}  // namespace fabatlas::pipeline
