// fabatlas/assembly/solve.h — the two-step FabHacks solve (FabHacks Sec. 4.3.2–4.3.3).
//
// Unknowns: a 6-DoF pose per part (translation mm + rotation) and the
// connection parameters of both primitives of every connect (bounded as in
// Primitive::Params()). A connection holds when P_a·M_a(s_a)·A = P_b·M_b(s_b);
// its residual is the position difference (mm) and `rotation_scale_mm` × the
// rotation-matrix difference.
//  0. Feasibility (cycle closure, 4.3.2): minimise C = Σ‖g_j‖² from a
//     deterministic quasi-random grid of starts (Halton points over the
//     parameter box; start 0 = box centre), poses initialised by forward
//     kinematics along a spanning tree so tree connections hold exactly;
//     stall detection aborts a start whose log-cost stops decreasing.
//     Feasible when C < feasibility_tolerance. In programs with cycles one
//     start (`chain_start`) is computed chain by chain instead (FabHacks
//     Table 5 ★): the chain to the target part first, then each cycle from
//     the chains already solved.
//  1. User objective (4.3.3 step 1): minimise ‖target pose − end_with frame‖²
//     + σ·(C + C_m), σ from penalty_start doubling up to penalty_doublings
//     times until C < feasibility_tolerance. C_m: multi-connection spacing.
//  2. Relaxation under gravity (4.3.3 step 2): minimise Σ m_i g z_i +
//     σ_r Σ‖g_j‖² over all poses and parameters (clip parameters and is_fixed
//     connections held), mass = mesh volume × 1 g/cm³, g = 9.8 m/s² along −z.
//     A weak anchor ½k‖s − s_step1‖² fixes the gauge of parts free to turn
//     about the vertical. Connectors on rods start held by static friction
//     and are let go, relaxing again, while any one's load leaves the
//     friction cone (slide_friction). Optionally (relaxation_active_set)
//     parameters that reach a bound are held there and released when pushed
//     back in, and (relaxation_target_weight) the relaxation starts from the
//     reference's continuation on the target term. Then every BOUNDED_AND_OPEN parameter
//     pinned at a bound whose energy gradient points out of its interval
//     (and, on a rod, outside the friction cone) is reported as falling apart.
// Single-threaded (Ceres with one thread); deterministic.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "fabatlas/assembly/program.h"

