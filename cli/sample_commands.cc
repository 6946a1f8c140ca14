// fabatlas sample JOB.yaml --out DIR [--threads N] — a precompute job in this
// process: bootstrap grid, adaptive ΔG subdivision (Fab Forms Sec. 5) on a
// local thread pool, then the form, its statistics and validity maps in DIR.
#include <filesystem>
#include <iostream>
#include <memory>

#include "commands.h"
#include "fabatlas/pipeline/local_executor.h"
#include "fabatlas/pipeline/run_job.h"
#include "fabatlas/precompute/form_outputs.h"

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
  const pipeline::Job job = pipeline::ReadJob(job_path);
  pipeline::LocalExecutorOptions local;
  local.threads = args.threads > 0 ? args.threads : job.file.threads;
  // The geometry cache re-evaluates the valid samples' geometry and keeps
  // every subtree here as a blob until the artifact is written.
  local.scratch_dir = std::filesystem::path(args.out) / "subtree-blobs";
  pipeline::LocalExecutor executor(job.design, local);
  pipeline::RunOptions options;
  options.out_dir = args.out;
  options.cache = args.cache;
  const pipeline::RunSummary run = pipeline::RunJob(job, executor, options);
  if (run.cache) {
    const auto& c = run.cache_manifest;
    std::cout << "cache " << c.strategy << ": H_TOP " << c.top_entries << " subtrees / " << c.top_bytes << " B, H_opt "
              << c.opt_entries << " / " << c.opt_bytes << " B, H_rfree " << c.rfree_entries << " / " << c.rfree_bytes
              << " B (" << run.written.cache_entries << " entries stored)\n";
    if (run.cache_added.exact.solved())
      std::cout << "cache plan: exact worst case " << run.cache_added.exact.worst_seconds() << " s ("
                << (run.cache_added.exact.optimal() ? "optimal" : "time limit") << "), H_opt gap "
                << 100.0 * run.cache_added.exact.gap() << " %\n";
  }
  std::cout << precompute::Table3Row(job.design, run.sampling.statistics) << "\n";
  std::cout << "wrote " << args.out << "/" << run.artifact_file << (run.form_json ? ", form.json" : "")
            << (run.swept_volumes > 0 ? ", swept_volumes.json" : "") << ", statistics.json and validity maps\n";
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
                   "plan the geometry cache and store it in the artifact even without a cache strategy in the job file "
                   "(re-evaluates the valid samples' geometry)");
  sample->callback([args] { Sample(*args); });
}

}  // namespace fabatlas::cli
