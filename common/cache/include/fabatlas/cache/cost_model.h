// fabatlas/cache/cost_model.h — deterministic subtree costs for planning.
//
// Measured root times t_i differ from run to run (load, worker count,
// faults), so a plan fed with them is not reproducible. Whatever must be
// byte-identical across runs (the artifact's cache) is planned with these
// model costs instead: a function of facts every run computes identically —
// the operation and the sizes of its output and input geometry. Measured
// times are still reported beside the plan. Coefficients were fitted to
// measured times of the example designs (docs/cache.md "Cost model").
#pragma once

#include <cstdint>
#include <string_view>

namespace fabatlas::cache {

// Modelled compute time in seconds of a subtree root running operation `op`
// (design op name, e.g. "union", "revolve") that produced `output_bytes` of
// geometry from children totalling `input_bytes`. Pure, >= 0, deterministic
// (no clocks, no state). Unknown ops use the default coefficients.
double ModelSubtreeSeconds(std::string_view op, std::uint64_t output_bytes, std::uint64_t input_bytes);

}  // namespace fabatlas::cache
