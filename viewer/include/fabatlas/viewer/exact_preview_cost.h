// fabatlas/viewer/exact_preview_cost.h — how long a preview at the slider's
// exact point (not snapped to a sample) is expected to take, so `serve`
// evaluates it only when that fits the page's budget (docs/viewer.md, Exact
// previews).
//
// The estimate for a point is its snapped sample's recorded preview time
// (EncodedPreview::seconds: EvaluateSample with the cache, checks skipped)
// times the median, over the last kWindow exact previews of this design, of
// their measured wall time (evaluate, mesh, encode glTF) divided by their
// snapped sample's recorded time; the ratio is 1 before any exact preview.
// The ratio carries what the sample's time does not: subtrees the cache
// holds for the sample's parameter values but not for the exact ones, and
// meshing and encoding. An estimate over budget is not measured again until
// a point whose sample is cheaper fits.
#pragma once

#include <deque>
#include <mutex>

namespace fabatlas::viewer {

struct ExactPreviewOptions {
  // Wall time an exact preview may be expected to take, seconds (`fabatlas
  // serve --exact-budget-ms`, default 150 ms). 0: every preview snaps.
  double budget_seconds = 0.150;
};

// Thread-safe; O(kWindow) per call.
class ExactPreviewCost {
 public:
  static constexpr int kWindow = 5;

  // Seconds an exact preview is expected to take near a sample whose
  // preview took snapped_seconds.
  double Estimate(double snapped_seconds) const;

  // One exact preview measured: exact_seconds of wall time near a sample
  // whose preview took snapped_seconds. Non-positive times are ignored.
  void Record(double snapped_seconds, double exact_seconds);

 private:
  mutable std::mutex mu_;
  std::deque<double> ratios_;  // most recent last, at most kWindow
};

}  // namespace fabatlas::viewer
