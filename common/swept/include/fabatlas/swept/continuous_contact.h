// fabatlas/swept/continuous_contact.h — the first (or last) time two moving
// parts touch between two times, by conservative advancement (Mirtich 1996;
// docs/references.md): at time t the exact distance d between the posed
// surfaces (FCL, OBB/RSS trees over each part's triangles, built once) is a
// lower bound on how long they stay apart, d / (V_a + V_b), where V_p is a
// bound on the speed of any point of part p (RigidMotion::SpeedBound over
// its farthest vertex from the pivot). Advancing t by that amount never steps
// over a contact, whatever the motion does in between; the search stops at
// contact (d <= tolerance) or when it passes the end time. This makes the
// spacetime collision test conservative for any number of time samples
// (spacetime_collision.h uses it between samples).
//
// Units: mm, t in [0, 1]. Threading: const queries may run concurrently.
#pragma once

#include <memory>
#include <vector>

#include "fabatlas/swept/spacetime_collision.h"

namespace fabatlas::swept {

struct ContactSearchOptions {
  double tolerance = 1e-3;  // mm: closer than this counts as touching
  // A search that takes more steps stops and reports contact at the time
  // reached (conservative: a graze closer than the parts' speed can resolve).
  int max_steps = 100000;
};

struct ContactSearch {
  bool contact = false;     // the parts come within tolerance between the two times
  double t = 0;             // the first such time from `from` towards `to`
  int steps = 0;            // distance queries run
  bool step_limit = false;  // stopped by max_steps (contact is then true)
};

class ContinuousContact {
 public:
  // Builds one distance tree per part. Throws InputError for empty meshes.
  explicit ContinuousContact(const std::vector<MovingPart>& parts);
  ~ContinuousContact();
  ContinuousContact(const ContinuousContact&) = delete;
  ContinuousContact& operator=(const ContinuousContact&) = delete;

  // Bound on the speed of any point of part p, mm per unit t.
  double SpeedBound(int p) const;
  // Distance between the surfaces of parts a and b posed at time t (mm);
  // <= 0 when they touch or cross.
  double Distance(int a, int b, double t) const;
  // The same with the closest points of the two surfaces (world frame at
  // t): point_b - point_a is the direction that parts b from a fastest (the
  // gradient of the distance with respect to a translation of b).
  struct Closest {
    double distance = 0;
    Vec3 point_a{0, 0, 0}, point_b{0, 0, 0};
  };
  Closest Nearest(int a, int b, double t) const;
  // Searches from `from` towards `to` (backwards if to < from) for the first
  // time parts a and b are within options.tolerance.
  ContactSearch Advance(int a, int b, double from, double to, const ContactSearchOptions& options) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace fabatlas::swept
