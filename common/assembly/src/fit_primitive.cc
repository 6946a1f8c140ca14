#include "fabatlas/assembly/fit_primitive.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Eigenvalues>

#include "fabatlas/assembly/mass_properties.h"
#include "fabatlas/error.h"

namespace fabatlas::assembly {
namespace {

constexpr double kDeg = 180.0 / M_PI;

// Unit vector with its largest-magnitude component positive (a deterministic sign).
Eigen::Vector3d Canonical(Eigen::Vector3d v) {
  v.normalize();
  int k = 0;
  v.cwiseAbs().maxCoeff(&k);
  return v[k] < 0 ? Eigen::Vector3d(-v) : v;
}

// Principal directions of the points, by increasing variance.
Eigen::Matrix3d Principal(const std::vector<Eigen::Vector3d>& p, Eigen::Vector3d& mean) {
  mean.setZero();
  for (const auto& x : p) mean += x;
  mean /= static_cast<double>(p.size());
  Eigen::Matrix3d c = Eigen::Matrix3d::Zero();
  for (const auto& x : p) c += (x - mean) * (x - mean).transpose();
  return Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(c).eigenvectors();
}

double Median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

Eigen::Vector3d Rotate(const Eigen::Vector3d& v, const Eigen::Vector3d& axis, double deg) {
  return Eigen::AngleAxisd(deg / kDeg, axis) * v;
}

ArcFit FitArcOnce(const std::vector<Eigen::Vector3d>& p) {
  ArcFit f;
  Eigen::Vector3d mean;
  const Eigen::Matrix3d e = Principal(p, mean);
  f.normal = Canonical(e.col(0));
  const Eigen::Vector3d e1 = (e.col(2) - e.col(2).dot(f.normal) * f.normal).normalized();
  const Eigen::Vector3d e2 = f.normal.cross(e1);
  // Kåsa: u² + v² + D u + E v + F = 0 in least squares.
  Eigen::MatrixXd a(p.size(), 3);
  Eigen::VectorXd b(p.size());
  for (std::size_t i = 0; i < p.size(); ++i) {
    const double u = (p[i] - mean).dot(e1), v = (p[i] - mean).dot(e2);
    a.row(i) << u, v, 1.0;
    b[i] = -(u * u + v * v);
  }
  const Eigen::Vector3d s = a.colPivHouseholderQr().solve(b);
  const double cu = -s[0] / 2, cv = -s[1] / 2;
  f.centre = mean + cu * e1 + cv * e2;
  std::vector<double> rho;
  for (const auto& x : p) {
    const Eigen::Vector3d d = x - f.centre;
    rho.push_back((d - d.dot(f.normal) * f.normal).norm());
  }
  double sum = 0;
  for (double r : rho) sum += r;
  f.radius = sum / static_cast<double>(rho.size());
  std::vector<double> tube;
  for (std::size_t i = 0; i < p.size(); ++i)
    tube.push_back(std::hypot(rho[i] - f.radius, (p[i] - f.centre).dot(f.normal)));
  f.wire_radius = Median(tube);
  // Angular span: 360° minus the largest gap between vertex angles.
  std::vector<double> ang;
  for (const auto& x : p) {
    const Eigen::Vector3d d = x - f.centre;
    ang.push_back(std::atan2(d.dot(e2), d.dot(e1)) * kDeg);
  }
  std::sort(ang.begin(), ang.end());
  double gap = ang.front() + 360 - ang.back(), start = ang.front();
  for (std::size_t i = 1; i < ang.size(); ++i)
    if (ang[i] - ang[i - 1] > gap) gap = ang[i] - ang[i - 1], start = ang[i];
  f.span_deg = 360 - gap;
  f.start = Rotate(e1, f.normal, start);
  f.points = static_cast<int>(p.size());
  return f;
}

}  // namespace

ArcFit FitArc(const std::vector<Eigen::Vector3d>& points) {
  if (points.size() < 12) throw InputError("arc fit: needs at least 12 points, got " + std::to_string(points.size()));
  ArcFit f = FitArcOnce(points);
  // Drop what is not on the bent wire (a shank, a mounting plate): vertices
  // whose in-plane distance from the centre arc exceeds 1.6 × the median one
  // (a round wire's surface has median 0.7 × its radius, a flat strip's
  // edges its half width), then fit again.
  for (int pass = 0; pass < 3; ++pass) {
    std::vector<double> off;
    for (const auto& x : points) {
      const Eigen::Vector3d d = x - f.centre;
      off.push_back(std::abs((d - d.dot(f.normal) * f.normal).norm() - f.radius));
    }
    const double band = 1.6 * Median(off);
    std::vector<Eigen::Vector3d> kept;
    for (std::size_t i = 0; i < points.size(); ++i)
      if (off[i] <= band) kept.push_back(points[i]);
    if (kept.size() < 12) break;
    f = FitArcOnce(kept);
  }
  return f;
}

AxisFit FitAxis(const std::vector<Eigen::Vector3d>& points) {
  if (points.size() < 12) throw InputError("axis fit: needs at least 12 points, got " + std::to_string(points.size()));
  AxisFit f;
  Eigen::Vector3d mean;
  f.axis = Canonical(Principal(points, mean).col(2));
  double lo = 1e300, hi = -1e300;
  for (const auto& x : points) lo = std::min(lo, (x - mean).dot(f.axis)), hi = std::max(hi, (x - mean).dot(f.axis));
  f.centre = mean + 0.5 * (lo + hi) * f.axis;
  f.length = hi - lo;
  std::vector<double> r;
  for (const auto& x : points) {
    const Eigen::Vector3d d = x - f.centre;
    r.push_back((d - d.dot(f.axis) * f.axis).norm());
  }
  f.radius = Median(r);
  f.points = static_cast<int>(points.size());
  return f;
}

Eigen::Vector3d RotationToEuler(const Eigen::Matrix3d& r) {
  const double b = std::asin(std::clamp(-r(2, 0), -1.0, 1.0));
  double a, c;
  if (std::abs(r(2, 0)) < 1 - 1e-6) {
    a = std::atan2(r(2, 1), r(2, 2));
    c = std::atan2(r(1, 0), r(0, 0));
  } else {
    a = 0;
    c = std::atan2(-r(0, 1), r(1, 1));
  }
  return Eigen::Vector3d(a, b, c) * kDeg;
}

Frame ArcFrame(const ArcFit& fit, double arc_angle_deg, const Eigen::Vector3d& down) {
  Eigen::Vector3d x, u0;
  if (arc_angle_deg >= 360) {
    x = fit.normal;
    u0 = down - down.dot(x) * x;
    if (u0.norm() < 1e-9) u0 = fit.start;
    u0.normalize();
  } else {
    // point(θ) = c + r′(cos θ u0 − sin θ ŷ) runs clockwise about x, so x = −normal
    // makes θ run along the span (counter-clockwise about the normal).
    x = -fit.normal;
    u0 = Rotate(fit.start, fit.normal, 0.5 * (fit.span_deg - arc_angle_deg));
  }
  const Eigen::Vector3d z = -u0, y = z.cross(x);
  Eigen::Matrix3d r;
  r << x, y, z;
  Frame f;
  f.position = fit.centre;
  f.euler_deg = RotationToEuler(r);
  return f;
}

Frame AxisFrame(const AxisFit& fit, const Eigen::Vector3d& up) {
  const Eigen::Vector3d z = fit.axis;
  Eigen::Vector3d y = up - up.dot(z) * z;
  if (y.norm() < 1e-9) throw InputError("axis fit: 'up' is parallel to the rod axis");
  y.normalize();
  Eigen::Matrix3d r;
  r << y.cross(z), y, z;
  Frame f;
  f.position = fit.centre;
  f.euler_deg = RotationToEuler(r);
  return f;
}

std::vector<Eigen::Vector3d> MeshPointsIn(const std::string& path, const Eigen::Vector3d& lo,
                                          const Eigen::Vector3d& hi) {
  std::vector<Eigen::Vector3d> out;
  for (const auto& v : ReadPartMesh(path).vertices)
    if ((v.array() >= lo.array()).all() && (v.array() <= hi.array()).all()) out.push_back(v);
  return out;
}

}  // namespace fabatlas::assembly
