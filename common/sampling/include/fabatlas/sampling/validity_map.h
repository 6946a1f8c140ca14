// fabatlas/sampling/validity_map.h — a 2-D slice of the sampled form as a PNG
// (Fab Forms Fig. 10 style): the plane spanned by two dimensions, the others
// fixed.
//
// Picture: each pixel takes the colour of the leaf that contains it — green
// when all its corners are valid, otherwise the colour of the most common
// failure type among its invalid corners (dark shade if every corner is
// invalid, light shade if the leaf is mixed). Leaf boundaries are thin grey
// lines; leaf corners in the slice are dots (white = valid, black = invalid);
// axes carry tick labels and the dimension names; a legend lists the colours.
#pragma once

#include <string>
#include <vector>

#include "fabatlas/sampling/form.h"

namespace fabatlas::sampling {

struct ValidityMapOptions {
  int x_dimension = 0;
  int y_dimension = 1;
  // Values of all dimensions (entries for x and y are ignored). Empty: the
  // centre of each range (enumerated / integer: the middle value).
  std::vector<double> fixed;
  int plot_pixels = 480;  // side of the square plot area
};

// Where the plot sits in the picture, so readers can map pixels to values:
// parameter (x_lo + (px - plot_left + 0.5) / plot_size * (x_hi - x_lo)), and y
// upwards from plot_top + plot_size.
struct ValidityMapLayout {
  int width = 0, height = 0;
  int plot_left = 0, plot_top = 0, plot_size = 0;
};

// Writes the PNG to `path`, whole or not at all (picture::Canvas::WritePng).
// Throws fabatlas::InputError for bad dimensions or fixed values outside the
// space, and one-line InputError / ResourceError (full disk) naming `path`
// when the file cannot be written.
ValidityMapLayout WriteValidityMap(const Form& form, const ValidityMapOptions& options, const std::string& path);

// The colour used for valid leaves and, for a failure type, the colour of
// all-invalid leaves (0xRRGGBB), so tests and viewers can read the picture.
unsigned ValidColour();
unsigned FailureColour(const Form& form, const std::string& failure_type);

}  // namespace fabatlas::sampling
