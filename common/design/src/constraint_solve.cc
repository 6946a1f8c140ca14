#include "fabatlas/design/constraint_solve.h"

#include <ceres/ceres.h>

#include <chrono>
#include <cmath>

#include "expression.h"

namespace fabatlas::design {
namespace {

// Residual block: every constraint's violation, then the weighted distance of
// each mutable parameter from its default. Derivatives by central differences
// (the expressions are muparser programs, not templated code).
class ConstraintResidual : public ceres::CostFunction {
 public:
  ConstraintResidual(const Design& d, const Point& u, double least_change_weight)
      : design_(d), scope_(ParameterNames(d)), weight_(least_change_weight) {
    for (const auto& [name, value] : u) scope_.Set(name, value);
    for (const auto& c : d.constraints) {
      lhs_.emplace_back(c.lhs, scope_, c.place);
      rhs_.emplace_back(c.rhs, scope_, c.place);
    }
    set_num_residuals(static_cast<int>(d.constraints.size() + (weight_ > 0 ? d.mutables.size() : 0)));
    mutable_parameter_block_sizes()->push_back(static_cast<int>(d.mutables.size()));
  }

  // Violations at x (mutable values), one per constraint.
  void Violations(const double* x, double* out) const {
    for (std::size_t i = 0; i < design_.mutables.size(); ++i) scope_.Set(design_.mutables[i].name, x[i]);
    for (std::size_t k = 0; k < design_.constraints.size(); ++k) {
      double diff = lhs_[k].Evaluate() - rhs_[k].Evaluate();
      switch (design_.constraints[k].relation) {
        case Relation::kEqual: out[k] = diff; break;
        case Relation::kLessEqual: out[k] = std::max(0.0, diff); break;
        case Relation::kGreaterEqual: out[k] = std::min(0.0, diff); break;
      }
      if (!std::isfinite(out[k])) out[k] = 1e6;
    }
  }

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    const std::size_t n = design_.mutables.size(), m = design_.constraints.size();
    const double* x = parameters[0];
    auto all = [&](const double* at, double* out) {
      Violations(at, out);
      if (weight_ > 0)
        for (std::size_t i = 0; i < n; ++i) {
          const auto& v = design_.mutables[i];
          double scale = std::max(1.0, std::abs(v.default_value));
          out[m + i] = weight_ * (at[i] - v.default_value) / scale;
        }
    };
    all(x, residuals);
    if (jacobians && jacobians[0]) {
      const int rows = num_residuals();
      std::vector<double> xp(x, x + n), rp(rows), rm(rows);
      for (std::size_t j = 0; j < n; ++j) {
        double h = 1e-6 * std::max(1.0, std::abs(x[j]));
        xp[j] = x[j] + h;
        all(xp.data(), rp.data());
        xp[j] = x[j] - h;
        all(xp.data(), rm.data());
        xp[j] = x[j];
        for (int r = 0; r < rows; ++r) jacobians[0][r * n + j] = (rp[r] - rm[r]) / (2 * h);
      }
    }
    return true;
  }

 private:
  const Design& design_;
  mutable Scope scope_;
  std::vector<Expression> lhs_, rhs_;
  double weight_;
};

void Solve(const Design& d, const Point& u, double weight, std::vector<double>& x, int max_iterations) {
  ceres::Problem problem;
  auto* cost = new ConstraintResidual(d, u, weight);
  problem.AddResidualBlock(cost, nullptr, x.data());
  for (std::size_t i = 0; i < d.mutables.size(); ++i) {
    problem.SetParameterLowerBound(x.data(), static_cast<int>(i), d.mutables[i].min);
    problem.SetParameterUpperBound(x.data(), static_cast<int>(i), d.mutables[i].max);
  }
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_QR;
  options.max_num_iterations = max_iterations;
  options.function_tolerance = 1e-14;
  options.gradient_tolerance = 1e-14;
  options.parameter_tolerance = 1e-12;
  options.num_threads = 1;
  options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
}

}  // namespace

ConstraintSolveSummary SolveConstraints(const Design& d, const Point& u, const ConstraintSolveOptions& options) {
  auto start = std::chrono::steady_clock::now();
  ConstraintSolveSummary s;
  std::vector<double> x;
  for (const auto& m : d.mutables) x.push_back(m.default_value);

  if (!d.mutables.empty() && !d.constraints.empty()) {
    Solve(d, u, options.least_change_weight, x, options.max_iterations);
    Solve(d, u, 0.0, x, options.max_iterations);
  }

  ConstraintResidual check(d, u, 0.0);
  std::vector<double> v(d.constraints.size());
  check.Violations(x.data(), v.data());
  for (std::size_t k = 0; k < v.size(); ++k) {
    if (std::abs(v[k]) > s.max_violation) {
      s.max_violation = std::abs(v[k]);
      s.worst_constraint = d.constraints[k].text;
    }
  }
  s.satisfiable = s.max_violation <= options.tolerance;
  for (const auto& [name, value] : u) s.values[name] = value;
  for (std::size_t i = 0; i < d.mutables.size(); ++i) s.values[d.mutables[i].name] = x[i];
  s.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return s;
}

}  // namespace fabatlas::design
