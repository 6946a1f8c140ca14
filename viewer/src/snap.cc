#include "fabatlas/viewer/snap.h"

#include <cmath>
#include <limits>

#include "leaf_search.h"

namespace fabatlas::viewer {

double CachedGeometryChange(const sampling::Form& form, std::int64_t a, std::int64_t b) {
  if (a == b) return 0.0;
  const auto it = form.geometry_changes.find({std::min(a, b), std::max(a, b)});
  return it == form.geometry_changes.end() ? 1.0 : it->second;
}

std::optional<Snap> SnapToValidSample(const sampling::Form& form, const sampling::DesignSpace& space,
                                      const std::vector<double>& u) {
  const auto x = internal::KeyCoordinates(space, u);
  if (!x) return std::nullopt;
  const int n = space.dimension_count();
  std::optional<Snap> best;
  for (const internal::LeafHit& hit : internal::LeavesTouching(form, space, *x)) {
    const sampling::FormNode* leaf = hit.node;
    const std::vector<std::int64_t> corners = sampling::CornerSampleIds(form, *leaf);
    std::vector<double> t(n);
    for (int d = 0; d < n; ++d)
      t[d] = ((*x)[d] - static_cast<double>(leaf->lo[d])) / static_cast<double>(leaf->hi[d] - leaf->lo[d]);
    for (size_t c = 0; c < corners.size(); ++c) {
      if (!form.samples[corners[c]].outcome.valid) continue;
      double distance = 0;
      for (int d = 0; d < n; ++d) {
        const double along = std::abs(t[d] - static_cast<double>((c >> d) & 1));
        distance += along * (CachedGeometryChange(form, corners[c], corners[c ^ (size_t{1} << d)]) + 1e-6);
      }
      if (!best || distance < best->distance || (distance == best->distance && corners[c] < best->sample))
        best = Snap{corners[c], distance, true};
    }
  }
  if (best) return best;
  // Fallback: nearest valid sample in normalised parameter space.
  double best_d2 = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < form.samples.size(); ++i) {
    const auto& s = form.samples[i];
    if (!s.outcome.valid) continue;
    double d2 = 0;
    for (int d = 0; d < n; ++d) {
      const double range = static_cast<double>(space.key_hi(d) - space.key_lo(d));
      const double diff = (static_cast<double>(s.key[d]) - (*x)[d]) / range;
      d2 += diff * diff;
    }
    if (d2 < best_d2) {
      best_d2 = d2;
      best = Snap{static_cast<std::int64_t>(i), std::sqrt(d2), false};
    }
  }
  return best;
}

}  // namespace fabatlas::viewer
