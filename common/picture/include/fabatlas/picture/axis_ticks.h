// fabatlas/picture/axis_ticks.h — tick spacing and labels for the plots'
// axes (Fig. 13 curves, Pareto fronts).
#pragma once

#include <string>

namespace fabatlas::picture {

// A "nice" step (1, 2 or 5 times a power of ten) giving about `ticks` ticks
// over `range`; 1 for a range that is not positive.
double NiceStep(double range, int ticks);

// A tick's label: 3 significant digits (printf %.3g).
std::string TickLabel(double value);

}  // namespace fabatlas::picture
