// fabatlas/sampling/sample_evaluator.h — what the sampler asks of a design.
//
// The sampler never sees geometry: it asks an evaluator for the outcome of
// EvaluateSample(u) (Fab Forms, Alg. 2) and for ΔG between two *valid* samples
// (Fab Forms, Eq. 2). The conventions for invalid samples (zero volume, so
// ΔG(invalid, invalid) = 0 and ΔG(valid, invalid) = 1; Fab Forms
// Sec. 5.2) are applied by the sampler, so GeometryChange is only called for
// valid/valid pairs.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "fabatlas/sampling/design_space.h"

namespace fabatlas::sampling {

// A point handed to the evaluator: u holds one value per dimension in the
// order of DesignSpace::dimensions() (enumerated: the value index, an exact
// small integer in a double); key is its exact identity (design_space.h).
struct SamplePoint {
  PointKey key;
  std::vector<double> u;
};

// Result of EvaluateSample(u). failure_type is empty when valid, otherwise
// the name of the first failing check (e.g. "unsat_constraints",
// "min_thickness"). cpu_seconds is filled in by the executor (thread CPU time
// spent in the call); evaluators may leave it at 0.
struct SampleOutcome {
  bool valid = false;
  std::string failure_type;
  std::map<std::string, double> properties;
  double cpu_seconds = 0.0;
};

// Implementations must be safe to call concurrently from several threads and
// deterministic: the same point gives the same outcome and the same ΔG.
class SampleEvaluator {
 public:
  virtual ~SampleEvaluator() = default;
  // EvaluateSample(u), Fab Forms Alg. 2.
  virtual SampleOutcome EvaluateSample(const SamplePoint& point) = 0;
  // ΔG(a, b) = |V(Ga) xor V(Gb)| / |V(Ga) u V(Gb)| in [0, 1] for two samples
  // the evaluator previously reported valid (Fab Forms, Eq. 2). Symmetric.
  virtual double GeometryChange(const SamplePoint& a, const SamplePoint& b) = 0;
};

}  // namespace fabatlas::sampling
