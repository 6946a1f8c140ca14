// solve/stopping_rules.h (internal to fabatlas_assembly) — when the solve's
// Ceres runs stop early: step 1's stall prevention (FabHacks Sec. 4.3.2) and
// step 2's window on the motion.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <deque>
#include <vector>

#include <ceres/ceres.h>

#include "kinematics.h"

namespace fabatlas::assembly::internal {

// Stall prevention (FabHacks, 4.3.2): linear regression of log10(cost) over a
// sliding window; abort when it decreases slower than `slope` per iteration.
class StallCallback : public ceres::IterationCallback {
 public:
  StallCallback(int window, double slope, double floor) : window_(window), slope_(slope), floor_(floor) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& s) override {
    const double c = 2 * s.cost;
    if (c < floor_) return ceres::SOLVER_TERMINATE_SUCCESSFULLY;
    logs_.push_back(std::log10(std::max(c, 1e-300)));
    if (static_cast<int>(logs_.size()) > window_) logs_.pop_front();
    if (static_cast<int>(logs_.size()) < window_) return ceres::SOLVER_CONTINUE;
    double mx = 0, my = 0;
    const int n = static_cast<int>(logs_.size());
    for (int i = 0; i < n; ++i) mx += i, my += logs_[i];
    mx /= n;
    my /= n;
    double sxy = 0, sxx = 0;
    for (int i = 0; i < n; ++i) sxy += (i - mx) * (logs_[i] - my), sxx += (i - mx) * (i - mx);
    return sxy / sxx > -slope_ ? ceres::SOLVER_ABORT : ceres::SOLVER_CONTINUE;
  }

 private:
  int window_;
  double slope_, floor_;
  std::deque<double> logs_;
};

// Step 2 stopping rule on the motion itself: LM creeps along a soft mode of
// a hanging chain with steps of ~1e-6 (its Gauss-Newton model has no
// curvature along a swing), so after `window` iterations in which no
// parameter moved by more than `motion` (mm or degrees) the relaxation is
// converged for every purpose here (Ceres reports USER_SUCCESS). The
// reproducibility test (relaxation_test) bounds what this leaves.
class RelaxationWindow : public ceres::IterationCallback {
 public:
  RelaxationWindow(const std::vector<Block>& blocks, int window, double motion)
      : blocks_(blocks), window_(window), motion_(motion), last_(blocks) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& it) override {
    if (window_ <= 0 || it.iteration == 0 || it.iteration % window_ != 0) return ceres::SOLVER_CONTINUE;
    double moved = 0;
    for (size_t b = 0; b < blocks_.size(); ++b)
      for (int i = 0; i < internal::kParamBlock; ++i) moved = std::max(moved, std::abs(blocks_[b][i] - last_[b][i]));
    last_ = blocks_;
    if (std::getenv("FABATLAS_ASSEMBLY_DEBUG"))
      std::fprintf(stderr, "  relaxation it %d: cost %.12e, largest motion over the window %.3e\n", it.iteration,
                   it.cost, moved);
    return moved < motion_ ? ceres::SOLVER_TERMINATE_SUCCESSFULLY : ceres::SOLVER_CONTINUE;
  }

 private:
  const std::vector<Block>& blocks_;
  int window_;
  double motion_;
  std::vector<Block> last_;
};

}  // namespace fabatlas::assembly::internal
