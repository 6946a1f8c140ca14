// Deterministic subtree cost model: t = a + b·(output_bytes + input_bytes)
// per operation. Coefficients: least squares (a, b >= 0) over 3,400 measured
// subtree root times of the example designs (docs/cache.md "Cost model").
#include "fabatlas/cache/cost_model.h"

#include <string_view>

namespace fabatlas::cache {

namespace {
struct Coefficients {
  std::string_view op;
  double fixed_seconds;     // a
  double seconds_per_byte;  // b, over output + input bytes
};

// Operations not in the table.
constexpr Coefficients kDefault{"", 1e-3, 1e-8};

constexpr Coefficients kTable[] = {
    {"box", 1.89e-3, 0},         {"cylinder", 0, 9.11e-9},      {"difference", 0, 1.14e-9}, {"offset", 0, 9.64e-8},
    {"polar_array", 0, 3.04e-8}, {"revolve", 2.70e-2, 2.02e-8}, {"rotate", 0, 1.38e-8},     {"sphere", 6.56e-3, 0},
    {"tentacle", 0, 3.40e-7},    {"torus", 0, 9.49e-9},         {"translate", 0, 1.10e-8},  {"union", 0, 8.43e-10},
};
}  // namespace

double ModelSubtreeSeconds(std::string_view op, std::uint64_t output_bytes, std::uint64_t input_bytes) {
  const Coefficients* c = &kDefault;
  for (const Coefficients& row : kTable)
    if (row.op == op) c = &row;
  return c->fixed_seconds +
         c->seconds_per_byte * (static_cast<double>(output_bytes) + static_cast<double>(input_bytes));
}

}  // namespace fabatlas::cache
