// fabatlas/swept/contact_normal.h — the spacetime contact normal of two
// moving parts over a time span (Reconfigurables, Secs. 6.2–6.4, Eqs. 1–2).
//
// At a time t the surfaces of parts a and b cross along the intersection
// contour I_c(t): the union of the segments where a triangle of a meets a
// triangle of b. Intersection contour minimisation (Volino and
// Magnenat-Thalmann 2006) moves the surfaces so that this contour shrinks;
// for a segment of length l on triangles with outward unit normals N_a and
// N_b the contour recedes into the overlap's edge when b moves relative to
// a along
//
//   g = l (N_a - N_b) / |N_a - N_b|,
//
// the bisector of leaving a through its surface (N_a) and of withdrawing
// b's surface from a (-N_b); it is the per-segment direction of their
// contour gradient. Summed over the contour it is the contact normal at t.
// The energy of Eq. 1 is the area of the spacetime intersection surface,
//
//   |I_S| = integral over [t0, t1] of |I_c(t)| dt ~ sum_i |I_c(t_i)| dt,
//
// and the spacetime contact normal is its gradient, Eq. 2: the per-time
// contact normals summed over regularly spaced samples t_i of the span,
// each weighted by dt. Each summand is kept as a "force" (where, when, how
// much) so that callers can project it on any degree of freedom by the
// chain rule of Eq. 3 (design/resolution_hint.h).
//
// For comparison (Sec. 6.1, Fig. 15) the summary also holds the spatial
// normal at first contact: the direction from a's closest point to b's just
// before the parts first touch (conservative advancement,
// continuous_contact.h, from the sample before t0).
//
// Units: mm, t in [0, 1]. Threading: runs on the calling thread.
#pragma once

#include <array>
#include <vector>

#include "fabatlas/swept/spacetime_collision.h"

namespace fabatlas::swept {

struct ContactNormalOptions {
  // Regular samples t_i = i/(n-1) of the transition; those in [t0, t1]
  // (and t0, t1 themselves) are integrated, each weighted by dt = 1/(n-1).
  int time_steps = 101;
  // First contact: closer than this fraction of the parts' largest extent
  // counts as touching (as SpacetimeOptions::contact_tolerance).
  double contact_tolerance = 1e-5;
  bool first_contact = true;  // false: skip the spatial normal at first contact
};

// One contour segment at one time sample, as a generalised force on b
// relative to a (world frame at t).
struct ContourForce {
  double t = 0;
  Vec3 point{0, 0, 0};                        // the segment's midpoint, mm
  Vec3 force{0, 0, 0};                        // l dt (N_a - N_b)/|N_a - N_b|, mm (x unit t)
  Vec3 normal_a{0, 0, 0}, normal_b{0, 0, 0};  // outward unit normals of the two triangles
};

struct ContactNormalSummary {
  double energy = 0;                 // |I_S| of Eq. 1, mm x (unit t)
  Vec3 spacetime_normal{0, 0, 0};    // Eq. 2 for a translation of b relative to a, unit (zero if no contour)
  Vec3 spacetime_gradient{0, 0, 0};  // the same before normalising (the sum of the forces)
  // The translation control points P0..P3 of b's motion (rigid_motion.h):
  // Eq. 3 with dT/dP_k = B_k(t) (Bernstein weights), i.e. the forces summed
  // with those weights. A keyframe hint in mm (x unit t).
  std::array<Vec3, 4> control_point_gradient{};
  bool has_first_contact = false;  // false when the parts touch from t = 0
  double first_contact_t = 0;
  Vec3 first_contact_normal{0, 0, 0};  // unit, from a towards b just before first contact (Sec. 6.1)
  int contour_samples = 0;             // samples with a non-empty contour
  std::vector<ContourForce> forces;    // every segment of every sample
};

// Parts a and b (a != b) of `parts` over [t0, t1] (0 <= t0 <= t1 <= 1).
// Throws InputError for bad indices, open or empty meshes, time_steps < 2
// or a bad span.
ContactNormalSummary SpacetimeContactNormal(const std::vector<MovingPart>& parts, int a, int b, double t0, double t1,
                                            const ContactNormalOptions& options = {});

}  // namespace fabatlas::swept
