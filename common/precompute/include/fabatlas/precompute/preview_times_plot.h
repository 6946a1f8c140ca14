// fabatlas/precompute/preview_times_plot.h — Fab Forms Fig. 14 as a picture:
// the distribution of measured preview times (preview_times.h) with no
// cache, H_opt and H_rfree as box plots, labelled with a TrueType font.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "fabatlas/picture/true_type_font.h"

namespace fabatlas::precompute {

struct PreviewTimesSeries {
  std::string name;             // e.g. "no cache", "H_opt", "H_rfree"
  std::vector<double> seconds;  // one measured preview time per point
};

struct PreviewTimesPlotOptions {
  int width = 900, height = 560;  // pixels
  std::string title;              // e.g. "pawn: preview time over 200 valid points"
  // The TrueType font of every label (Debian: fonts-dejavu-core).
  std::filesystem::path font_file = picture::kDefaultFontFile;
};

// One box per series on a log10 time axis (milliseconds): the box spans the
// first to third quartile (linear interpolation between order statistics),
// a line marks the median, whiskers reach the smallest and largest times,
// and a diamond the mean; under each box its name, n, mean and worst.
// Empty series are drawn as "n = 0". Written atomically as PNG. Throws
// InputError when no series has a time, the font cannot be read, or the
// file cannot be written.
void WritePreviewTimesPng(const std::vector<PreviewTimesSeries>& series, const std::filesystem::path& path,
                          const PreviewTimesPlotOptions& options = {});

}  // namespace fabatlas::precompute
