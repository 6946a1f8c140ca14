// Deterministic subtree cost model: t = a + b·output_bytes + c·input_bytes
// per operation. Coefficients: docs/cache.md "Cost model".
#include "fabatlas/cache/cost_model.h"

#include <string_view>

namespace fabatlas::cache {

namespace {
struct Coefficients {
  std::string_view op;
  double fixed_seconds;
  double seconds_per_output_byte;
  double seconds_per_input_byte;
};

// Fallback for operations not in the table.
constexpr Coefficients kDefault{"", 1e-3, 2e-9, 2e-9};

constexpr Coefficients kTable[] = {
    {"union", 1e-3, 2e-9, 2e-9},
    {"difference", 1e-3, 2e-9, 2e-9},
    {"intersection", 1e-3, 2e-9, 2e-9},
};
}  // namespace

double ModelSubtreeSeconds(std::string_view op, std::uint64_t output_bytes, std::uint64_t input_bytes) {
  const Coefficients* c = &kDefault;
  for (const Coefficients& row : kTable)
    if (row.op == op) c = &row;
  return c->fixed_seconds + c->seconds_per_output_byte * static_cast<double>(output_bytes) +
         c->seconds_per_input_byte * static_cast<double>(input_bytes);
}

}  // namespace fabatlas::cache
