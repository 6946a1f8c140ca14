// Internal: what collision resolution (resolution_hint.h,
// resolve_collisions.h) computes at a point: the energy of Reconfigurables
// Eq. 1 over every pair and transition, the chain rule of Eq. 3 to the
// design's parameters, and the golden-section line search of Sec. 6.6.
#pragma once

#include <limits>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "fabatlas/design/resolution_hint.h"
#include "fabatlas/design/state_graph.h"
#include "fabatlas/design/subtree_cache.h"

namespace fabatlas::design {

// A degree of freedom: an exposed real parameter and its range.
struct Freedom {
  std::string name;
  double min = 0, max = 1;
};

// The free parameters options.parameters names (all real ones if empty).
// Throws InputError for an unknown or non-real name.
std::vector<Freedom> Freedoms(const Design& design, const ResolutionOptions& options);

// The design at u: objects, motions, and the contour of every pair of
// objects on every transition, sampled at `time_steps` (the check's).
struct ContactState {
  Point u;
  bool has_geometry = false;
  std::string failure, reason;  // why not, when it has none
  StateGraph graph;             // objects and motions (no check run)
  struct Pair {
    std::size_t transition = 0;
    int a = 0, b = 0;
    swept::ContactNormalSummary normal;  // over the whole transition
  };
  std::vector<Pair> pairs;  // pairs with a contour
  double energy = 0;        // infinity without geometry
  double PairEnergy(int a, int b) const;
};

// Evaluates the design at u without its checks (geometry and motions only;
// `cache` may be null) and integrates every contour.
ContactState EvaluateContacts(const Design& design, const Point& u, int time_steps, SubtreeCache* cache);
// The same from a state graph already evaluated at u.
ContactState ContactsOf(const Point& u, StateGraph graph, int time_steps);

// The design at u with every check (as precompute evaluates it), its state
// graph filled. `cache` may be null.
StateGraphResult EvaluateWithChecks(const Design& design, const Point& u, SubtreeCache* cache);

// The design moved by one parameter: u + h e_k.
struct Perturbation {
  std::string name;
  double h = 0;  // signed step, parameter units
  ContactState state;
};
std::vector<Perturbation> Perturb(const Design& design, const ContactState& at, const std::vector<Freedom>& free,
                                  const ResolutionOptions& options, SubtreeCache* cache);

// Eq. 3: -dE/du_k for the forces of pair (a, b) at `at`, per parameter.
std::map<std::string, double> PairDescent(const ContactState& at, const std::vector<Perturbation>& perturbations, int a,
                                          int b);

// The line search along `descent` (scaled to each parameter's range,
// projected on the bounds): the best point it evaluated.
struct LineSearch {
  bool moved = false;                       // a step that lowered the energy was found
  Point u;                                  // the best point (u itself if none)
  ContactState state;                       // there
  std::map<std::string, double> direction;  // parameter change per unit step
  double step = 0, bracket = 0;             // chosen step; final bracket width (unit steps)
  int evaluations = 0;
};
LineSearch GoldenSectionSearch(const Design& design, const ContactState& at,
                               const std::map<std::string, double>& descent, const std::vector<Freedom>& free,
                               const ResolutionOptions& options, int time_steps, SubtreeCache* cache);

// The point moved by `direction` x step, clamped to the ranges.
Point Moved(const Point& u, const std::map<std::string, double>& direction, double step,
            const std::vector<Freedom>& free);

}  // namespace fabatlas::design
