// Koo et al. Sec. 6: two stages of constrained least squares (Eq. 4), solved
// with Ceres by an augmented Lagrangian over equality constraints, with a
// bounded slack s >= 0 for every inequality g >= 0 (g - s = 0).
#include "fabatlas/prototype/solve.h"

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cmath>
#include <memory>
#include <set>

#include <ceres/ceres.h>

#include "model.h"

namespace fabatlas::prototype {
namespace {

using internal::Affine;
using Clock = std::chrono::steady_clock;

struct Con {
  std::unique_ptr<ceres::CostFunction> f;  // one residual g(x), one parameter block x
  bool eq = true;
  int group = 0;
  std::string label;
};

struct Nlp {
  int n = 0;
  Eigen::VectorXd target, weight, lower, upper;
  std::vector<Con> cons;
  std::vector<std::string> groups;
};

class AffineCost : public ceres::CostFunction {
 public:
  AffineCost(const Affine& f, int n) : f_(f) {
    set_num_residuals(1);
    mutable_parameter_block_sizes()->push_back(n);
    n_ = n;
  }
  bool Evaluate(double const* const* p, double* r, double** j) const override {
    r[0] = f_.c;
    for (const auto& [i, v] : f_.a) r[0] += v * p[0][i];
    if (j && j[0]) {
      std::fill(j[0], j[0] + n_, 0.0);
      for (const auto& [i, v] : f_.a) j[0][i] = v;
    }
    return true;
  }

 private:
  Affine f_;
  int n_;
};

// Augmented-Lagrangian residual (Powell-Hestenes-Rockafellar): equality
// sqrt(mu) (g + lambda/mu); inequality g >= 0: sqrt(mu) max(0, lambda/mu - g).
class ConResidual : public ceres::CostFunction {
 public:
  ConResidual(const Con& c, int n, const double* mu, const double* lambda) : c_(c), n_(n), mu_(mu), lambda_(lambda) {
    set_num_residuals(1);
    mutable_parameter_block_sizes()->push_back(n);
  }
  bool Evaluate(double const* const* p, double* r, double** j) const override {
    double g = 0;
    double* jg[1] = {j ? j[0] : nullptr};
    if (!c_.f->Evaluate(p, &g, j && j[0] ? jg : nullptr)) return false;
    double sm = std::sqrt(*mu_);
    double scale = sm;
    if (c_.eq) {
      r[0] = sm * (g + *lambda_ / *mu_);
    } else {
      double v = *lambda_ / *mu_ - g;
      r[0] = v > 0 ? sm * v : 0.0;
      scale = v > 0 ? -sm : 0.0;
    }
    if (j && j[0])
      for (int i = 0; i < n_; ++i) j[0][i] *= scale;
    return true;
  }

 private:
  const Con& c_;
  int n_;
  const double* mu_;
  const double* lambda_;
};

class DeviationCost : public ceres::CostFunction {
 public:
  DeviationCost(const Nlp& nlp) : nlp_(nlp) {
    set_num_residuals(nlp.n);
    mutable_parameter_block_sizes()->push_back(nlp.n);
  }
  bool Evaluate(double const* const* p, double* r, double** j) const override {
    for (int i = 0; i < nlp_.n; ++i) r[i] = std::sqrt(nlp_.weight[i]) * (p[0][i] - nlp_.target[i]);
    if (j && j[0]) {
      std::fill(j[0], j[0] + nlp_.n * nlp_.n, 0.0);
      for (int i = 0; i < nlp_.n; ++i) j[0][i * nlp_.n + i] = std::sqrt(nlp_.weight[i]);
    }
    return true;
  }

