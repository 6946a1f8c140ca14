#include "fabatlas/design/constraint_solve.h"

#include <ceres/ceres.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
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

// An equality constraint "v = expr" that defines the mutable variable v from
// expr, which does not read v.
struct Definition {
  std::size_t constraint, defined;
  const Expression* value;
  std::vector<std::size_t> reads;  // variables the value reads
};

// What the definitions followed from a point say about it.
struct DefinitionVerdict {
  bool all_known = true;        // every mutable variable was defined
  bool inside = true;           // every defined one lies within its bounds
  bool holds = true;            // every decidable constraint holds within tolerance
  bool unsat = false;           // a bound or constraint is missed by more than the error bound allows
  std::vector<bool> decidable;  // constraint k reads only defined variables
};

std::string Trimmed(const std::string& t) {
  const auto a = t.find_first_not_of(" \t"), b = t.find_last_not_of(" \t");
  return a == std::string::npos ? std::string() : t.substr(a, b - a + 1);
}

// Deciding a point by definitions (constraint_solve.h): the constraints read
// in the point's scope, the definitions among them, and the values x and
// first-order error bounds e of the mutable variables defined so far.
class DefinitionSolve {
 public:
  DefinitionSolve(const Design& d, const Point& u)
      : d_(d), n_(d.mutables.size()), m_(d.constraints.size()), scope_(ParameterNames(d)), reads_(m_) {
    for (const auto& [name, value] : u) scope_.Set(name, value);
    for (std::size_t i = 0; i < n_; ++i) variable_[d.mutables[i].name] = i;
    lhs_.reserve(m_);  // definitions point into lhs_ and rhs_
    rhs_.reserve(m_);
    for (std::size_t k = 0; k < m_; ++k) ReadConstraint(k);
    x_.assign(n_, 0.0);
    e_.assign(n_, 0.0);
    known_.assign(n_, false);
    defining_.assign(m_, false);
  }
  DefinitionSolve(const DefinitionSolve&) = delete;
  DefinitionSolve& operator=(const DefinitionSolve&) = delete;

  // Follows the definitions from the exposed values, each as soon as the
  // variables it reads are known; false when a value or its error bound is
  // not finite.
  bool FollowDefinitions(double tolerance) {
    for (bool progress = true; progress;) {
      progress = false;
      for (const Definition& def : definitions_) {
        if (known_[def.defined] || defining_[def.constraint]) continue;
        bool ready = true;
        for (std::size_t j : def.reads) ready = ready && known_[j];
        if (!ready) continue;
        const double value = def.value->Evaluate();
        if (!std::isfinite(value)) return false;
        x_[def.defined] = value;
        scope_.Set(d_.mutables[def.defined].name, value);
        e_[def.defined] = tolerance + Spread([&] { return def.value->Evaluate(); }, def.reads);
        if (!std::isfinite(e_[def.defined])) return false;
        known_[def.defined] = defining_[def.constraint] = true;
        progress = true;
      }
    }
    return true;
  }

  // The bounds and constraints checked at the defined values; nullopt when
  // a constraint's violation is not finite.
  std::optional<DefinitionVerdict> Judge(const ConstraintSolveOptions& options) {
    DefinitionVerdict v;
    for (std::size_t i = 0; i < n_; ++i) {
      if (!known_[i]) {
        v.all_known = false;
        continue;
      }
      const double excess = std::max({d_.mutables[i].min - x_[i], x_[i] - d_.mutables[i].max, 0.0});
      v.inside = v.inside && excess == 0;
      v.unsat = v.unsat || excess > options.definition_safety * e_[i];
    }
    v.decidable.assign(m_, false);
    for (std::size_t k = 0; k < m_; ++k) {
      bool ready = true;
      for (std::size_t j : reads_[k]) ready = ready && known_[j];
      if (!ready) continue;
      v.decidable[k] = true;
      const double miss = Violation(d_.constraints[k].relation, Difference(k));
      if (!std::isfinite(miss)) return std::nullopt;
      v.holds = v.holds && miss <= options.tolerance;
      if (defining_[k] || miss <= options.tolerance) continue;
      const double allowed = options.tolerance + Spread([&] { return Difference(k); }, reads_[k]);
      v.unsat = v.unsat || miss > options.definition_safety * allowed;
    }
    return v;
  }

