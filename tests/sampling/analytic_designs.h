// Analytic test designs for the sampler: validity known in closed form and ΔG
// computed exactly from the geometry (Fab Forms Eq. 2), so tests and benches
// compare against numbers nobody tuned.
#pragma once

#include <algorithm>
#include <atomic>
#include <cmath>
#include <map>
#include <mutex>
#include <numbers>
#include <random>
#include <thread>
#include <vector>

#include "fabatlas/sampling/adaptive_sampler.h"
#include "fabatlas/sampling/executor.h"
#include "fabatlas/sampling/sample_evaluator.h"

namespace fabatlas::sampling::testing {

// ΔG of two coaxial hollow cylinders standing on z = 0 (outer radius R, wall
// t, height h): the intersection is the radial overlap annulus times the
// smaller height, so |A xor B| / |A u B| is exact.
inline double HollowCylinderVolume(double R, double t, double h) {
  const double r = std::max(0.0, R - t);
  return std::numbers::pi * (R * R - r * r) * h;
}
inline double HollowCylinderChange(double R1, double t1, double h1, double R2, double t2, double h2) {
  const double v1 = HollowCylinderVolume(R1, t1, h1), v2 = HollowCylinderVolume(R2, t2, h2);
  const double a = std::max(std::max(0.0, R1 - t1), std::max(0.0, R2 - t2));
  const double b = std::min(R1, R2);
  const double inter = b > a ? std::numbers::pi * (b * b - a * a) * std::min(h1, h2) : 0.0;
  const double uni = v1 + v2 - inter;
  return uni > 0 ? (uni - inter) / uni : 0.0;
}

// A hollow cylinder's sample outcome: invalid with `failure` when it is set,
// else valid with its volume (mm^3) as the property.
inline SampleOutcome HollowCylinderOutcome(const char* failure, double R, double t, double h) {
  SampleOutcome o;
  o.valid = failure == nullptr;
  if (failure)
    o.failure_type = failure;
  else
    o.properties["volume_mm3"] = HollowCylinderVolume(R, t, h);
  return o;
}

// (a) 2-D: outer radius R in [5, 20] mm, wall t in [0.5, 5] mm, height 10 mm.
// Valid iff t >= t_min(R) = 0.5 + 0.01 R^2 (a curved boundary), failure
// "min_thickness". True valid area = 67.5 - 0.01 (20^3 - 5^3) / 3 = 41.25 of
// 67.5, i.e. 61.11 %.
class HollowCylinder2D : public SampleEvaluator {
 public:
  static std::vector<Dimension> Dimensions() {
    return {{"outer_radius", DimensionKind::kReal, 5.0, 20.0, {}}, {"wall", DimensionKind::kReal, 0.5, 5.0, {}}};
  }
  static bool TrulyValid(const std::vector<double>& u) { return u[1] >= 0.5 + 0.01 * u[0] * u[0]; }
  SampleOutcome EvaluateSample(const SamplePoint& p) override {
    return HollowCylinderOutcome(TrulyValid(p.u) ? nullptr : "min_thickness", p.u[0], p.u[1], 10.0);
  }
  double GeometryChange(const SamplePoint& a, const SamplePoint& b) override {
    return HollowCylinderChange(a.u[0], a.u[1], 10.0, b.u[0], b.u[1], 10.0);
  }
};

// (a') 2-D with a material budget: as (a), plus the wall's cross-section
// pi (R^2 - (R - t)^2) must not exceed 150 mm^2 (else "over_budget"), so the
// valid region is the curved sliver between t_min(R) = 0.5 + 0.01 R^2 and
// t_max(R) = R - sqrt(R^2 - 150 / pi): about 25.6 % of the bounded space
// (Fab Forms Table 3's designs range from 3 % to 100 % valid).
class BudgetCylinder2D : public SampleEvaluator {
 public:
  static constexpr double kMaxSection = 150.0;  // mm^2
  static std::vector<Dimension> Dimensions() { return HollowCylinder2D::Dimensions(); }
  static const char* Failure(const std::vector<double>& u) {
    if (u[1] < 0.5 + 0.01 * u[0] * u[0]) return "min_thickness";
    const double r = u[0] - u[1];
    if (std::numbers::pi * (u[0] * u[0] - r * r) > kMaxSection) return "over_budget";
    return nullptr;
  }
  static bool TrulyValid(const std::vector<double>& u) { return Failure(u) == nullptr; }
  SampleOutcome EvaluateSample(const SamplePoint& p) override {
    return HollowCylinderOutcome(Failure(p.u), p.u[0], p.u[1], 10.0);
  }
  double GeometryChange(const SamplePoint& a, const SamplePoint& b) override {
    return HollowCylinderChange(a.u[0], a.u[1], 10.0, b.u[0], b.u[1], 10.0);
  }
};

// (b) 3-D: R in [5, 20], t in [0.5, 5], height h in [10, 60] mm. Valid iff
// t >= 0.5 + R h / 300 (else "min_thickness") and h <= 6 R (else "tips_over").
class HollowCylinder3D : public SampleEvaluator {
 public:
  static std::vector<Dimension> Dimensions() {
    return {{"outer_radius", DimensionKind::kReal, 5.0, 20.0, {}},
            {"wall", DimensionKind::kReal, 0.5, 5.0, {}},
            {"height", DimensionKind::kReal, 10.0, 60.0, {}}};
  }
  static const char* Failure(const std::vector<double>& u) {
    if (u[1] < 0.5 + u[0] * u[2] / 300.0) return "min_thickness";
    if (u[2] > 6.0 * u[0]) return "tips_over";
    return nullptr;
  }
  static bool TrulyValid(const std::vector<double>& u) { return Failure(u) == nullptr; }
  SampleOutcome EvaluateSample(const SamplePoint& p) override {
    return HollowCylinderOutcome(Failure(p.u), p.u[0], p.u[1], p.u[2]);
  }
  double GeometryChange(const SamplePoint& a, const SamplePoint& b) override {
    return HollowCylinderChange(a.u[0], a.u[1], a.u[2], b.u[0], b.u[1], b.u[2]);
  }
};

// Square plate of side 1 + x + y on [0,1]^2, valid iff x + y <= 1.3 ("too_big").
// True valid fraction 1 - 0.7^2 / 2 = 0.755; the region is convex, so every
// all-valid leaf lies inside it and the valid-volume estimate is <= 75.5 %.
class HalfPlane : public SampleEvaluator {
 public:
  static std::vector<Dimension> Dimensions() {
    return {{"x", DimensionKind::kReal, 0.0, 1.0, {}}, {"y", DimensionKind::kReal, 0.0, 1.0, {}}};
  }
  SampleOutcome EvaluateSample(const SamplePoint& p) override {
    SampleOutcome o;
    o.valid = p.u[0] + p.u[1] <= 1.3;
    if (!o.valid) o.failure_type = "too_big";
    return o;
  }
  double GeometryChange(const SamplePoint& a, const SamplePoint& b) override {
    const double sa = 1 + a.u[0] + a.u[1], sb = 1 + b.u[0] + b.u[1];
    return std::abs(sa * sa - sb * sb) / std::max(sa * sa, sb * sb);  // nested squares
  }
};

// Bar of length x in [0, 1] made of material e in {pla, petg, tpu}; valid iff
// x < limit[e] with limits 0.31, 0.57, 0.83 (not on the dyadic grid) ("too_long"). ΔG of two bars = nested
// lengths |x1 - x2| / max(x1, x2).
class MaterialBar : public SampleEvaluator {
 public:
  static std::vector<Dimension> Dimensions() {
    return {{"length", DimensionKind::kReal, 0.0, 1.0, {}},
            {"material", DimensionKind::kEnumerated, 0, 0, {"pla", "petg", "tpu"}}};
  }
  static double Limit(double e) { return e == 0 ? 0.31 : e == 1 ? 0.57 : 0.83; }
  SampleOutcome EvaluateSample(const SamplePoint& p) override {
    SampleOutcome o;
    o.valid = p.u[0] < Limit(p.u[1]);
    if (!o.valid) o.failure_type = "too_long";
    return o;
  }
  double GeometryChange(const SamplePoint& a, const SamplePoint& b) override {
    const double m = std::max(a.u[0], b.u[0]);
    return m > 0 ? std::abs(a.u[0] - b.u[0]) / m : 0.0;
  }
};

// A stack of n + 1 unit blocks (n integer in [0, 10]) with an irrelevant real
// parameter x in [0, 1]; valid iff n <= 6 ("too_tall").
class BlockStack : public SampleEvaluator {
 public:
  static std::vector<Dimension> Dimensions() {
    return {{"x", DimensionKind::kReal, 0.0, 1.0, {}}, {"blocks", DimensionKind::kInteger, 0.0, 10.0, {}}};
  }
  SampleOutcome EvaluateSample(const SamplePoint& p) override {
    SampleOutcome o;
    o.valid = p.u[1] <= 6;
    if (!o.valid) o.failure_type = "too_tall";
    return o;
  }
  double GeometryChange(const SamplePoint& a, const SamplePoint& b) override {
    return std::abs(a.u[1] - b.u[1]) / (std::max(a.u[1], b.u[1]) + 1.0);
  }
};

// Wraps an evaluator: counts calls per point key and records any ΔG request
// that involves a sample the inner evaluator calls invalid.
class CountingEvaluator : public SampleEvaluator {
 public:
  explicit CountingEvaluator(SampleEvaluator& inner) : inner_(inner) {}
  SampleOutcome EvaluateSample(const SamplePoint& p) override {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      ++sample_calls_[p.key];
    }
    return inner_.EvaluateSample(p);
  }
  double GeometryChange(const SamplePoint& a, const SamplePoint& b) override {
    const bool both_valid = inner_.EvaluateSample(a).valid && inner_.EvaluateSample(b).valid;
    std::lock_guard<std::mutex> lock(mutex_);
    ++change_calls_[{a.key, b.key}];
    if (!both_valid) ++invalid_change_requests_;
    return inner_.GeometryChange(a, b);
  }
  std::map<PointKey, int> sample_calls_;
  std::map<std::pair<PointKey, PointKey>, int> change_calls_;
  int invalid_change_requests_ = 0;

