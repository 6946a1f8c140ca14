#include "fabatlas/design/constraint_solve.h"

#include <ceres/ceres.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <functional>
#include <optional>

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
        case Relation::kEqual:
          out[k] = diff;
          break;
        case Relation::kLessEqual:
          out[k] = std::max(0.0, diff);
          break;
        case Relation::kGreaterEqual:
          out[k] = std::min(0.0, diff);
          break;
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

// The violation of constraint k given lhs - rhs (as ConstraintResidual).
double Violation(Relation relation, double diff) {
  switch (relation) {
    case Relation::kEqual:
      return std::abs(diff);
    case Relation::kLessEqual:
      return std::max(0.0, diff);
    case Relation::kGreaterEqual:
      return std::max(0.0, -diff);
  }
  return std::abs(diff);
}

// The decision of SolveConstraints from definitions (constraint_solve.h), or
// nullopt when they leave the point undecided.
std::optional<ConstraintSolveSummary> SolveByDefinitions(const Design& d, const Point& u,
                                                         const ConstraintSolveOptions& options) {
  const std::size_t n = d.mutables.size(), m = d.constraints.size();
  Scope scope(ParameterNames(d));
  for (const auto& [name, value] : u) scope.Set(name, value);
  std::map<std::string, std::size_t> variable;
  for (std::size_t i = 0; i < n; ++i) variable[d.mutables[i].name] = i;

  std::vector<Expression> lhs, rhs;
  std::vector<std::vector<std::size_t>> reads(m);  // variables read by either side of constraint k
  struct Definition {
    std::size_t constraint, defined;
    const Expression* value;
    std::vector<std::size_t> reads;  // variables the value reads
  };
  std::vector<Definition> definitions;
  lhs.reserve(m);
  rhs.reserve(m);
  auto variables_of = [&](const Expression& e) {
    std::vector<std::size_t> out;
    for (const std::string& name : e.Names())
      if (auto it = variable.find(name); it != variable.end()) out.push_back(it->second);
    return out;
  };
  auto trim = [](const std::string& t) {
    const auto a = t.find_first_not_of(" \t"), b = t.find_last_not_of(" \t");
    return a == std::string::npos ? std::string() : t.substr(a, b - a + 1);
  };
  for (std::size_t k = 0; k < m; ++k) {
    const Constraint& c = d.constraints[k];
    lhs.emplace_back(c.lhs, scope, c.place);
    rhs.emplace_back(c.rhs, scope, c.place);
    const auto l = variables_of(lhs[k]), r = variables_of(rhs[k]);
    reads[k] = l;
    reads[k].insert(reads[k].end(), r.begin(), r.end());
    if (c.relation != Relation::kEqual) continue;
    auto side = [&](const std::string& text, const Expression* other, const std::vector<std::size_t>& other_reads) {
      auto it = variable.find(trim(text));
      if (it == variable.end()) return;
      for (std::size_t j : other_reads)
        if (j == it->second) return;
      definitions.push_back({k, it->second, other, other_reads});
    };
    side(c.lhs, &rhs[k], r);
    side(c.rhs, &lhs[k], l);
  }

  // The first-order bound on how far `f` moves when the variables it reads
  // move by their e_j: sum_j |df/dx_j| e_j (central differences).
  std::vector<double> x(n, 0.0), e(n, 0.0);
  std::vector<bool> known(n, false), defining(m, false);
  auto spread = [&](const std::function<double()>& f, const std::vector<std::size_t>& of) {
    double sum = 0;
    for (std::size_t j : of) {
      const double h = 1e-6 * std::max(1.0, std::abs(x[j]));
      const std::string& name = d.mutables[j].name;
      scope.Set(name, x[j] + h);
      const double up = f();
      scope.Set(name, x[j] - h);
      const double down = f();
      scope.Set(name, x[j]);
      sum += std::abs(up - down) / (2 * h) * e[j];
    }
    return sum;
  };

  // Follow the definitions from the exposed values.
  for (bool progress = true; progress;) {
    progress = false;
    for (const Definition& def : definitions) {
      if (known[def.defined] || defining[def.constraint]) continue;
      bool ready = true;
      for (std::size_t j : def.reads) ready = ready && known[j];
      if (!ready) continue;
      const double value = def.value->Evaluate();
      if (!std::isfinite(value)) return std::nullopt;
      x[def.defined] = value;
      scope.Set(d.mutables[def.defined].name, value);
      e[def.defined] = options.tolerance + spread([&] { return def.value->Evaluate(); }, def.reads);
      if (!std::isfinite(e[def.defined])) return std::nullopt;
      known[def.defined] = defining[def.constraint] = true;
      progress = true;
    }
  }

  bool all_known = true, inside = true, holds = true, unsat = false;
  for (std::size_t i = 0; i < n; ++i) {
    if (!known[i]) {
      all_known = false;
      continue;
    }
    const double excess = std::max({d.mutables[i].min - x[i], x[i] - d.mutables[i].max, 0.0});
    inside = inside && excess == 0;
    unsat = unsat || excess > options.definition_safety * e[i];
  }
  std::vector<bool> decidable(m, false);
  for (std::size_t k = 0; k < m; ++k) {
    bool ready = true;
    for (std::size_t j : reads[k]) ready = ready && known[j];
    if (!ready) continue;
    decidable[k] = true;
    const Relation relation = d.constraints[k].relation;
    const double miss = Violation(relation, lhs[k].Evaluate() - rhs[k].Evaluate());
    if (!std::isfinite(miss)) return std::nullopt;
    holds = holds && miss <= options.tolerance;
    if (defining[k] || miss <= options.tolerance) continue;
    const double allowed = options.tolerance + spread([&] { return lhs[k].Evaluate() - rhs[k].Evaluate(); }, reads[k]);
    unsat = unsat || miss > options.definition_safety * allowed;
  }

  ConstraintSolveSummary s;
  s.by_definitions = true;
  for (const auto& [name, value] : u) s.values[name] = value;
  if (!unsat && !(all_known && inside && holds)) return std::nullopt;
  if (unsat) {  // report the violations with x* clamped into the bounds
    for (std::size_t i = 0; i < n; ++i) {
      x[i] = known[i] ? std::clamp(x[i], d.mutables[i].min, d.mutables[i].max) : d.mutables[i].default_value;
      scope.Set(d.mutables[i].name, x[i]);
    }
    for (std::size_t k = 0; k < m; ++k) {
      if (!decidable[k]) continue;
      const double miss = Violation(d.constraints[k].relation, lhs[k].Evaluate() - rhs[k].Evaluate());
      if (miss > s.max_violation) {
        s.max_violation = miss;
        s.worst_constraint = d.constraints[k].text;
      }
    }
  }
  s.satisfiable = !unsat;
  for (std::size_t i = 0; i < n; ++i) s.values[d.mutables[i].name] = x[i];
  return s;
}

}  // namespace

ConstraintSolveSummary SolveConstraints(const Design& d, const Point& u, const ConstraintSolveOptions& options) {
  auto start = std::chrono::steady_clock::now();
  if (options.use_definitions && !d.mutables.empty() && !d.constraints.empty())
    if (auto decided = SolveByDefinitions(d, u, options)) {
      decided->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      return *decided;
    }
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
