// A job as a worker holds it (see job_cache.h).
#include "job_cache.h"

#include <algorithm>

#include "fabatlas/design/design.h"
#include "fabatlas/protocol/job_bundle.h"
#include "fabatlas/protocol/solid_blob.h"
#include "fabatlas/sampling/job_file.h"

namespace fabatlas::worker {

std::shared_ptr<JobContext> LoadJobContext(const v1::JobBundle& bundle, const std::filesystem::path& dir,
                                           std::int64_t memory_mb, UploadBlob upload) {
  auto ctx = std::make_shared<JobContext>();
  auto files = protocol::Materialize(bundle, dir);
  ctx->min_subtree_seconds =
      sampling::ParseJobFile(bundle.job_file(), files.job_file.string()).cache_min_subtree_seconds;
  precompute::DesignEvaluatorOptions options;
  const std::size_t budget = static_cast<std::size_t>(memory_mb) << 20;
  const std::size_t geometry = budget / 2, level_sets_at_least = budget / 16;
  options.subtree_memory_bytes = budget / 8;
  options.min_subtree_seconds = ctx->min_subtree_seconds;
  options.confine_model_files = true;  // the bundle is all an evaluation reads
  ctx->shelf.SetBudget(budget / 16 * 5);
  ctx->subtree_uploads.SetBudget(budget / 16);
  ctx->upload = std::move(upload);
  JobContext* job = ctx.get();
  options.solid_memory_budget = [job, geometry, level_sets_at_least] {
    // job->evaluator is set before the first evaluation remembers a solid.
    const std::size_t held = job->shelf.bytes() + job->evaluator->subtree_bytes();
    return std::max(level_sets_at_least, held < geometry ? geometry - held : 0);
  };
  options.on_solid_dropped = [job](const sampling::PointKey& key, const geometry::Solid& solid) {
    if (!job->shelf.Holds(key)) job->shelf.Put(key, protocol::SolidBlobOf(solid));
  };
  options.on_subtree_computed = [job](const std::string& key, const geometry::Solid& solid, double seconds) {
    {
      std::lock_guard lock(job->mu);
      job->last_seconds[key] = seconds;
    }
    if (seconds >= job->min_subtree_seconds) job->subtree_uploads.Computed(key, solid);
  };
  ctx->evaluator =
      std::make_unique<precompute::DesignSampleEvaluator>(design::LoadDesign(files.design_file), std::move(options));
  return ctx;
}

void UploadReusedSubtrees(JobContext& ctx, const std::vector<design::SubtreeRecord>& records) {
  std::vector<std::string> keys;
  keys.reserve(records.size());
  for (const design::SubtreeRecord& rec : records) keys.push_back(rec.key);
  for (auto& [key, solid] : ctx.subtree_uploads.Used(keys))
    ctx.subtree_uploads.Uploaded(key, ctx.upload(protocol::SolidBlobOf(solid)));
}

std::optional<std::string> HeldSolidBlob(JobContext& ctx, const sampling::PointKey& key) {
  if (ctx.evaluator)
    if (auto solid = ctx.evaluator->RememberedSolid(key)) return protocol::SolidBlobOf(*solid);
  return ctx.shelf.Get(key);
}

}  // namespace fabatlas::worker