 private:
  SampleEvaluator& inner_;
  std::mutex mutex_;
};

// Runs each batch on two threads that take tasks in a seeded random order,
// so completion order differs from task order (and from run to run of seeds).
class ShuffledExecutor : public Executor {
 public:
  explicit ShuffledExecutor(unsigned seed) : rng_(seed) {}
  std::vector<SampleOutcome> RunSampleTasks(const std::vector<SampleTask>& tasks, SampleEvaluator& ev,
                                            std::vector<TaskTiming>* timings) override {
    std::vector<SampleOutcome> out(tasks.size());
    Run(tasks.size(), [&](size_t i) { out[i] = ev.EvaluateSample(tasks[i].point); });
    if (timings) timings->assign(tasks.size(), TaskTiming{});
    return out;
  }
  std::vector<GeometryChangeResult> RunGeometryChangeTasks(const std::vector<GeometryChangeTask>& tasks,
                                                           SampleEvaluator& ev,
                                                           std::vector<TaskTiming>* timings) override {
    std::vector<GeometryChangeResult> out(tasks.size());
    Run(tasks.size(),
        [&](size_t i) { out[i].geometry_change = ev.GeometryChange(tasks[i].point_a, tasks[i].point_b); });
    if (timings) timings->assign(tasks.size(), TaskTiming{});
    return out;
  }

