// The published artifact of a job (see publish.h).
#include "fabatlas/coordinator/publish.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <yaml-cpp/yaml.h>
#include <set>

#include "fabatlas/design/evaluate_sample.h"
#include "fabatlas/error.h"
#include "fabatlas/geometry/solid.h"
#include "fabatlas/precompute/design_evaluator.h"
#include "fabatlas/storage/blob_store.h"
#include "fabatlas/storage/job_store.h"
#include "fabatlas/storage/glb.h"

#include "fabatlas/protocol/cache_plan.h"
#include "fabatlas/protocol/job_bundle.h"
#include "fabatlas/protocol/solid_blob.h"
#include "fabatlas/protocol/tasks.h"

namespace fabatlas::coordinator {

storage::JobBundle PlainBundle(const v1::JobBundle& bundle) {
  storage::JobBundle b;
  b.job_file_name = bundle.job_file_name();
  b.job_file = bundle.job_file();
  b.design_file_name = bundle.design_file_name();
  b.design_file = bundle.design_file();
  for (const auto& [name, bytes] : bundle.files()) b.files[name] = bytes;
  return b;
}

v1::JobBundle ProtoBundle(const storage::JobBundle& b) {
  v1::JobBundle bundle;
  bundle.set_job_file_name(b.job_file_name);
  bundle.set_job_file(b.job_file);
  bundle.set_design_file_name(b.design_file_name);
  bundle.set_design_file(b.design_file);
  for (const auto& [name, bytes] : b.files) (*bundle.mutable_files())[name] = bytes;
  return bundle;
}

storage::Artifact ArtifactOf(const v1::JobBundle& bundle, const std::string& design_name,
                             const sampling::JobFile& job, const sampling::Form& form) {
  storage::Artifact a;
  a.form = form;
  storage::Manifest& m = a.manifest;
  m.design_name = design_name;
  m.design_hash = protocol::EvaluationDigest(bundle);
  m.code_version = protocol::kCodeVersion;
  m.subdivisions = form.subdivisions;
  m.max_depth = job.sampling.max_depth;
  m.dg_threshold = job.sampling.dg_threshold;
  m.max_samples = job.sampling.max_samples;
  m.statistics = storage::StatisticsOf(form);
  a.bundle = PlainBundle(bundle);
  AddStartingPoints(a);
  return a;
}

v1::CachePlanInput CachePlanInputOf(const CacheAssembly& a) {
  v1::CachePlanInput input;
  for (const auto& s : a.subtrees) {
    v1::CachePlanSubtree* out = input.add_subtrees();
    out->set_key(s.key);
    out->set_op(s.op);
    for (const auto& c : s.children) out->add_children(c);
    out->set_bytes(s.bytes);
    out->set_stored(s.stored);
  }
  for (const auto& r : a.sample_roots) input.add_sample_roots(r);
  *input.mutable_options() = protocol::CachePlanOptionsOf(a.options);
  input.mutable_options()->set_exact_max_variables(a.exact_max_variables);
  input.mutable_options()->set_exact_time_limit_seconds(a.exact_time_limit_seconds);
  return input;
}

CacheAssemblySummary AddCache(storage::Artifact& artifact, const CacheAssembly& a,
                              const v1::CachePlanReport& report) {
  CacheAssemblySummary summary;
  summary.exact = report.exact();
  const cache::CacheOptions& options = a.options;
  storage::CacheSummary& m = artifact.manifest.cache;
  m.strategy = cache::StrategyName(options.strategy);
  m.budget_bytes = options.budget_bytes == std::numeric_limits<std::uint64_t>::max()
                       ? 0
                       : static_cast<std::int64_t>(options.budget_bytes);
  m.threshold_seconds = options.min_seconds;
  m.cost_model = "cache::ModelSubtreeSeconds (docs/cache.md)";
  m.top_entries = report.top().entries();
  m.top_bytes = static_cast<std::int64_t>(report.top().bytes());
  m.opt_entries = report.opt().entries();
  m.opt_bytes = static_cast<std::int64_t>(report.opt().bytes());
  m.rfree_entries = report.rfree().entries();
  m.rfree_bytes = static_cast<std::int64_t>(report.rfree().bytes());

  artifact.cache_curves.clear();
  for (const auto& curve : report.curves())
    for (int step = 0; step < curve.points_size(); ++step) {
      const auto& p = curve.points(step);
      artifact.cache_curves.push_back({curve.strategy(), static_cast<std::int64_t>(step), p.entries(),
                                       static_cast<std::int64_t>(p.bytes()), p.mean_seconds(), p.worst_seconds()});
    }

  artifact.cache.clear();
  artifact.cache_geometry = nullptr;
  // The geometry of an entry: the subtree's grid and its zero iso-surface.
  auto fill = [grid_of = a.grid_of](storage::CacheEntry& e) {
    try {
      e.grid = grid_of ? grid_of(e.key) : std::string();
    } catch (const std::exception&) {
      e.grid.clear();
    }
    if (e.grid.empty()) return false;
    e.glb = storage::MeshToGlb(geometry::Solid::Deserialize(e.grid).ToMesh());
    return true;
  };
  if (a.stream_geometry) artifact.cache_geometry = fill;
  for (const auto& r : report.entries()) {
    if (!r.in_opt() && !a.store_rfree) continue;  // H_rfree beyond H_opt: sizes in the manifest only
    storage::CacheEntry e;
    e.key = r.key();
    e.op = r.op();
    e.children.assign(r.children().begin(), r.children().end());
    e.bytes = r.bytes();
    e.cost_seconds = r.cost_seconds();
    e.in_opt = r.in_opt();
    e.in_rfree = r.in_rfree();
    if (!a.stream_geometry && !fill(e)) {
      ++summary.missing;
      continue;
    }
    artifact.cache.push_back(std::move(e));
    ++summary.entries;
  }
  return summary;
}

CacheAssemblySummary AddCache(storage::Artifact& artifact, const CacheAssembly& assembly) {
  return AddCache(artifact, assembly, protocol::RunCachePlan(CachePlanInputOf(assembly)));
}

cache::CacheOptions CacheOptionsOf(const sampling::JobFile& job) {
  cache::CacheOptions o;
  o.budget_bytes = kDefaultCacheBudgetMb << 20;
  auto it = job.reserved_sections.find("cache");
  if (it == job.reserved_sections.end()) return o;
  const std::string where = job.path + ": cache: ";
  YAML::Node node;
  try {
    node = YAML::Load(it->second);
  } catch (const YAML::Exception& e) {
    throw InputError(where + e.msg);
  }
  if (!node || node.IsNull()) return o;
  if (!node.IsMap()) throw InputError(where + "expected a mapping");
  for (const auto& kv : node) {
    const std::string key = kv.first.as<std::string>();
    try {
      if (key == "strategy") {
        const std::string v = kv.second.as<std::string>();
        if (v == "naive") o.strategy = cache::Strategy::kNaive;
        else if (v == "opt_ave") o.strategy = cache::Strategy::kOptAve;
        else if (v == "opt_max") o.strategy = cache::Strategy::kOptMax;
        else throw InputError(where + "strategy '" + v + "' is not naive, opt_ave or opt_max");
      } else if (key == "budget_mb") {
        const double v = kv.second.as<double>();
        if (!(v > 0) || !std::isfinite(v)) throw InputError(where + "budget_mb must be a positive number");
        o.budget_bytes = static_cast<std::uint64_t>(v * 1024 * 1024);
      } else if (key == "min_subtree_seconds") {
        const double v = kv.second.as<double>();
        if (!(v >= 0) || !std::isfinite(v)) throw InputError(where + "min_subtree_seconds must be >= 0");
        o.min_seconds = v;
      } else if (key == "store_rfree") {
        kv.second.as<bool>();  // read by StoresRfree
      } else {
        throw InputError(where + "unknown key '" + key + "' (strategy, budget_mb, min_subtree_seconds, store_rfree)");
      }
    } catch (const YAML::Exception&) {
      throw InputError(where + "'" + key + "' has the wrong type");
    }
  }
  return o;
}

namespace {

// Serves subtrees computed before (kept in memory up to a budget, else read
// back from the blob store) and keeps every new one as a blob.
class CollectingCache final : public design::SubtreeCache {
 public:
  explicit CollectingCache(storage::BlobStore& blobs) : blobs_(blobs) {}
  std::optional<geometry::Solid> Find(const std::string& key) override {
    std::lock_guard lock(mutex_);
    auto it = digests_.find(key);
    if (it == digests_.end()) return std::nullopt;
    return geometry::Solid::Deserialize(blobs_.Read(it->second));
  }
  void Offer(const std::string& key, const geometry::Solid& solid, double) override {
    {
      std::lock_guard lock(mutex_);
      if (digests_.count(key)) return;
    }
    std::string digest = blobs_.Put(solid.Serialize());
    std::lock_guard lock(mutex_);
    digests_.emplace(key, digest);
  }
  std::string DigestOf(const std::string& key) {
    std::lock_guard lock(mutex_);
    auto it = digests_.find(key);
    return it == digests_.end() ? std::string() : it->second;
  }

