// Internal: affine forms c + sum_i a_i x_i over the solver variables, and a
// small parser for linear expressions ("door.w / 2 + 3", "free" not here).
#pragma once

#include <array>
#include <cmath>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Dense>

namespace fabatlas::prototype::internal {

struct Affine {
  std::map<int, double> a;
  double c = 0;

  static Affine Var(int i) {
    Affine f;
    f.a[i] = 1;
    return f;
  }
  static Affine Const(double v) {
    Affine f;
    f.c = v;
    return f;
  }
  bool IsConst() const {
    for (const auto& [_, v] : a)
      if (v != 0) return false;
    return true;
  }
  double Eval(const Eigen::VectorXd& x) const {
    double s = c;
    for (const auto& [i, v] : a) s += v * x[i];
    return s;
  }
};

inline Affine operator+(Affine l, const Affine& r) {
  for (const auto& [i, v] : r.a) l.a[i] += v;
  l.c += r.c;
  return l;
}
inline Affine operator*(double s, Affine f) {
  for (auto& [_, v] : f.a) v *= s;
  f.c *= s;
  return f;
}
inline Affine operator-(const Affine& l, const Affine& r) { return l + (-1.0) * r; }

using Affine3 = std::array<Affine, 3>;

inline Affine3 Mul(const Eigen::Matrix3d& m, const Affine3& v) {
  Affine3 out;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (m(i, j) != 0) out[i] = out[i] + m(i, j) * v[j];
  return out;
}
inline Affine3 Add(const Affine3& l, const Affine3& r) { return {l[0] + r[0], l[1] + r[1], l[2] + r[2]}; }
inline Affine3 Sub(const Affine3& l, const Affine3& r) { return {l[0] - r[0], l[1] - r[1], l[2] - r[2]}; }

// Parses a linear expression: numbers, names, + - * / and parentheses; a
// product needs a constant side. `resolve` maps a name to its form and
// throws InputError for unknown names. Throws InputError(where + ": ...").
Affine ParseAffine(const std::string& text, const std::function<Affine(const std::string&)>& resolve,
                   const std::string& where);

}  // namespace fabatlas::prototype::internal
