// fabatlas/swept/spacetime_collision.h — collision intervals between moving
// parts (Reconfigurables, section 5): first *when* (time spans), then *where*
// (spatial box and pair of parts).
//
// Time is discretised at t_i = i/(n-1). Each part contributes one spacetime
// proxy per interval [t_i, t_i+1]: the 4D box [t_i, t_i+1] x (AABB at t_i
// union AABB at t_i+1). The proxies of all parts sit in one bounding volume
// hierarchy over 4D boxes (median split on the longest axis, time scaled by
// the scene's spatial extent); overlapping proxies of two parts are candidate
// pairs, confirmed at the interval's end samples by an exact mesh test:
// the smaller part's triangles, posed into the larger part's body frame,
// against a CGAL AABB tree of its faces (built once per part; touching
// counts), then a point-in-volume test each way (CGAL Side_of_triangle_mesh)
// so that containment counts too. Two parts that both hold still are tested
// once. Consecutive colliding samples of a pair form one interval.
// Between samples (SpacetimeOptions::continuous, default on) the test is
// conservative for any time_steps: each part's box at a sample, grown by the
// farthest any of its points can move in one step (RigidMotion::SpeedBound),
// bounds it over the whole step; for a pair whose grown boxes meet in a step
// where both end samples are collision-free, conservative advancement
// (continuous_contact.h) finds the first contact from the step's start and
// the last from its end, which becomes an interval of its own. So a thin
// part crossing another between two samples is reported, with its time
// span.
#pragma once

#include <array>
#include <cstddef>
#include <vector>

#include "fabatlas/mesh/triangle_mesh.h"
#include "fabatlas/swept/rigid_motion.h"

namespace fabatlas::swept {

struct MovingPart {
  mesh::TriangleMesh mesh;  // closed, body coordinates, mm
  RigidMotion motion;       // body -> world
};

struct SpacetimeOptions {
  int time_steps = 101;  // samples t_i = i/(n-1), n >= 2
  // Broad phase: the proxy hierarchy (default), every pair of proxies
  // (reference for tests and the benchmark; same result, O(proxies^2)), or
  // Embree's rtcCollide over the proxies flattened to 3D (each time interval
  // shifted along x into its own slab; boxes rounded outward to float, then
  // re-checked in double, so the candidates are the hierarchy's). Same result
  // with every choice; bench_collision compares them (docs/swept.md).
  enum class BroadPhase { kHierarchy, kAllPairs, kEmbree };
  BroadPhase broad_phase = BroadPhase::kHierarchy;
  // Collisions between samples by conservative advancement (see above).
  bool continuous = true;
  // Closer than this counts as touching between samples: this fraction of
  // the largest extent of a part's box over the motion (1e-5 x 100 mm =
  // 1 micrometre).
  double contact_tolerance = 1e-5;
};

struct SpatialBox {
  Vec3 min{0, 0, 0};
  Vec3 max{0, 0, 0};
};

// The axis-aligned box of a mesh's vertices placed by `f` (world frame).
SpatialBox PosedBox(const mesh::TriangleMesh& m, const Transform& f);

struct CollisionInterval {
  // First and last colliding sample; for a collision found only between
  // two samples, its first and last contact time (within the tolerance).
  double t_begin = 0, t_end = 0;
  int part_a = 0, part_b = 0;  // indices into the parts, part_a < part_b
  SpatialBox where;            // union over the samples of the two parts' AABB intersection
};

struct CollisionReport {
  std::vector<CollisionInterval> intervals;  // sorted by t_begin, then (part_a, part_b)
  std::size_t proxies = 0;                   // spacetime boxes in the hierarchy
  std::size_t candidate_pairs = 0;           // proxy pairs that overlap
  std::size_t exact_tests = 0;               // mesh-mesh tests run
  std::size_t continuous_searches = 0;       // (pair, step) searched between samples
  std::size_t distance_queries = 0;          // distance queries of those searches
  double broad_phase_seconds = 0;            // wall time of building and querying the broad phase
  bool collision_free() const { return intervals.empty(); }
};

// Throws InputError for open meshes, bad indices or time_steps < 2.
CollisionReport DetectCollisions(const std::vector<MovingPart>& parts, const SpacetimeOptions& options = {});

}  // namespace fabatlas::swept