 private:
  template <class F>
  void Run(size_t n, F&& f) {
    std::vector<size_t> order(n);
    for (size_t i = 0; i < n; ++i) order[i] = i;
    std::shuffle(order.begin(), order.end(), rng_);
    std::atomic<size_t> next{0};
    auto work = [&] {
      for (size_t k; (k = next.fetch_add(1)) < n;) f(order[k]);
    };
    std::thread other(work);
    work();
    other.join();
  }
  std::mt19937 rng_;
};

// IoU of the estimated valid region (all-valid leaves) with the true region,
// by Monte Carlo with a fixed seed over the bounded space.
template <class TrulyValid>
double EstimatedRegionIoU(const Form& form, TrulyValid truly_valid, int points = 200000, unsigned seed = 12345) {
  std::mt19937_64 rng(seed);
  std::vector<std::uniform_real_distribution<double>> dist;
  for (const Dimension& d : form.dimensions) dist.emplace_back(d.lo, d.hi);
  long long inter = 0, uni = 0;
  std::vector<double> u(form.dimensions.size());
  const DesignSpace space = form.space();
  for (int i = 0; i < points; ++i) {
    for (size_t d = 0; d < u.size(); ++d) u[d] = dist[d](rng);
    const bool t = truly_valid(u), e = InEstimatedValidRegion(form, space, u);
    inter += t && e;
    uni += t || e;
  }
  return uni ? static_cast<double>(inter) / static_cast<double>(uni) : 1.0;
}

}  // namespace fabatlas::sampling::testing
