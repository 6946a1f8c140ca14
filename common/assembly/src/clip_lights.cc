#include "fabatlas/assembly/clip_lights.h"

#include <sstream>

#include "fabatlas/error.h"

namespace fabatlas::assembly {

const char* ToString(RingSize s) {
  switch (s) {
    case RingSize::kXS:
      return "XS";
    case RingSize::kS:
      return "S";
    case RingSize::kM:
      return "M";
    case RingSize::kL:
      return "L";
  }
  return "?";
}

Program BuildClipLights(const ClipLightsParams& p, const std::string& library_path, const std::string& mesh_dir) {
  if (p.pairs < 1 || p.pairs > 4)
    throw InputError("clip lights: pairs must be in 1..4, got " + std::to_string(p.pairs));
  if (!(p.extension >= 0 && p.extension <= 45.7))
    throw InputError("clip lights: extension must be in [0, 45.7] mm, got " + std::to_string(p.extension));
  // PARTS.md §4 ex 16–20: ceiling hook → n × (turnbuckle → ring) → fabric
  // hanger → clip light; the hanger hangs flipped on the M and L rings and the
  // clip is a fixed joint on the M ring, as in the paper's programs.
  const bool flip = p.ring == RingSize::kM || p.ring == RingSize::kL;
  const bool fixed_clip = p.ring == RingSize::kM;
  std::ostringstream y;
  y << "start_with: {name: ceiling, part: CeilingHook, frame: [[0, 0, 1000], [0, 0, 0]]}\n"
    << "parts: {";
  for (int k = 1; k <= p.pairs; ++k)
    y << "tb" << k << ": ParamTurnbuckle, ring" << k << ": Ring" << ToString(p.ring) << ", ";
  y << "hanger: FabricHanger}\n"
    << "end_with: {name: light, part: ClipLight, primitive: clip, frame: [[0, 0, 0], [180, 90, 0]]}\n"
    << "steps:\n  - {attach: tb1.hook1, to: ceiling.hook}\n";
  for (int k = 1; k <= p.pairs; ++k) {
    y << "  - {attach: ring" << k << ".ring, to: tb" << k << ".hook2}\n";
    if (k < p.pairs) y << "  - {attach: tb" << k + 1 << ".hook1, to: ring" << k << ".ring}\n";
  }
  y << "  - {attach: hanger.hook1, to: ring" << p.pairs << ".ring" << (flip ? ", alignment: flip" : "") << "}\n"
    << "  - {attach: light.clip, to: hanger.rod" << (p.flip_clip ? ", alignment: flip" : "")
    << (fixed_clip ? ", is_fixed: true" : "") << "}\n";
  Program prog = ParseProgram(y.str(), "clip_lights(n=" + std::to_string(p.pairs) + ")", library_path, mesh_dir);
  // ParamTurnbuckle with extension e (PARTS.md §3.1): hooks at y = ±hook_y,
  // hook_y = 43.5 + e/2; the library's part is e = 0.
  Part& tb = prog.library.parts.at("ParamTurnbuckle");
  for (auto& prim : tb.primitives) prim.frame.position.y() += (prim.frame.position.y() > 0 ? 0.5 : -0.5) * p.extension;
  return prog;
}

ClipLightsResult EvaluateClipLights(const ClipLightsParams& p, const std::string& library_path, double tolerance_mm,
                                    const SolveOptions& options) {
  ClipLightsResult r;
  SolveOptions o = options;
  o.target_tolerance_mm = tolerance_mm;
  r.summary = SolveAssembly(BuildClipLights(p, library_path), o);
  r.feasible = r.summary.prechecks_passed && r.summary.feasible;
  r.stable = r.summary.stable;
  r.target_reached = r.summary.target_reached;
  r.target_deviation_mm = r.summary.final_target_error_mm;
  return r;
}

}  // namespace fabatlas::assembly
