#include "fabatlas/assembly/clip_lights.h"

#include <sstream>

#include "fabatlas/error.h"

namespace fabatlas::assembly {

const char* ToString(RingSize s) {
  switch (s) {
    case RingSize::kXS: return "XS";
    case RingSize::kS: return "S";
    case RingSize::kM: return "M";
    case RingSize::kL: return "L";
  }
  return "?";
}

Program BuildClipLights(const ClipLightsParams& p, const std::string& library_path, const std::string& mesh_dir) {
  if (p.pairs < 1 || p.pairs > 4) throw InputError("clip lights: pairs must be in 1..4, got " + std::to_string(p.pairs));
  if (!(p.extension >= 0 && p.extension <= 45.7))
    throw InputError("clip lights: extension must be in [0, 45.7] mm, got " + std::to_string(p.extension));
  std::ostringstream y;
  y << "start_with: {name: ceiling, part: Ceiling, frame: [[0, 0, 1000], [0, 0, 0]]}\n"
    << "parts: {hanger: FabricHanger";
  for (int k = 1; k <= p.pairs; ++k) y << ", tb" << k << ": Turnbuckle, ring" << k << ": Ring" << ToString(p.ring);
  y << "}\nend_with: {name: light, part: ClipLight, frame: [[0, 0, 0], [180, 90, 0]], match_rotation: false}\n"
    << "connect:\n  - {a: tb1.hook1, b: ceiling.hook}\n";
  for (int k = 1; k <= p.pairs; ++k) {
    y << "  - {a: ring" << k << ".ring, b: tb" << k << ".hook2}\n";
    if (k < p.pairs) y << "  - {a: ring" << k << ".ring, b: tb" << k + 1 << ".hook1}\n";
  }
  y << "  - {a: ring" << p.pairs << ".ring, b: hanger.hook}\n  - {a: light.clip, b: hanger.rod}\n";
  Program prog = ParseProgram(y.str(), "clip_lights(n=" + std::to_string(p.pairs) + ")", library_path, mesh_dir);
  // Turnbuckle with extension l: the library's frames are fitted on the
  // closed turnbuckle (long axis y); each hook moves out by l/2.
  Part& tb = prog.library.parts.at("Turnbuckle");
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
