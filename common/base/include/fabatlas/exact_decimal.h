// fabatlas/exact_decimal.h — a double as decimal text that reads back to the
// same double ("%.17g": 17 significant digits, e.g. 0.10000000000000001).
// Used wherever a number becomes part of a key, a digest or a stored text, so
// equal values always give equal bytes.
#pragma once

#include <cstdio>
#include <string>

namespace fabatlas {

inline std::string ExactDecimal(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

}  // namespace fabatlas
