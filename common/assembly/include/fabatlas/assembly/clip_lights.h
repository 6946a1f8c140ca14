// fabatlas/assembly/clip_lights.h — the clip-lights hack (FabHacks Table 5,
// "clip lights 1–4") as a design family for precompute.
//
// Exposed parameters: n turnbuckle–ring pairs (1..4), turnbuckle extension
// l in [0, 45.7] mm, ring size XS/S/M/L. The assembly is: ceiling hook at
// z = 1000 mm → n × (turnbuckle with extension l → ring) → fabric hanger →
// clip light, target clip light pose [0,0,0]/[180,90,0] (position matched).
#pragma once

#include <string>

#include "fabatlas/assembly/program.h"
#include "fabatlas/assembly/solve.h"

namespace fabatlas::assembly {

enum class RingSize { kXS, kS, kM, kL };
const char* ToString(RingSize s);

struct ClipLightsParams {
  int pairs = 4;         // n in 1..4
  double extension = 0;  // l in [0, 45.7] mm
  RingSize ring = RingSize::kXS;
  // Attach the clip light to the hanger's bar with alignment flip (Rod_Clip
  // [0,0,0] instead of the published programs' [0,180,0]): the clip on the
  // other side of the bar. The published target orientation [180,90,0] is
  // reachable with the hanger hanging upright only this way; with the
  // published alignment the clip frame is then 180° from it about the clip's
  // width axis (docs/assembly.md "Clip-lights family").
  bool flip_clip = false;
};

struct ClipLightsResult {
  // Checks.
  bool feasible = false;        // the program solves (no cycles here: always, unless prechecks fail)
  bool stable = false;          // nothing falls apart under gravity, small relaxation motion
  bool target_reached = false;  // relaxed clip light within `tolerance_mm` of the target position
  // Property.
  double target_deviation_mm = 0;  // relaxed clip light position error
  SolveSummary summary;
};

// Builds the program for `p` from the part library at `library_path` (the
// library's Turnbuckle hooks, fitted on the closed turnbuckle, move out by l/2).
// Throws InputError for parameters outside their ranges.
Program BuildClipLights(const ClipLightsParams& p, const std::string& library_path, const std::string& mesh_dir = "");

// Builds, solves and checks one variation.
ClipLightsResult EvaluateClipLights(const ClipLightsParams& p, const std::string& library_path,
                                    double tolerance_mm = 25, const SolveOptions& options = {});

}  // namespace fabatlas::assembly
