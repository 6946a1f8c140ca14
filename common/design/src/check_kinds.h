// The checks a design can name (docs/design-format.md, checks), one function
// per kind; RunCheck (checks.cc) picks one by CheckSpec::type. Each returns
// the outcome of one sample: passed, or the failure type and a reason in
// words; a SampleFailure when the sample has no geometry to judge.
#pragma once

#include "checks.h"

namespace fabatlas::design::check {

// surface_checks.cc: the sample's solid and its surface.
CheckOutcome Watertight(CheckContext& c);
CheckOutcome MinThickness(const CheckSpec& spec, CheckContext& c);
CheckOutcome Stands(const CheckSpec& spec, CheckContext& c);
CheckOutcome MaxVolume(const CheckSpec& spec, CheckContext& c);

// fem_check.cc: voxel FEM under the design's load case.
CheckOutcome Fem(const CheckSpec& spec, CheckContext& c);

// collision_check.cc: a reconfigurable's transitions swept in spacetime.
CheckOutcome CollisionFree(const CheckSpec& spec, CheckContext& c);

// assembly_checks.cc: an assembly's cycles, rest and target.
CheckOutcome AssemblyFeasible(CheckContext& c);
CheckOutcome AssemblyStable(CheckContext& c);
CheckOutcome TargetReached(const CheckSpec& spec, CheckContext& c);

}  // namespace fabatlas::design::check
