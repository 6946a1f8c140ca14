#include "fabatlas/picture/axis_ticks.h"

#include <cmath>
#include <cstdio>

namespace fabatlas::picture {

double NiceStep(double range, int ticks) {
  if (!(range > 0) || ticks < 1) return 1.0;
  const double raw = range / ticks;
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (m * p >= raw) return m * p;
  return 10 * p;
}

std::string TickLabel(double value) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", value);
  return buf;
}

}  // namespace fabatlas::picture
