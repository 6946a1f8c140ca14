#include "fabatlas/viewer/customiser.h"

#include <atomic>
#include <chrono>
#include <fstream>
#include <sstream>

#include <unistd.h>

#include "fabatlas/cache/starting_points.h"
#include "fabatlas/design/evaluate_sample.h"
#include "fabatlas/error.h"
#include "fabatlas/precompute/design_evaluator.h"
#include "fabatlas/sampling/form_json.h"
#include "fabatlas/artifact/artifact.h"
#include "fabatlas/artifact/glb.h"

namespace fabatlas::viewer {

namespace {

// The source's cache entries, read-only: previews look subtrees up but never
// add to the cache, so every preview costs what the chosen cache H allows.
class FixedSubtreeCache final : public design::SubtreeCache {
 public:
  explicit FixedSubtreeCache(const std::map<std::string, std::pair<geometry::Solid, double>>& entries)
      : entries_(entries) {}
  std::optional<design::CachedSubtree> Find(const std::string& key) override {
    const auto it = entries_.find(key);
    if (it == entries_.end()) return std::nullopt;
    return design::CachedSubtree{it->second.first};
  }
  void Offer(const std::string&, const design::CachedSubtree&, double) override {}

 private:
  const std::map<std::string, std::pair<geometry::Solid, double>>& entries_;
};

std::string ReadText(const std::filesystem::path& path, const std::string& what) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path.string() + ": cannot read " + what);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace

CustomiserSource LoadRunDirectory(const std::filesystem::path& out_dir, const std::filesystem::path& job_file) {
  CustomiserSource source;
  const std::filesystem::path form_path = out_dir / "form.json";
  source.form = sampling::FormFromJson(ReadText(form_path, "the form (run `fabatlas run JOB --out DIR` first)"),
                                       form_path.string());
  const sampling::JobFile job = sampling::ReadJobFile(job_file.string());
  source.materials = job.materials;
  source.design = design::LoadDesign(job.design_path);
  source.name = source.design->name;
  const auto& exposed = source.design->exposed;
  bool same = exposed.size() == source.form.dimensions.size();
  for (size_t i = 0; same && i < exposed.size(); ++i) same = exposed[i].name == source.form.dimensions[i].name;
  if (!same)
    throw InputError(form_path.string() + ": the form's parameters differ from the exposed parameters of " +
                     job.design_path);
  return source;
}

namespace {

// Writes one bundled file under dir; names that would leave it are refused.
void WriteBundled(const std::filesystem::path& dir, const std::string& name, const std::string& bytes,
                  const std::filesystem::path& artifact) {
  const std::filesystem::path rel = std::filesystem::path(name).lexically_normal();
  if (name.empty() || rel.is_absolute() || *rel.begin() == "..")
    throw InputError(artifact.string() + ": bundled file name '" + name + "' leaves the bundle");
  const std::filesystem::path path = dir / rel;
  std::filesystem::create_directories(path.parent_path());
  std::ofstream out(path, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (!out) throw InputError(path.string() + ": cannot write the bundled file");
}

}  // namespace

CustomiserSource LoadArtifact(const std::filesystem::path& artifact, CacheChoice cache) {
  // Metadata only; the chosen cache's geometry is read entry by entry below,
  // so loading holds the form and that cache, never the whole file.
  artifact::Artifact art = artifact::ReadArtifact(artifact, {.load_geometry = false});
  CustomiserSource source;
  source.form = std::move(art.form);
  source.name = art.manifest.design_name;
  for (const auto& p : art.starting_points) source.starting_points.push_back(p.sample_id);

  static std::atomic<int> counter{0};
  source.bundle_dir = std::filesystem::temp_directory_path() /
                      ("fabatlas-serve-" + std::to_string(::getpid()) + "-" + std::to_string(counter++));
  std::filesystem::remove_all(source.bundle_dir);
  const std::filesystem::path design_dir = source.bundle_dir / "design";
  WriteBundled(design_dir, art.bundle.design_file_name, art.bundle.design_file, artifact);
  for (const auto& [name, bytes] : art.bundle.files) WriteBundled(design_dir, name, bytes, artifact);
  source.design =
      design::LoadDesign(design_dir / std::filesystem::path(art.bundle.design_file_name).lexically_normal());
  if (!art.bundle.job_file.empty()) {
    // The job's design path points elsewhere; only its materials matter here.
    source.materials =
        sampling::ParseJobFile(art.bundle.job_file, artifact.string() + ":" + art.bundle.job_file_name).materials;
  }
  const auto& exposed = source.design->exposed;
  bool same = exposed.size() == source.form.dimensions.size();
  for (size_t i = 0; same && i < exposed.size(); ++i) same = exposed[i].name == source.form.dimensions[i].name;
  if (!same) throw InputError(artifact.string() + ": the form's parameters differ from the bundled design's");

  const bool has_cache = !art.manifest.cache.strategy.empty();
  source.cache_name = !has_cache || cache == CacheChoice::kNone ? "none"
                      : cache == CacheChoice::kOpt              ? "H_opt"
                                                                : "H_rfree";
  if (has_cache && cache != CacheChoice::kNone)
    artifact::ReadCacheGeometry(
        artifact, [&](const artifact::CacheEntry& e) { return cache == CacheChoice::kOpt ? e.in_opt : e.in_rfree; },
        [&](artifact::CacheEntry& e) {
          source.cache.emplace(e.key, std::make_pair(geometry::Solid::Deserialize(e.grid), e.cost_seconds));
        });
  return source;
}

std::vector<MaterialReadout> MaterialReadouts(double volume_mm3, const std::vector<sampling::Material>& materials) {
  std::vector<MaterialReadout> out;
  for (const auto& m : materials) {
    MaterialReadout r;
    r.name = m.name;
    r.weight_g = volume_mm3 / 1000.0 * m.density_g_per_cm3;
    r.cost = r.weight_g / 1000.0 * m.price_per_kg;
    out.push_back(r);
  }
  return out;
}

Customiser::Customiser(CustomiserSource source, PreviewCacheOptions preview_cache, ExactPreviewOptions exact_preview)
    : source_(std::move(source)),
      space_(source_.form.space()),
      corners_(source_.form),
      preview_options_(preview_cache),
      previews_(std::make_unique<PreviewCache>(preview_cache)),
      exact_options_(exact_preview) {
  starting_points_ = source_.starting_points;
  if (starting_points_.empty())  // a run directory: the artifact's rule (cache/starting_points.h)
    for (const auto& p : cache::ChooseStartingPoints(source_.form)) starting_points_.push_back(p.sample_id);
  cache_ = std::make_unique<FixedSubtreeCache>(source_.cache);
}

Customiser::~Customiser() {
  if (!source_.bundle_dir.empty()) {
    std::error_code ec;
    std::filesystem::remove_all(source_.bundle_dir, ec);
  }
}

std::vector<MaterialReadout> Customiser::Materials(std::int64_t sample) const {
  const auto& properties = source_.form.samples.at(sample).outcome.properties;
  const auto it = properties.find("volume");
  if (it == properties.end()) return {};
  return MaterialReadouts(it->second, source_.materials);
}

std::string PreviewGlbBytes(const PreviewResult& p) {
  const bool exact = p.solid.boundary() != nullptr;
  bool coloured = false;
  for (const auto& part : p.parts) coloured = coloured || part.coloured;
  if (p.parts.size() < 2 && !coloured) return artifact::SolidPreviewGlb(p.solid.ToMesh(), exact);
  std::vector<artifact::GlbPart> parts;
  for (const auto& part : p.parts) parts.push_back({part.name, &part.mesh, part.coloured, part.rgba});
  return artifact::PartsToGlb(parts, exact);
}

PreviewResult Customiser::Preview(std::int64_t sample, bool with_cache) const {
  PreviewResult out = PreviewAt(source_.form.samples.at(sample).u, with_cache);
  out.sample = sample;
  return out;
}

PreviewResult Customiser::PreviewAt(const std::vector<double>& u, bool with_cache) const {
  if (!source_.design) throw InputError("this form has no design to preview");
  design::EvaluateOptions options;
  options.cache = with_cache ? cache_.get() : nullptr;
  options.run_checks = false;             // the sample was checked during sampling
  options.lookup_before_children = true;  // a cached subtree skips everything below it
  PreviewResult out;
  if (source_.design->tree.op == "openscad") options.parts = &out.parts;  // bodies and colours
  const auto start = std::chrono::steady_clock::now();
  design::SampleResult r =
      design::EvaluateSample(*source_.design, precompute::DesignPointOf(*source_.design, u), options);
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  out.valid = r.valid;
  out.failure = r.failure;
  out.solid = std::move(r.solid);
  out.subtrees = static_cast<int>(r.subtrees.size());
  for (const auto& t : r.subtrees) out.cache_hits += t.from_cache;
  return out;
}

std::shared_ptr<const EncodedPreview> Customiser::PreviewGlb(std::int64_t sample, bool* hit) const {
  return previews_->Get(
      sample,
      [this](std::int64_t id) {
        const PreviewResult p = Preview(id);
        EncodedPreview e;
        e.sample = id;
        e.glb = PreviewGlbBytes(p);
        e.seconds = p.seconds;
        e.subtrees = p.subtrees;
        e.cache_hits = p.cache_hits;
        return e;
      },
      hit);
}

PointPreview Customiser::PreviewGlbAt(const std::vector<double>& u, std::int64_t snapped, bool exact) const {
  PointPreview out;
  out.sample = snapped;
  out.preview = PreviewGlb(snapped, &out.cache_hit);
  out.u = source_.form.samples.at(snapped).u;
  out.seconds = out.preview->seconds;
  out.estimate_seconds = exact_cost_.Estimate(out.preview->seconds);
  if (!exact) return out;
  if (!(exact_options_.budget_seconds > 0) || out.estimate_seconds > exact_options_.budget_seconds) {
    out.fallback = "budget";
    return out;
  }
  const auto start = std::chrono::steady_clock::now();
  try {
    const PreviewResult p = PreviewAt(u);
    if (!p.valid || p.solid.empty()) {
      out.fallback = "failed";
      return out;
    }
    auto e = std::make_shared<EncodedPreview>();
    e->glb = PreviewGlbBytes(p);
    e->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    e->subtrees = p.subtrees;
    e->cache_hits = p.cache_hits;
    exact_cost_.Record(out.preview->seconds, e->seconds);
    out.seconds = e->seconds;
    out.preview = std::move(e);
    out.exact = true;
    out.u = u;
    out.cache_hit = false;
  } catch (const std::exception&) {
    out.fallback = "failed";  // the snapped sample's preview stands
  }
  return out;
}

int Customiser::WarmPreviews(const std::atomic<bool>& stop) const {
  if (!source_.design || preview_options_.max_bytes == 0) return 0;
  std::vector<std::int64_t> order = starting_points_;
  for (std::size_t id = 0; id < source_.form.samples.size(); ++id)
    if (source_.form.samples[id].outcome.valid) order.push_back(static_cast<std::int64_t>(id));
  int evaluated = 0;
  std::size_t typical = 0;
  for (const std::int64_t id : order) {
    if (stop.load()) break;
    if (typical && previews_->stats().bytes + typical > preview_options_.max_bytes) break;
    bool hit = false;
    const auto p = PreviewGlb(id, &hit);
    if (!typical) typical = p->glb.size();
    evaluated += !hit;
  }
  return evaluated;
}

std::shared_ptr<const sampling::Form> Customiser::LimitedForm(const std::vector<PropertyLimit>& limits) const {
  if (limits.empty()) return std::shared_ptr<const sampling::Form>(std::shared_ptr<void>(), &source_.form);
  std::ostringstream key;
  key.precision(17);
  for (const auto& l : limits) key << l.property << '\n' << l.min << '\n' << l.max << '\n';
  {
    std::lock_guard<std::mutex> lock(limited_mu_);
    for (auto it = limited_.begin(); it != limited_.end(); ++it)
      if (it->first == key.str()) {
        limited_.splice(limited_.begin(), limited_, it);
        return limited_.front().second;
      }
  }
  auto form = std::make_shared<const sampling::Form>(ApplyLimits(source_.form, limits, source_.materials));
  std::lock_guard<std::mutex> lock(limited_mu_);
  limited_.emplace_front(key.str(), form);
  if (limited_.size() > 8) limited_.pop_back();
  return form;
}

}  // namespace fabatlas::viewer
