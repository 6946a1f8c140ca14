// The large-deflection elastica of a tip-loaded cantilever, the reference of
// the FEM bending tests (bending_test.cc, static_solve_test.cc).
#pragma once

#include <array>
#include <cmath>

namespace fabatlas::fem {

// The elastica of a cantilever (clamped at s = 0, inextensible, length 1)
// under a dead transverse tip load with alpha = P L^2 / (E I):
// theta'' = -alpha cos(theta), theta(0) = 0, theta'(1) = 0, solved by
// shooting on theta'(0) (bisection, RK4 with 4000 steps). Returns the tip
// deflection v/L = int sin(theta) ds and shortening u/L = 1 - int cos(theta).
struct Elastica {
  double v, u;
};
inline Elastica ElasticaTip(double alpha) {
  auto shoot = [alpha](double k0, Elastica* tip) {
    const int n = 4000;
    const double h = 1.0 / n;
    double th = 0, k = k0, x = 0, y = 0;
    auto f = [alpha](double t, double kk) {
      return std::array<double, 4>{kk, -alpha * std::cos(t), std::cos(t), std::sin(t)};
    };
    for (int i = 0; i < n; ++i) {
      const auto a = f(th, k);
      const auto b = f(th + 0.5 * h * a[0], k + 0.5 * h * a[1]);
      const auto c = f(th + 0.5 * h * b[0], k + 0.5 * h * b[1]);
      const auto d = f(th + h * c[0], k + h * c[1]);
      th += h / 6 * (a[0] + 2 * b[0] + 2 * c[0] + d[0]);
      k += h / 6 * (a[1] + 2 * b[1] + 2 * c[1] + d[1]);
      x += h / 6 * (a[2] + 2 * b[2] + 2 * c[2] + d[2]);
      y += h / 6 * (a[3] + 2 * b[3] + 2 * c[3] + d[3]);
    }
    if (tip) *tip = {y, 1 - x};
    return k;  // theta'(1), zero at the solution
  };
  double lo = 0, hi = alpha;  // theta'(0) = alpha * (horizontal arm) / L <= alpha
  for (int i = 0; i < 100; ++i) {
    const double mid = 0.5 * (lo + hi);
    (shoot(mid, nullptr) > 0 ? hi : lo) = mid;
  }
  Elastica tip;
  shoot(0.5 * (lo + hi), &tip);
  return tip;
}

}  // namespace fabatlas::fem
