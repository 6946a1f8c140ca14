// fabatlas/design/resolution_hint.h — how to resolve the collisions of a
// reconfigurable design at one point (Reconfigurables, Secs. 6.4–6.5).
//
// For every collision interval the collision_free check finds (the same
// check precompute runs), the spacetime contact normal of the two objects
// (swept/contact_normal.h, Eqs. 1–2): a direction in space for the selected
// object, the gradient for its translation keyframes, and for comparison
// the spatial normal at first contact (Sec. 6.1, Fig. 15).
//
// For every colliding pair of objects, the hint in the design's degrees of
// freedom, its exposed real parameters (motion parameters and geometry
// parameters alike): Eq. 3, the chain rule from the contour forces to each
// parameter u_k,
//
//   -dE/du_k = sum over forces f of  f . (v_b(f) - v_a(f)),
//
// where v_x(f) is how fast the contour point moves as a point of object x
// when u_k changes: its motion's change (f_x at u + h e_k against f_x at u,
// applied to the body point) plus, when u_k changes x's shape, the normal
// speed of x's surface there (the signed distance of the body point to x's
// surface at u + h e_k, over h). The hint's magnitude is found as automatic
// resolution finds it (Sec. 6.6): the golden-section line search (Press et
// al. 1992) along the hint for the step that minimises the energy of all
// pairs (resolve_collisions.h).
//
// Units: parameters in their own units, mm, t in [0, 1]. Threading: the
// calling thread (each evaluation is EvaluateSample's).
#pragma once

#include <map>
#include <string>
#include <vector>

#include "fabatlas/design/design.h"
#include "fabatlas/design/evaluate_sample.h"
#include "fabatlas/swept/contact_normal.h"

namespace fabatlas::design {

struct ResolutionOptions {
  // The degrees of freedom: exposed real parameters by name; empty = all of
  // the design's exposed real parameters. Each moves within [min, max].
  std::vector<std::string> parameters;
  // Finite-difference step of a parameter's velocity, as a fraction of its
  // range (a step that would leave the range is taken downwards).
  double difference_step = 0.01;
  // Golden-section iterations of one line search (each evaluates the design
  // once; the bracket shrinks by 0.618 per iteration).
  int line_search_iterations = 12;
  // Energies within this fraction of the starting energy count as equal in
  // the line search (a level-set contour moves by less than a voxel).
  double energy_tolerance = 1e-3;
  // Automatic resolution: greedy steps (one pair each) at most.
  int max_steps = 6;
  // After the energy reaches zero, steps further along the last direction
  // (each twice the last, starting at the line search's final bracket) until
  // the design's checks pass (clearance, contact between samples).
  int max_extra_steps = 6;
};

// The contact normal of one collision interval.
struct IntervalNormal {
  std::string transition, object_a, object_b;  // object_b is the selected object; a's normal is the opposite
  double t_begin = 0, t_end = 0;
  swept::SpatialBox where;             // the check's box of the interval (world, mm)
  swept::ContactNormalSummary normal;  // forces dropped (normal.forces empty)
};

// The hint for one colliding pair of objects, over all its intervals.
struct PairHint {
  std::string object_a, object_b;
  double energy = 0;                      // |I_S| of the pair over every transition, mm x (unit t)
  std::map<std::string, double> descent;  // -dE/du_k per parameter (mm x unit t per parameter unit)
  std::map<std::string, double> step;     // the edit the line search chose (parameter units); empty when none helps
  double energy_after = 0;                // energy of all pairs after the step
};

struct HintSummary {
  SampleResult sample;                    // the point with every check, as precompute evaluates it
  std::vector<IntervalNormal> intervals;  // the collision_free check's intervals, by transition then t_begin
  std::vector<PairHint> pairs;            // by energy, largest first
  double energy = 0;                      // all pairs
  int evaluations = 0;                    // design evaluations run
};

// Throws InputError for a design without objects and transitions, an
// unknown or non-real parameter in options.parameters, or what
// EvaluateSample throws.
HintSummary ResolutionHints(const Design& design, const Point& u, const ResolutionOptions& options = {});

}  // namespace fabatlas::design
