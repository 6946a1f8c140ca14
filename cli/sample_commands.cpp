// fabatlas sample JOB.yaml --out DIR [--threads N] — a precompute job in this
// process: bootstrap grid, adaptive ΔG subdivision (Fab Forms Sec. 5) on a
// local thread pool, then the form, its statistics and validity maps in DIR.
#include <filesystem>
#include <iostream>
#include <memory>

#include "commands.h"
#include "fabatlas/coordinator/publish.h"
#include "fabatlas/protocol/job_bundle.h"
#include "fabatlas/storage/artifact.h"
#include "fabatlas/design/design.h"
#include "fabatlas/precompute/design_evaluator.h"
#include "fabatlas/precompute/form_outputs.h"
#include "fabatlas/sampling/adaptive_sampler.h"
#include "fabatlas/sampling/executor.h"
#include "fabatlas/sampling/job_file.h"

namespace fabatlas::cli {

namespace {

struct SampleArgs {
  std::string job, out;
  int threads = 0;
  bool cache = false;
};

void Sample(const SampleArgs& args) {
  // An OpenSCAD model runs as the job of its import, written under DIR/model.
  const std::string job_path = JobOrModel(args.job, (std::filesystem::path(args.out) / "model").string());
  sampling::JobFile job = sampling::ReadJobFile(job_path);
  design::Design design = design::LoadDesign(job.design_path);
  const cache::CacheOptions cache_options = coordinator::CacheOptionsOf(job);  // bad input before the work
  int threads = args.threads > 0 ? args.threads : job.threads;
  sampling::DesignSpace space = precompute::DesignSpaceOf(design, job.subdivisions);
  precompute::DesignSampleEvaluator evaluator(design);
  sampling::ThreadPoolExecutor executor(threads);
  sampling::SamplingSummary summary = sampling::SampleDesignSpace(space, evaluator, executor, job.sampling);
  const bool form_json = precompute::WritesFormJson(job, summary.form.samples.size());
  precompute::WriteFormOutputs(design, summary, args.out, form_json);
  // The same artifact the cluster publishes for this job (docs/artifact.md).
  const std::string artifact = coordinator::ArtifactFileName(design.name);
  storage::Artifact published = coordinator::ArtifactOf(protocol::MakeJobBundle(job_path), design.name, job, summary.form);
  if (args.cache || coordinator::WantsCache(job)) {
    // The geometry cache (Fab Forms Sec. 6): re-evaluate the valid samples'
    // geometry, keep every subtree as a blob, plan and store H_opt / H_rfree.
    const std::filesystem::path blobs = std::filesystem::path(args.out) / "subtree-blobs";
    coordinator::CacheAssembly assembly = coordinator::CollectSubtreesInProcess(design, summary.form, blobs);
    assembly.options = cache_options;
    assembly.store_rfree = coordinator::StoresRfree(job);
    assembly.stream_geometry = true;  // one entry's geometry in memory at a time
    const auto added = coordinator::AddCache(published, assembly);
    const auto written = storage::WriteArtifact(published, std::filesystem::path(args.out) / artifact);
    std::filesystem::remove_all(blobs);
    const auto& c = published.manifest.cache;
    std::cout << "cache " << c.strategy << ": H_TOP " << c.top_entries << " subtrees / " << c.top_bytes
              << " B, H_opt " << c.opt_entries << " / " << c.opt_bytes << " B, H_rfree " << c.rfree_entries << " / "
              << c.rfree_bytes << " B (" << written.cache_entries << " entries stored)\n";
    if (added.exact.solved())
      std::cout << "cache plan: exact worst case " << added.exact.worst_seconds() << " s ("
                << (added.exact.optimal() ? "optimal" : "time limit") << "), H_opt gap "
                << 100.0 * added.exact.gap() << " %\n";
  } else {
    storage::WriteArtifact(published, std::filesystem::path(args.out) / artifact);
  }
  std::cout << precompute::Table3Row(design, summary.statistics) << "\n";
  std::cout << "wrote " << args.out << "/" << artifact << (form_json ? ", form.json" : "")
            << ", statistics.json and validity maps\n";
}

}  // namespace

void AddSampleCommands(CLI::App& app, int& exit_code) {
  (void)exit_code;
  auto args = std::make_shared<SampleArgs>();
  auto* sample = app.add_subcommand("sample", "run a precompute job in this process on a thread pool");
  sample->add_option("job", args->job, "job YAML (docs/job-format.md) or OpenSCAD model (.scad)")->required();
  sample->add_option("--out", args->out, "output directory")->required();
  sample->add_option("--threads", args->threads, "threads (default: the job file's)");
  sample->add_flag("--cache", args->cache,
                   "plan the geometry cache and store it in the artifact even without a cache strategy in the job file (re-evaluates the valid samples' geometry)");
  sample->callback([args] { Sample(*args); });
}

}  // namespace fabatlas::cli
