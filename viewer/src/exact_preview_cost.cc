#include "fabatlas/viewer/exact_preview_cost.h"

#include <algorithm>
#include <vector>

namespace fabatlas::viewer {

double ExactPreviewCost::Estimate(double snapped_seconds) const {
  std::vector<double> r;
  {
    std::lock_guard<std::mutex> lock(mu_);
    r.assign(ratios_.begin(), ratios_.end());
  }
  if (r.empty()) return snapped_seconds;
  std::sort(r.begin(), r.end());
  const std::size_t m = r.size() / 2;
  const double median = r.size() % 2 ? r[m] : (r[m - 1] + r[m]) / 2;
  return snapped_seconds * median;
}

void ExactPreviewCost::Record(double snapped_seconds, double exact_seconds) {
  if (!(snapped_seconds > 0) || !(exact_seconds > 0)) return;
  std::lock_guard<std::mutex> lock(mu_);
  ratios_.push_back(exact_seconds / snapped_seconds);
  if (static_cast<int>(ratios_.size()) > kWindow) ratios_.pop_front();
}

}  // namespace fabatlas::viewer
