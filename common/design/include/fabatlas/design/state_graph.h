// fabatlas/design/state_graph.h — a reconfigurable design's state graph at
// one point, for playing it (Reconfigurables, Secs. 3 and 5: collisions
// first by *when*, then *where*): every object's mesh in its body frame,
// every transition's motions, and the collision intervals its collision_free
// check found there.
//
// One implementation: EvaluateStateGraph runs EvaluateSample with every
// check, and the collision_free check itself records what it tested (the
// object meshes, the resolved motions, swept::DetectCollisions' intervals)
// into the StateGraph, so what is played is exactly what `fabatlas eval`
// and sampling decide on.
#pragma once

#include <string>
#include <vector>

#include "fabatlas/design/evaluate_sample.h"
#include "fabatlas/mesh/triangle_mesh.h"
#include "fabatlas/swept/rigid_motion.h"
#include "fabatlas/swept/spacetime_collision.h"

namespace fabatlas::design {

struct StateGraphTransition {
  std::string name, from, to;
  // Each object's motion (body -> world, t in [0, 1], mm), parallel to
  // StateGraph::object_names; objects the transition does not move hold the
  // pose of `from`.
  std::vector<swept::RigidMotion> motions;
  // The collision_free check's intervals on this transition, by t_begin
  // (part_a/part_b index the objects); empty when it found none or did not
  // run.
  std::vector<swept::CollisionInterval> collisions;
};

struct StateGraph {
  // True when the design has a collision_free check and it ran at this point
  // (it runs whenever constraints and geometry pass: every check runs).
  bool collisions_checked = false;
  int time_steps = 0;                             // the check's time samples per transition
  std::vector<std::string> object_names;          // Design::objects order
  std::vector<mesh::TriangleMesh> objects;        // body frame (pose in the first state), mm, from the level sets
  std::vector<StateGraphTransition> transitions;  // Design::transitions order
};

struct StateGraphResult {
  SampleResult sample;  // EvaluateSample at u with every check: verdict, failure, reason
  StateGraph graph;     // empty objects when the point has no geometry (unsat constraints, ...)
};

// Evaluates the design at exactly u with all its checks and returns its
// state graph there. Threading: evaluates on the calling thread. Throws
// InputError for a design without objects or transitions, and whatever
// EvaluateSample throws.
StateGraphResult EvaluateStateGraph(const Design& design, const Point& u);

}  // namespace fabatlas::design