 private:
  storage::BlobStore& blobs_;
  std::mutex mutex_;
  std::map<std::string, std::string> digests_;
};

}  // namespace

CacheAssembly CollectSubtreesInProcess(const design::Design& design, const sampling::Form& form,
                                       const std::filesystem::path& blob_dir) {
  auto blobs = std::make_shared<storage::BlobStore>(blob_dir);
  auto collecting = std::make_shared<CollectingCache>(*blobs);
  CacheAssembly a;
  design::EvaluateOptions options;
  options.cache = collecting.get();
  options.keep_solid = false;
  options.run_checks = false;
  for (const auto& sample : form.samples) {
    if (!sample.outcome.valid) continue;
    const design::SampleResult r =
        design::EvaluateSample(design, precompute::DesignPointOf(design, sample.u), options);
    if (r.subtrees.empty()) continue;
    for (const auto& s : r.subtrees)
      a.subtrees.push_back({s.key, s.op, s.children, static_cast<std::int64_t>(s.bytes), true});
    a.sample_roots.push_back(r.subtrees.back().key);
  }
  a.grid_of = [blobs, collecting](const std::string& key) {
    const std::string digest = collecting->DigestOf(key);
    return digest.empty() ? std::string() : blobs->Read(digest);
  };
  return a;
}

namespace {

// Keeps the geometry of one subtree key offered during an evaluation.
class CaptureCache final : public design::SubtreeCache {
 public:
  explicit CaptureCache(std::string key) : key_(std::move(key)) {}
  std::optional<geometry::Solid> Find(const std::string&) override { return std::nullopt; }
  void Offer(const std::string& key, const geometry::Solid& solid, double) override {
    std::lock_guard lock(mutex_);
    if (key == key_ && grid_.empty()) grid_ = solid.Serialize();
  }
  std::string grid() {
    std::lock_guard lock(mutex_);
    return grid_;
  }

