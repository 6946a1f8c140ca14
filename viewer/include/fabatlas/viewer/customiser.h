// fabatlas/viewer/customiser.h — the runtime over one computed form (Fab Forms,
// Sec. 7): validity lookups, snapping, properties with material cost/weight,
// starting points and previews evaluated with cached subtrees.
//
// A Customiser owns what it was loaded from (CustomiserSource) and is
// read-only afterwards; lookups are thread-safe, Preview() is too (each call
// evaluates the design on its own; the subtree cache is read-only).
#pragma once

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <list>
#include <map>
#include <mutex>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "fabatlas/design/design.h"
#include "fabatlas/design/evaluate_sample.h"
#include "fabatlas/design/subtree_cache.h"
#include "fabatlas/geometry/solid.h"
#include "fabatlas/sampling/form.h"
#include "fabatlas/sampling/job_file.h"
#include "fabatlas/viewer/exact_preview_cost.h"
#include "fabatlas/viewer/leaf_corners.h"
#include "fabatlas/viewer/preview_cache.h"
#include "fabatlas/viewer/property_limits.h"
#include "fabatlas/viewer/snap.h"
#include "fabatlas/viewer/valid_region.h"

namespace fabatlas::viewer {

// Everything the runtime needs from a computed job.
struct CustomiserSource {
  std::string name;  // shown to users (the design's name)
  sampling::Form form;
  std::optional<design::Design> design;       // needed for previews
  std::vector<sampling::Material> materials;  // cost/weight table
  std::vector<std::int64_t> starting_points;  // sample ids; empty: computed by cache::ChooseStartingPoints
  // Cached subtree geometry by cache key (design::SubtreeRecord::key), with
  // the root compute time t_i in seconds (Fab Forms Sec. 6).
  std::map<std::string, std::pair<geometry::Solid, double>> cache;
  std::string cache_name = "none";  // e.g. "H_opt", "H_rfree", "none"
  // Where the artifact's job bundle was written for evaluation (removed with
  // the Customiser); empty when the design came from the file system.
  std::filesystem::path bundle_dir;
};

// Which subtrees of an artifact's geometry cache previews load (Fab Forms
// Sec. 6 / Fig. 14): the chosen cache H_opt, the redundancy-free H_rfree, or
// none (every preview evaluates the whole tree).
enum class CacheChoice { kOpt, kRfree, kNone };

// A published artifact (artifact/artifact.h, docs/artifact.md): its form,
// starting points, the chosen cache entries and, from its job bundle, the
// design (written to a fresh scratch directory so mesh and OpenSCAD files
// resolve) and the job file's materials. Throws InputError naming the file
// for anything unreadable or inconsistent.
CustomiserSource LoadArtifact(const std::filesystem::path& artifact, CacheChoice cache = CacheChoice::kOpt);

// A run's output directory as `fabatlas run/sample --out DIR` writes it
// (DIR/form.json) plus the job file that produced it (design and materials).
// No cache entries: previews evaluate the whole tree. Throws InputError
// naming the file for a missing or malformed form.json / job / design, or a
// form whose dimensions differ from the design's exposed parameters.
CustomiserSource LoadRunDirectory(const std::filesystem::path& out_dir, const std::filesystem::path& job_file);

// Weight and cost of one sample in one material (Fab Forms Sec. 7.2).
struct MaterialReadout {
  std::string name;
  double weight_g = 0;  // volume_mm3 / 1000 * density
  double cost = 0;      // weight_g / 1000 * price_per_kg
};
std::vector<MaterialReadout> MaterialReadouts(double volume_mm3, const std::vector<sampling::Material>& materials);

struct PreviewResult {
  std::int64_t sample = -1;  // -1: evaluated at a point (PreviewAt)
  bool valid = false;        // the evaluation's verdict (constraints and geometry; checks skipped)
  std::string failure;
  geometry::Solid solid;
  double seconds = 0;  // wall time of EvaluateSample (constraints and tree; checks skipped)
  int subtrees = 0, cache_hits = 0;
  // An OpenSCAD model's bodies and colour regions (design::Part; empty for
  // other designs): the preview's glb shows them in their colours.
  std::vector<design::Part> parts;
};

// The glb of a preview: its parts with their materials when it has several
// or a coloured one (artifact::PartsToGlb), else the solid's surface
// (artifact::SolidPreviewGlb); normals split at creases for exact meshes.
std::string PreviewGlbBytes(const PreviewResult& preview);

// A preview for a point u (Customiser::PreviewGlbAt): the design at exactly u
// or u's snapped sample, and which.
struct PointPreview {
  std::shared_ptr<const EncodedPreview> preview;  // the glTF sent
  bool exact = false;                             // true: evaluated at exactly u; false: the snapped sample's
  std::int64_t sample = -1;                       // u's snapped sample (the preview's when !exact)
  std::vector<double> u;                          // the point shown: u itself, or the snapped sample's
  double seconds = 0;                             // exact: this preview's wall time (evaluate, mesh, encode);
                                                  // snapped: the sample's recorded evaluation time
  double estimate_seconds = 0;                    // what an exact preview was expected to take (ExactPreviewCost)
  std::string fallback;    // why snapped though exact was asked: "budget" or "failed"; else empty
  bool cache_hit = false;  // snapped: served from the preview cache
};

class Customiser {
 public:
  explicit Customiser(CustomiserSource source, PreviewCacheOptions preview_cache = {},
                      ExactPreviewOptions exact_preview = {});
  const PreviewCacheOptions& preview_cache_options() const { return preview_options_; }
  ~Customiser();
  Customiser(const Customiser&) = delete;  // the cache refers into source_
  Customiser& operator=(const Customiser&) = delete;