 private:
  const Nlp& nlp_;
};

double G(const Con& c, const Eigen::VectorXd& x) {
  double g = 0;
  const double* p[1] = {x.data()};
  c.f->Evaluate(p, &g, nullptr);
  return g;
}

double Violation(const Con& c, const Eigen::VectorXd& x) {
  double g = G(c, x);
  return c.eq ? std::abs(g) : std::max(0.0, -g);
}

struct Outcome {
  Eigen::VectorXd x;
  double violation = 0;
};

// Minimises deviation (unless feasibility_only) subject to the constraints of
// the active groups, from x0.
Outcome Run(const Nlp& nlp, const std::vector<bool>& active, bool feasibility_only, const Eigen::VectorXd& x0,
            double tolerance) {
  Outcome out;
  out.x = x0;
  std::vector<int> idx;
  for (std::size_t i = 0; i < nlp.cons.size(); ++i)
    if (active[nlp.cons[i].group]) idx.push_back(static_cast<int>(i));
  std::vector<double> lambda(idx.size(), 0.0);
  double mu = feasibility_only ? 1.0 : 100.0;
  auto max_violation = [&]() {
    double v = 0;
    for (int i : idx) v = std::max(v, Violation(nlp.cons[i], out.x));
    return v;
  };
  double prev = 1e300;
  for (int outer = 0; outer < (feasibility_only ? 3 : 40); ++outer) {
    ceres::Problem::Options po;
    po.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    ceres::Problem problem(po);
    std::vector<std::unique_ptr<ceres::CostFunction>> owned;
    double* x = out.x.data();
    problem.AddParameterBlock(x, nlp.n);
    if (!feasibility_only) {
      owned.push_back(std::make_unique<DeviationCost>(nlp));
      problem.AddResidualBlock(owned.back().get(), nullptr, x);
    }
    for (std::size_t k = 0; k < idx.size(); ++k) {
      const Con& c = nlp.cons[idx[k]];
      owned.push_back(std::make_unique<ConResidual>(c, nlp.n, &mu, &lambda[k]));
      problem.AddResidualBlock(owned.back().get(), nullptr, x);
    }
    if (problem.NumResidualBlocks() == 0) break;
    for (int i = 0; i < nlp.n; ++i) {
      if (std::isfinite(nlp.lower[i])) problem.SetParameterLowerBound(x, i, nlp.lower[i]);
      if (std::isfinite(nlp.upper[i])) problem.SetParameterUpperBound(x, i, nlp.upper[i]);
    }
    ceres::Solver::Options o;
    o.linear_solver_type = ceres::DENSE_QR;
    o.max_num_iterations = 200;
    o.function_tolerance = 1e-16;
    o.gradient_tolerance = 1e-16;
    o.parameter_tolerance = 1e-14;
    o.logging_type = ceres::SILENT;
    o.num_threads = 1;
    ceres::Solver::Summary s;
    ceres::Solve(o, &problem, &s);
    if (std::getenv("FABATLAS_PROTOTYPE_DEBUG"))
      std::fprintf(stderr, "outer %d mu %g: %s cost %g viol %g\n", outer, mu, s.BriefReport().c_str(), s.final_cost,
                   max_violation());
    double v = max_violation();
    if (v < tolerance * 1e-2) break;
    if (feasibility_only) continue;
    for (std::size_t k = 0; k < idx.size(); ++k) {
      const Con& c = nlp.cons[idx[k]];
      double g = G(c, out.x);
      lambda[k] = c.eq ? lambda[k] + mu * g : std::max(0.0, lambda[k] - mu * g);
    }
    if (v > 0.25 * prev) mu = std::min(mu * 10, 1e12);
    prev = v;
  }
  out.violation = max_violation();
  return out;
}

// Feasible from any of `starts`? Returns the best.
Outcome Feasibility(const Nlp& nlp, const std::vector<bool>& active, const std::vector<Eigen::VectorXd>& starts,
                    double tolerance) {
  Outcome best;
  best.violation = 1e300;
  for (const auto& s : starts) {
    Outcome o = Run(nlp, active, true, s, tolerance);
    if (o.violation < best.violation) best = o;
    if (best.violation <= tolerance) break;
  }
  return best;
}

// Deletion filter: an irreducible infeasible set of groups.
void Explain(const Nlp& nlp, const std::vector<Eigen::VectorXd>& starts, double tolerance, SolveSummary& s) {
  std::vector<bool> active(nlp.groups.size(), true);
  for (std::size_t g = 0; g < nlp.groups.size(); ++g) {
    active[g] = false;
    if (Feasibility(nlp, active, starts, tolerance).violation <= tolerance) active[g] = true;
  }
  Outcome o = Feasibility(nlp, active, starts, tolerance);
  for (std::size_t g = 0; g < nlp.groups.size(); ++g)
    if (active[g]) s.conflicts.push_back(nlp.groups[g]);
  for (const Con& c : nlp.cons) {
    if (!active[c.group]) continue;
    double v = Violation(c, o.x);
    if (v > tolerance) {
      char buf[64];
      std::snprintf(buf, sizeof buf, " (off by %.3g mm)", v);
      s.violated.push_back(c.label + buf);
    }
  }
}

// ---- Stage 2: double pivots (Sec. 5.6) ------------------------------------

struct Plane2 {
  Eigen::Matrix3d R;
  Eigen::Vector3d t;
};

struct PivotGeometry {
  Eigen::Vector3d ua, ea, ub, eb;  // pivot points (base) and offset directions
  std::vector<Plane2> rel;         // child -> parent frame, per configuration (rel[0] = base)
  std::array<double, 6> box_a, box_b;
  int u = 0, v = 1;  // in-plane axes
  double scale = 100;
};

template <typename T>
using V3 = Eigen::Matrix<T, 3, 1>;

template <typename T>
V3<T> Apply(const Plane2& p, const V3<T>& x) {
  return p.R.cast<T>() * x + p.t.cast<T>();
}

// (x2 - x1) . (xm - xB) = 0 between configurations i and j.
struct PositionFunctor {
  const PivotGeometry* g;
  int i, j;
  template <typename T>
  bool operator()(const T* ab, T* r) const {
    V3<T> ua = g->ua.cast<T>() + ab[0] * g->ea.cast<T>();
    V3<T> xb = g->ub.cast<T>() + ab[1] * g->eb.cast<T>();
    V3<T> x1 = Apply(g->rel[i], ua), x2 = Apply(g->rel[j], ua);
    V3<T> xm = (x1 + x2) * T(0.5);
    r[0] = (x2 - x1).dot(xm - xb) / T(g->scale);
    return true;
  }
};

template <typename T>
T InPlaneDistance(const V3<T>& a, const V3<T>& b, int u, int v) {
  T du = a[u] - b[u], dv = a[v] - b[v];
  return sqrt(du * du + dv * dv + T(1e-12));
}

// Distance from an in-plane point to the nearest side of a box (its inset).
template <typename T>
T Inset(const V3<T>& p, const std::array<double, 6>& box, int u, int v) {
  T d = p[u] - T(box[2 * u]);
  for (T e : {T(box[2 * u + 1]) - p[u], p[v] - T(box[2 * v]), T(box[2 * v + 1]) - p[v]})
    if (e < d) d = e;
  return d;
}

// Link length L >= lower bound from the corners it passes (Fig. 8):
// corner of B only: L >= |cB - uB| + inset of uA in A; corner of A only:
// L >= |cA - uA| + inset of uB in B; both: L >= |cA - uA| + |cB - uB|.
struct MotionFunctor {
  const PivotGeometry* g;
  int config;  // L measured in this configuration
  bool has_a, has_b;
  Eigen::Vector3d corner_a, corner_b;
  template <typename T>
  bool operator()(const T* ab, T* r) const {
    V3<T> ua = g->ua.cast<T>() + ab[0] * g->ea.cast<T>();
    V3<T> xb = g->ub.cast<T>() + ab[1] * g->eb.cast<T>();
    V3<T> x1 = Apply(g->rel[config], ua);
    T L = InPlaneDistance(x1, xb, g->u, g->v);
    T da = has_a ? InPlaneDistance<T>(corner_a.cast<T>(), ua, g->u, g->v) : Inset(xb, g->box_b, g->u, g->v);
    T db = has_b ? InPlaneDistance<T>(corner_b.cast<T>(), xb, g->u, g->v) : Inset(ua, g->box_a, g->u, g->v);
    r[0] = L - da - db;
    return true;
  }
};

double Angle(const Eigen::Vector3d& d, int u, int v) { return std::atan2(d[v], d[u]); }
double Wrap(double a) {
  while (a > M_PI) a -= 2 * M_PI;
  while (a <= -M_PI) a += 2 * M_PI;
  return a;
}
bool InArc(double psi, double phi1, double phi2) {
  double span = Wrap(phi2 - phi1), d = Wrap(psi - phi1);
  return span >= 0 ? d >= 0 && d <= span : d <= 0 && d >= span;
}

std::vector<Eigen::Vector3d> Corners(const std::array<double, 6>& box, int u, int v, int normal) {
  std::vector<Eigen::Vector3d> out;
  for (int i = 0; i < 4; ++i) {
    Eigen::Vector3d c;
    c[u] = box[2 * u + (i & 1)];
    c[v] = box[2 * v + (i >> 1)];
    c[normal] = 0;
    out.push_back(c);
  }
  return out;
}

// A point on a box's face and the unit direction of the face's longer
// in-plane side (the pivot's offset direction): the face's normal axis n,
// side 0 (low) or 1 (high), in-plane axes u and v, frac the point's
// fractions along them. Returns the longer axis.
int PivotOnFace(const std::array<double, 6>& box, const std::array<double, 2>& frac, int n, int side, int u, int v,
                Eigen::Vector3d& point, Eigen::Vector3d& dir) {
  point[n] = box[2 * n + side];
  point[u] = box[2 * u] + frac[0] * (box[2 * u + 1] - box[2 * u]);
  point[v] = box[2 * v] + frac[1] * (box[2 * v + 1] - box[2 * v]);
  dir.setZero();
  int longest = (box[2 * u + 1] - box[2 * u]) >= (box[2 * v + 1] - box[2 * v]) ? u : v;
  dir[longest] = 1;
  return longest;
}

// Double pivot j's geometry with the cuboids fixed at x: the pivots on the
// joint's face of child and parent, their offset axes (*la, *lb), and the
// child -> parent transform in the base and each configuration that sets j
// (their names in *config_names).
PivotGeometry PivotFrames(const Prototype& p, const internal::Model& model, const Joint& j, const Eigen::VectorXd& x,
                          SolveSummary& summary, std::vector<std::string>* config_names, int* la, int* lb) {
  PivotGeometry g;
  int ca = p.PartIndex(j.child), cb = p.PartIndex(j.parent);
  g.box_a = summary.cuboids[j.child];
  g.box_b = summary.cuboids[j.parent];
  int n = j.normal;
  g.u = n == 0 ? 1 : 0;
  g.v = n == 2 ? 1 : 2;
  int side = j.face.back() == '1' ? 1 : 0;
  *la = PivotOnFace(g.box_a, j.pivot_child, n, side, g.u, g.v, g.ua, g.ea);
  *lb = PivotOnFace(g.box_b, j.pivot_parent, n, side, g.u, g.v, g.ub, g.eb);
  g.scale = std::max(1.0, std::max(g.box_a[2 * *la + 1] - g.box_a[2 * *la], g.box_b[2 * *lb + 1] - g.box_b[2 * *lb]));
  for (const Configuration& c : p.configurations) {
    if (c.name != "base" && !c.values.count(j.name)) continue;
    internal::Pose pa = model.PoseOf(ca, c), pb = model.PoseOf(cb, c);
    Plane2 r;
    r.R = pb.R.transpose() * pa.R;
    Eigen::Vector3d ta, tb;
    for (int k = 0; k < 3; ++k) {
      ta[k] = pa.t[k].Eval(x);
      tb[k] = pb.t[k].Eval(x);
    }
    r.t = pb.R.transpose() * (ta - tb);
    g.rel.push_back(r);
    config_names->push_back(c.name);
  }
  return g;
}

// Adds to s2 the constraints of a pivot's offsets ab for configuration c:
// the link keeps its base length, and clears the corners it passes between
// base and c at the current offsets. Returns the corner cases added (a key
// that changes when the set of passed corners does).
std::string AddPivotConstraints(const PivotGeometry& g, const Joint& j, const std::string& config_name, std::size_t c,
                                const Eigen::Vector2d& ab, Nlp& s2) {
  const int n = j.normal;
  std::string key;
  s2.groups.push_back("position constraint of " + j.name + " base->" + config_name + " (" + j.where + ")");
  auto* f = new ceres::AutoDiffCostFunction<PositionFunctor, 1, 2>(new PositionFunctor{&g, 0, static_cast<int>(c)});
  s2.cons.push_back({std::unique_ptr<ceres::CostFunction>(f), true, static_cast<int>(s2.groups.size()) - 1,
                     j.name + ": equal link length in base and " + config_name});
  // Corners the link passes between base and c, at the current offsets.
  Eigen::Vector3d ua = g.ua + ab[0] * g.ea, xb = g.ub + ab[1] * g.eb;
  Eigen::Vector3d x0 = g.rel[0].R * ua + g.rel[0].t, x1 = g.rel[c].R * ua + g.rel[c].t;
  double phi0 = Angle(x0 - xb, g.u, g.v), phi1 = Angle(x1 - xb, g.u, g.v);
  std::vector<Eigen::Vector3d> cb, ca;
  for (const auto& k : Corners(g.box_b, g.u, g.v, n))
    if ((k - xb).norm() > 1e-6 && InArc(Angle(k - xb, g.u, g.v), phi0, phi1)) cb.push_back(k);
  Eigen::Vector3d y0 = g.rel[0].R.transpose() * (xb - g.rel[0].t), y1 = g.rel[c].R.transpose() * (xb - g.rel[c].t);
  double psi0 = Angle(y0 - ua, g.u, g.v), psi1 = Angle(y1 - ua, g.u, g.v);
  for (const auto& k : Corners(g.box_a, g.u, g.v, n))
    if ((k - ua).norm() > 1e-6 && InArc(Angle(k - ua, g.u, g.v), psi0, psi1)) ca.push_back(k);
  if (cb.empty() && ca.empty()) return key;
  s2.groups.push_back("motion constraint of " + j.name + " base->" + config_name + " (" + j.where + ")");
  auto add = [&](bool has_a, bool has_b, const Eigen::Vector3d& ka, const Eigen::Vector3d& kb) {
    auto* mf = new ceres::AutoDiffCostFunction<MotionFunctor, 1, 2>(new MotionFunctor{&g, 0, has_a, has_b, ka, kb});
    s2.cons.push_back({std::unique_ptr<ceres::CostFunction>(mf), false, static_cast<int>(s2.groups.size()) - 1,
                       j.name + ": link clears the corners"});
    key += std::to_string(has_a) + std::to_string(has_b) + ";";
  };
  if (!ca.empty() && !cb.empty()) {
    for (const auto& ka : ca)
      for (const auto& kb : cb) add(true, true, ka, kb);
  } else if (!cb.empty()) {
    for (const auto& kb : cb) add(false, true, Eigen::Vector3d::Zero(), kb);
  } else {
    for (const auto& ka : ca) add(true, false, ka, Eigen::Vector3d::Zero());
  }
  return key;
}

// Stage 2 for double pivot j with the cuboids fixed at x: its offsets a, b
// along the pivots' faces, in up to three rounds of re-listing the corners
// the link passes. Appends the PivotSolution to summary.pivots and returns
// true; on conflicting constraints records them in summary and returns false.
bool SolvePivot(const Prototype& p, const internal::Model& model, const Joint& j, const Eigen::VectorXd& x,
                const SolveOptions& options, SolveSummary& summary) {
  std::vector<std::string> config_names;
  int la = 0, lb = 0;
  const PivotGeometry g = PivotFrames(p, model, j, x, summary, &config_names, &la, &lb);
  Nlp s2;
  s2.n = 2;
  s2.target = Eigen::Vector2d::Zero();
  s2.weight = Eigen::Vector2d::Ones();
  double ma = std::min(5.0, 0.1 * (g.box_a[2 * la + 1] - g.box_a[2 * la]));
  double mb = std::min(5.0, 0.1 * (g.box_b[2 * lb + 1] - g.box_b[2 * lb]));
  s2.lower = Eigen::Vector2d(g.box_a[2 * la] + ma - g.ua[la], g.box_b[2 * lb] + mb - g.ub[lb]);
  s2.upper = Eigen::Vector2d(g.box_a[2 * la + 1] - ma - g.ua[la], g.box_b[2 * lb + 1] - mb - g.ub[lb]);
  std::vector<Eigen::VectorXd> starts = {Eigen::Vector2d::Zero()};
  for (int k = 0; k < 4; ++k)
    starts.push_back(Eigen::Vector2d(k & 1 ? s2.upper[0] : s2.lower[0], k & 2 ? s2.upper[1] : s2.lower[1]));
  for (auto& s : starts) s = s.cwiseMax(s2.lower).cwiseMin(s2.upper);

  PivotSolution ps;
  ps.joint = j.name;
  Eigen::Vector2d ab = starts[0];
  std::string corners_key;
  for (int round = 0; round < 3; ++round) {
    s2.cons.clear();
    s2.groups.clear();
    std::string key;
    for (std::size_t c = 1; c < g.rel.size(); ++c) key += AddPivotConstraints(g, j, config_names[c], c, ab, s2);
    std::vector<bool> act(s2.groups.size(), true);
    Outcome f = Feasibility(s2, act, starts, options.tolerance);
    if (f.violation > options.tolerance) {
      if (options.explain_conflicts) Explain(s2, starts, options.tolerance, summary);
      summary.conflicts.push_back("pivot ranges of " + j.name + " (pivots stay on their faces)");
      summary.max_violation = f.violation;
      return false;
    }
    Outcome o = Run(s2, act, false, f.x, options.tolerance);
    if (o.violation > options.tolerance) o = f;
    ab = o.x;
    // Motion bound reported at the solution.
    ps.link_length_bound = 0;
    for (const Con& c : s2.cons)
      if (!c.eq) {
        Eigen::Vector3d ua = g.ua + ab[0] * g.ea, xb = g.ub + ab[1] * g.eb;
        double L = (g.rel[0].R * ua + g.rel[0].t - xb).norm();
        ps.link_length_bound = std::max(ps.link_length_bound, L - G(c, o.x));
      }
    if (key == corners_key) break;
    corners_key = key;
  }
  ps.a = ab[0];
  ps.b = ab[1];
  Eigen::Vector3d ua = g.ua + ab[0] * g.ea, xb = g.ub + ab[1] * g.eb;
  Eigen::Vector3d xa = g.rel[0].R * ua + g.rel[0].t;
  // Parent frame == world for a root parent; map both through the parent's base pose (identity).
  for (int k = 0; k < 3; ++k) {
    ps.child_pivot[k] = xa[k];
    ps.parent_pivot[k] = xb[k];
  }
  ps.link_length = (xa - xb).norm();
  summary.pivots.push_back(ps);
  return true;
}

}  // namespace

std::string SolveSummary::Explain() const {
  if (satisfiable) return "constraints satisfiable";
  std::string s = "conflicting constraints: ";
  for (std::size_t i = 0; i < conflicts.size(); ++i) s += (i ? "; " : "") + conflicts[i];
  if (!violated.empty()) {
    s += " — e.g. ";
    for (std::size_t i = 0; i < violated.size() && i < 3; ++i) s += (i ? "; " : "") + violated[i];
  }
  return s;
}

SolveSummary SolvePrototype(const Prototype& p, const SolveOptions& options) {
  auto start = Clock::now();
  SolveSummary summary;
  internal::Model model(p);
  std::vector<internal::LinearConstraint> lin;
  Nlp nlp;
  model.Build(lin, nlp.groups);
  nlp.n = model.variables;
  nlp.target = model.base;
  nlp.weight = model.weight;
  nlp.lower = Eigen::VectorXd::Constant(nlp.n, -INFINITY);
  nlp.upper = Eigen::VectorXd::Constant(nlp.n, INFINITY);
  for (auto& c : lin) nlp.cons.push_back({std::make_unique<AffineCost>(c.g, nlp.n), c.eq, c.group, c.label});
  summary.variables = nlp.n;
  summary.constraints = static_cast<int>(nlp.cons.size());

  // Stage 1: cuboids B (and free joint values).
  std::vector<bool> all(nlp.groups.size(), true);
  Outcome feasible = Feasibility(nlp, all, {model.base}, options.tolerance);
  if (feasible.violation > options.tolerance) {
    if (options.explain_conflicts) Explain(nlp, {model.base}, options.tolerance, summary);
    summary.max_violation = feasible.violation;
    summary.seconds = std::chrono::duration<double>(Clock::now() - start).count();
    return summary;
  }
  Outcome solved = Run(nlp, all, false, feasible.x, options.tolerance);
  if (solved.violation > options.tolerance) solved = feasible;  // keep a feasible point
  const Eigen::VectorXd& x = solved.x;
  summary.max_violation = solved.violation;
  for (std::size_t c = 0; c < model.cuboids.size(); ++c) {
    std::array<double, 6> b;
    for (int k = 0; k < 6; ++k) {
      b[k] = x[6 * c + k];
      summary.deviation += std::pow(x[6 * c + k] - model.base[6 * c + k], 2);
    }
    summary.cuboids[model.cuboid_names[c]] = b;
  }
  summary.deviation = std::sqrt(summary.deviation);
  for (std::size_t i = 0; i < model.free_names.size(); ++i)
    summary.free_values[model.free_names[i]] = x[6 * model.cuboids.size() + i];

  // Stage 2: each double pivot's offsets a, b with B fixed.
  for (const Joint& j : p.joints) {
    if (j.type != JointType::kDoublePivot) continue;
    if (!SolvePivot(p, model, j, x, options, summary)) {
      summary.seconds = std::chrono::duration<double>(Clock::now() - start).count();
      return summary;
    }
  }
  summary.satisfiable = true;
  summary.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  return summary;
}

}  // namespace fabatlas::prototype