namespace fabatlas::assembly {

struct SolveOptions {
  int restarts = 16;  // starts of the feasibility solve (FabHacks uses T = 16)
  // Which start (0-based) is the chain-by-chain initial guess (FabHacks
  // Table 5 ★; SetChainStart in solve.cc) in programs with cycles; -1 never.
  int chain_start = 1;
  double feasibility_tolerance = 1e-6;  // C threshold, mm² (FabHacks: 1e-6)
  double penalty_start = 100;           // σ of step 1 (FabHacks: 100, doubling)
  int penalty_doublings = 5;
  double relaxation_penalty = 1e4;  // σ_r of step 2 (EXAMPLES.md: 1e4)
  double gravity = 9.8;             // m/s²
  double rotation_scale_mm = 20;    // closure: mm per unit of rotation-matrix difference
  // Step 1 target: mm per radian of rotation error. The reference weighs
  // |Δpos|² (mm²) against |ΔEuler|² (deg²), i.e. 1° ≈ 1 mm (PARTS.md §2.1).
  double target_mm_per_rad = 180 / 3.14159265358979323846;
  int max_iterations = 200;  // Ceres iterations per feasibility / objective solve
  // Step 2 (relaxation). Levenberg-Marquardt sees the gravity potential only
  // through its gradient (the least-squares form has no curvature along a
  // swing), so it converges linearly along hanging chains: it gets its own
  // iteration cap and stops on absolute criteria, not on the cost change.
  int relaxation_max_iterations = 20000;
  double relaxation_function_tolerance = 1e-16;   // relative cost change
  double relaxation_gradient_tolerance = 1e-14;   // projected gradient, J per unit
  double relaxation_parameter_tolerance = 1e-14;  // relative step
  // ... and when no parameter moved by more than `relaxation_window_motion`
  // (mm or degrees) over `relaxation_window` iterations (0 disables): LM
  // creeps along soft modes with steps of ~1e-6 (RelaxationWindow, solve.cc).
  int relaxation_window = 500;
  double relaxation_window_motion = 1e-3;
  // Gauge fix: ½k‖s − s_step1‖² over the free parameters (J per unit², degrees
  // for angles) so a part free to turn about the vertical stays where step 1
  // put it; 0 disables. See AnchorCost in solve.cc.
  double relaxation_anchor_stiffness = 1e-9;
  // Continuation from the target: step 2 first minimises energy +
  // w·‖target error‖² (w in J per mm², the step-1 target residual) with w =
  // relaxation_target_weight, then w/10, … while w > relaxation_target_weight_end,
  // then the energy alone. 0: the energy alone from the start.
  double relaxation_target_weight = 0;
  // Active set (the reference's active-set Newton): after a relaxation run,
  // hold every bounded parameter left at a bound with the energy pushing it
  // out, release the held one pushed back in hardest, and run again until
  // the set is stable. Bounded Levenberg-Marquardt alone creeps along a
  // bound it keeps running into and stops short of the constrained minimum.
  bool relaxation_active_set = false;
  double relaxation_target_weight_end = 1e-9;
  // The potential m g z is the least-squares term m g (z + D)²/(2000 D),
  // exact in gradient up to |z|/D. The cost (≈ m g D/2000 J) bounds the
  // energy resolution to ~1e-16 of it; a smaller D adds curvature that
  // changes the path and with it the equilibrium reached (not a tuning knob
  // for the examples; kept as an option for experiments).
  double relaxation_datum_mm = 1e5;
  int stall_window = 10;      // iterations in the stall regression
  double stall_slope = 1e-3;  // abort if log10(C) falls slower than this per iteration
  bool relax = true;          // run step 2
  // A part resting on another (a surface on a surface, a roll on a rod) is
  // held by static friction in step 2 and slides off when its support tilts
  // beyond this angle: atan μ for μ = 0.36, the low end of wood, paper and
  // plastic on each other (docs/assembly.md "Falling apart").
  double friction_angle_deg = 20;
  // Static friction along rods: a connector on a rod, tube or edge that is
  // not held (not is_fixed, clip or resting contact; a hook on a peg, a ring
  // on a bar) stays where step 1 put it while the load along the axis is at
  // most μ times the load across it, |F·a| ≤ μ‖F − (F·a)a‖, with the same
  // μ = tan(friction_angle_deg); a slide whose load leaves that cone slides
  // freely, and a connector pushed against an open end falls off only if it
  // is outside the cone there (docs/assembly.md "Static friction along rods").
  // false: the paper's model, in which such connectors slide without
  // friction (FabHacks Sec. 4.3.3; only is_fixed connections are "formed by
  // static friction", Sec. 4.2).
  bool slide_friction = true;
  // Step 1 stops trying further feasible starts once the target is within:
  double early_exit_mm = 1.0;
  // ... and after this many feasible starts have run step 1.
  int objective_starts = 4;
  // "target reached": final (relaxed) target pose within
  double target_tolerance_mm = 25;
  double target_tolerance_deg = 10;
};

struct SolveSummary {
  bool prechecks_passed = true;
  bool feasible = false;           // cycles close: C < feasibility_tolerance
  bool stable = false;             // relaxed, and nothing falls apart (falls_apart empty)
  bool target_reached = false;     // relaxed target within target_tolerance
  double constraint_residual = 0;  // C after step 1 (mm²)
  double step1_target_error_mm = 0, step1_target_error_deg = 0;
  double final_target_error_mm = 0, final_target_error_deg = 0;  // after relaxation
  double relax_displacement_mm = 0, relax_rotation_deg = 0;      // target motion in step 2
  // What falls apart after relaxation: "hook1.hook.theta at max" (a connector
  // slides off an open end), "bottle.surface tips over (...)".
  std::vector<std::string> falls_apart;
  // Every slide along a rod, tube or edge that static friction acts on
  // (SolveOptions::slide_friction): "room.rod2.t (tb.hook1)", the angle of
  // its load past the axis's normal plane, atan(|F·a| / ‖F − (F·a)a‖), in
  // degrees, and whether friction held it (angle ≤ friction_angle_deg; the
  // angle is the final one) or it slid (the angle at which it started to).
  struct Slide {
    std::string where;
    double load_angle_deg = 0;
    bool held = false;
  };
  std::vector<Slide> slides;
  std::vector<std::string> messages;  // pre-check issues and solver notes
  int starts_tried = 0;
  // Step 2 as Ceres ended it: "CONVERGENCE", "NO_CONVERGENCE" (iteration cap),
  // ... ; empty if step 2 did not run.
  // With static friction along rods step 2 may run more than once
  // (`relaxation_runs`): iterations are summed and the termination is the
  // last run's (an earlier run only decides which slides are let go; one
  // that ends at the iteration cap hands on where it stopped).
  std::string relaxation_termination;
  int relaxation_iterations = 0;
  int relaxation_runs = 0;
  double seconds = 0;  // wall time of the whole solve
  // Wall time per step, as FabHacks Table 5's columns: quick reject (the
  // pre-checks), feasibility (cycle closure over all starts tried; Table 5's
  // "constraints checking"), step 1 (target objective) and step 2 (relaxation).
  double precheck_seconds = 0, feasibility_seconds = 0, objective_seconds = 0, relaxation_seconds = 0;
  int feasibility_starts = 0;  // starts until the first feasible one (Table 5 "# initial guesses")
  // Per instance (mm). Infeasible: `poses` are those of the start that came
  // closest to closing the cycles (tree connections hold), `step1_poses` empty.
  std::vector<Eigen::Isometry3d> step1_poses, poses;
  std::vector<std::vector<double>> params;  // per connection: s_a then s_b
};

// Pre-checks, then the two-step solve. Never throws for a loaded Program.
SolveSummary SolveAssembly(const Program& program, const SolveOptions& options = {});

}  // namespace fabatlas::assembly
