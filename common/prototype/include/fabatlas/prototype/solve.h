// fabatlas/prototype/solve.h — part and joint parameters of a works-like
// prototype (Koo et al. Sec. 4-6): functional relationships become linear
// constraints on the cuboid coordinates B, solved as least-squares deviation
// from the base configuration (Eq. 4); then, with B fixed, the double pivot
// offsets L under the quadratic position and the motion constraints (Sec. 5.6).
#pragma once

#include <array>
#include <map>
#include <string>
#include <vector>

#include "fabatlas/prototype/prototype.h"
#include "fabatlas/vec3.h"

namespace fabatlas::prototype {

struct SolveOptions {
  double tolerance = 1e-4;        // largest constraint violation accepted, mm
  bool explain_conflicts = true;  // run the deletion filter when unsatisfiable
};

struct PivotSolution {
  std::string joint;
  double a = 0, b = 0;                 // pivot offsets along the long axes, mm
  Vec3 child_pivot{}, parent_pivot{};  // base configuration, world mm
  double link_length = 0;              // mm
  double link_length_bound = 0;        // motion constraint lower bound, mm (0 if none)
};

struct SolveSummary {
  bool satisfiable = false;
  // When unsatisfiable: an irreducible set of conflicting constraint groups
  // (relationship, joint attachment, held coordinates...), each
  // "name (file:line:col)", and the low-level constraints they violate.
  std::vector<std::string> conflicts;
  std::vector<std::string> violated;  // low-level constraints left violated within that set
  std::string Explain() const;        // one line
  double max_violation = 0;           // mm, at the returned solution

  std::map<std::string, std::array<double, 6>> cuboids;  // solved boxes: parts, "part.piece" and "part.cavity"
  std::map<std::string, double> free_values;             // solved free joint values "joint@config.k"
  std::vector<PivotSolution> pivots;
  double deviation = 0;  // sqrt(sum (B - B_base)^2), mm
  int variables = 0, constraints = 0;
  double seconds = 0;  // both stages
};

SolveSummary SolvePrototype(const Prototype& p, const SolveOptions& options = {});

}  // namespace fabatlas::prototype