  const CustomiserSource& source() const { return source_; }
  const sampling::Form& form() const { return source_.form; }
  const sampling::DesignSpace& space() const { return space_; }
  int dimension_count() const { return space_.dimension_count(); }
  const std::vector<std::int64_t>& starting_points() const { return starting_points_; }

  // The form's leaf corner table (leaf_corners.h), built once here; it fits
  // every LimitedForm too.
  const LeafCorners& corners() const { return corners_; }

  bool IsValid(const std::vector<double>& u) const { return IsValidPoint(source_.form, space_, corners_, u); }
  std::vector<Stretch> Stretches(const std::vector<double>& u, int dimension) const {
    return LineStretches(source_.form, space_, corners_, u, dimension);
  }
  std::optional<Snap> SnapTo(const std::vector<double>& u) const { return SnapToValidSample(source_.form, space_, u); }
  // The sample's recorded properties (Fab Forms P_F) and, when it has a
  // "volume" property, its weight and cost per material.
  std::vector<MaterialReadout> Materials(std::int64_t sample) const;

  // Evaluates the design at the sample (Fab Forms Sec. 7.3) through the
  // source's subtree cache. Throws InputError when the source has no design.
  // with_cache = false ignores the cache (the "no cache" baseline).
  PreviewResult Preview(std::int64_t sample, bool with_cache = true) const;
  // The same at any point u of the space (one value per parameter, the
  // form's order), with sample = -1. Says nothing of u's validity: the
  // form's checks are not run (valid is the constraints' and geometry's
  // verdict only).
  PreviewResult PreviewAt(const std::vector<double>& u, bool with_cache = true) const;

  // The sample's preview as glTF binary (artifact::MeshToGlb), from the
  // bounded cache of encoded previews (preview_cache.h) or evaluated with
  // Preview() and stored; `hit` says which.
  std::shared_ptr<const EncodedPreview> PreviewGlb(std::int64_t sample, bool* hit = nullptr) const;
  PreviewCache::Stats preview_cache_stats() const { return previews_->stats(); }

  // The preview for a point u whose snapped sample is `snapped`. With
  // exact = true and the expected time of an exact preview
  // (ExactPreviewCost::Estimate of the snapped preview's recorded time)
  // within the budget, the design is evaluated at exactly u through the
  // cache (PreviewAt, not stored in the preview cache) and its time
  // recorded; else, or when that evaluation fails (constraints at exactly
  // u, empty geometry, an error), the snapped sample's PreviewGlb. The
  // caller decides whether u may be shown exactly (the page asks only
  // inside the valid region); validity is never claimed here.
  PointPreview PreviewGlbAt(const std::vector<double>& u, std::int64_t snapped, bool exact) const;
  const ExactPreviewOptions& exact_preview_options() const { return exact_options_; }

  // Fills the preview cache ahead of requests: the starting points, then
  // every valid sample in id order, each evaluated once on the calling
  // thread, until all are cached, the next would exceed the cache's
  // max_bytes (the first preview's size is taken as typical), or `stop`
  // becomes true. Returns the number evaluated. `fabatlas serve` runs it on
  // one background thread, so a shared customiser evaluates each preview
  // at most once while it fits.
  int WarmPreviews(const std::atomic<bool>& stop) const;

  // The form under the user's limits (ApplyLimits; the form itself, shared,
  // when there are none). The last 8 distinct limit sets are kept, so a
  // page moving its sliders under fixed limits copies the form once.
  std::shared_ptr<const sampling::Form> LimitedForm(const std::vector<PropertyLimit>& limits) const;

 private:
  CustomiserSource source_;
  sampling::DesignSpace space_;
  LeafCorners corners_;
  std::vector<std::int64_t> starting_points_;
  std::unique_ptr<design::SubtreeCache> cache_;
  PreviewCacheOptions preview_options_;
  mutable std::mutex limited_mu_;
  mutable std::list<std::pair<std::string, std::shared_ptr<const sampling::Form>>> limited_;  // most recent first
  std::unique_ptr<PreviewCache> previews_;
  ExactPreviewOptions exact_options_;
  mutable ExactPreviewCost exact_cost_;
};

}  // namespace fabatlas::viewer