 private:
  std::string key_, grid_;
  std::mutex mutex_;
};

sampling::PointKey ParsePointKey(const std::string& text) {
  sampling::PointKey key;
  std::size_t start = 0;
  while (start <= text.size()) {
    std::size_t end = text.find(',', start);
    if (end == std::string::npos) end = text.size();
    key.push_back(std::stoll(text.substr(start, end - start)));
    start = end + 1;
  }
  return key;
}

}  // namespace

bool StoresRfree(const sampling::JobFile& job) {
  CacheOptionsOf(job);  // the section's errors, once
  auto it = job.reserved_sections.find("cache");
  if (it == job.reserved_sections.end()) return false;
  const YAML::Node node = YAML::Load(it->second);
  return node.IsMap() && node["store_rfree"] && node["store_rfree"].as<bool>();
}

bool WantsCache(const sampling::JobFile& job) {
  auto it = job.reserved_sections.find("cache");
  if (it == job.reserved_sections.end()) return false;
  return it->second.find("strategy") != std::string::npos || it->second.find("budget_mb") != std::string::npos;
}

CacheAssembly CollectSubtreesFromStore(storage::JobStore& store, storage::BlobStore& blobs,
                                       const std::string& job_id, const design::Design& design,
                                       const sampling::Form& form) {
  CacheAssembly a;
  auto digests = std::make_shared<std::map<std::string, std::string>>();
  for (const auto& row : store.Subtrees(job_id)) {
    a.subtrees.push_back({row.key, row.op, row.children, row.bytes, true});
    if (!row.blob_digest.empty()) (*digests)[row.key] = row.blob_digest;
  }
  // Valid samples in id order, with the subtree keys each evaluated.
  std::map<std::int64_t, std::vector<std::string>> sample_keys;
  for (const auto& s : store.SampleSubtreeKeys(job_id)) {
    if (s.subtree_keys.empty()) continue;
    auto it = form.sample_ids.find(ParsePointKey(s.point_key));
    if (it == form.sample_ids.end() || !form.samples[it->second].outcome.valid) continue;
    sample_keys.emplace(it->second, s.subtree_keys);
  }
  for (const auto& [id, keys] : sample_keys) a.sample_roots.push_back(keys.back());
  auto samples = std::make_shared<std::map<std::int64_t, std::vector<std::string>>>(std::move(sample_keys));
  a.grid_of = [&blobs, &design, &form, digests, samples](const std::string& key) -> std::string {
    if (auto it = digests->find(key); it != digests->end() && blobs.Contains(it->second))
      return protocol::GridOfBlob(blobs.Read(it->second));  // workers upload zstd frames
    for (const auto& [id, keys] : *samples) {
      if (std::find(keys.begin(), keys.end(), key) == keys.end()) continue;
      CaptureCache capture(key);
      design::EvaluateOptions options;
      options.cache = &capture;
      options.keep_solid = false;
      options.run_checks = false;
      design::EvaluateSample(design, precompute::DesignPointOf(design, form.samples[id].u), options);
      return capture.grid();
    }
    return {};
  };
  return a;
}

void AddStartingPoints(storage::Artifact& artifact, const cache::StartingPointOptions& options) {
  artifact.starting_points.clear();
  for (const auto& p : cache::ChooseStartingPoints(artifact.form, options))
    artifact.starting_points.push_back({p.sample_id, p.component, p.u});
}

std::string ArtifactFileName(const std::string& design_name) {
  std::string name = design_name.empty() ? "design" : design_name;
  for (char& c : name)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '.' && c != '_' && c != '-') c = '_';
  return name + ".fabatlas";
}

}  // namespace fabatlas::coordinator