  // The decision: the defined values (u's exposed ones beside them); when
  // unsatisfiable, the worst violation with the values clamped into their
  // bounds (undefined ones at their defaults).
  ConstraintSolveSummary Summary(const Point& u, const DefinitionVerdict& v) {
    ConstraintSolveSummary s;
    s.by_definitions = true;
    for (const auto& [name, value] : u) s.values[name] = value;
    if (v.unsat) {
      for (std::size_t i = 0; i < n_; ++i) {
        x_[i] = known_[i] ? std::clamp(x_[i], d_.mutables[i].min, d_.mutables[i].max) : d_.mutables[i].default_value;
        scope_.Set(d_.mutables[i].name, x_[i]);
      }
      for (std::size_t k = 0; k < m_; ++k) {
        if (!v.decidable[k]) continue;
        const double miss = Violation(d_.constraints[k].relation, Difference(k));
        if (miss > s.max_violation) {
          s.max_violation = miss;
          s.worst_constraint = d_.constraints[k].text;
        }
      }
    }
    s.satisfiable = !v.unsat;
    for (std::size_t i = 0; i < n_; ++i) s.values[d_.mutables[i].name] = x_[i];
    return s;
  }

 private:
  std::vector<std::size_t> VariablesOf(const Expression& e) const {
    std::vector<std::size_t> out;
    for (const std::string& name : e.Names())
      if (auto it = variable_.find(name); it != variable_.end()) out.push_back(it->second);
    return out;
  }

  // Both sides of constraint k, the variables they read, and the
  // definitions an equality gives.
  void ReadConstraint(std::size_t k) {
    const Constraint& c = d_.constraints[k];
    lhs_.emplace_back(c.lhs, scope_, c.place);
    rhs_.emplace_back(c.rhs, scope_, c.place);
    const auto l = VariablesOf(lhs_[k]), r = VariablesOf(rhs_[k]);
    reads_[k] = l;
    reads_[k].insert(reads_[k].end(), r.begin(), r.end());
    if (c.relation != Relation::kEqual) return;
    AddDefinition(k, c.lhs, &rhs_[k], r);
    AddDefinition(k, c.rhs, &lhs_[k], l);
  }

  // When `side` is a variable's name alone and `other` does not read it,
  // constraint k defines that variable as `other`.
  void AddDefinition(std::size_t k, const std::string& side, const Expression* other,
                     const std::vector<std::size_t>& other_reads) {
    auto it = variable_.find(Trimmed(side));
    if (it == variable_.end()) return;
    for (std::size_t j : other_reads)
      if (j == it->second) return;
    definitions_.push_back({k, it->second, other, other_reads});
  }

  // lhs - rhs of constraint k at the scope's current values.
  double Difference(std::size_t k) const { return lhs_[k].Evaluate() - rhs_[k].Evaluate(); }

  // The first-order bound on how far `f` moves when the variables it reads
  // move by their e_j: sum_j |df/dx_j| e_j (central differences).
  double Spread(const std::function<double()>& f, const std::vector<std::size_t>& of) {
    double sum = 0;
    for (std::size_t j : of) {
      const double h = 1e-6 * std::max(1.0, std::abs(x_[j]));
      const std::string& name = d_.mutables[j].name;
      scope_.Set(name, x_[j] + h);
      const double up = f();
      scope_.Set(name, x_[j] - h);
      const double down = f();
      scope_.Set(name, x_[j]);
      sum += std::abs(up - down) / (2 * h) * e_[j];
    }
    return sum;
  }

  const Design& d_;
  const std::size_t n_, m_;  // mutable variables, constraints
  Scope scope_;
  std::map<std::string, std::size_t> variable_;  // mutable variable index by name
  std::vector<Expression> lhs_, rhs_;
  std::vector<std::vector<std::size_t>> reads_;  // variables read by either side of constraint k
  std::vector<Definition> definitions_;
  std::vector<double> x_, e_;
  std::vector<bool> known_, defining_;  // variable i defined; constraint k used as its definition
};

// The decision of SolveConstraints from definitions (constraint_solve.h), or
// nullopt when they leave the point undecided.
std::optional<ConstraintSolveSummary> SolveByDefinitions(const Design& d, const Point& u,
                                                         const ConstraintSolveOptions& options) {
  DefinitionSolve solve(d, u);
  if (!solve.FollowDefinitions(options.tolerance)) return std::nullopt;
  const std::optional<DefinitionVerdict> v = solve.Judge(options);
  if (!v) return std::nullopt;
  if (!v->unsat && !(v->all_known && v->inside && v->holds)) return std::nullopt;
  return solve.Summary(u, *v);
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
