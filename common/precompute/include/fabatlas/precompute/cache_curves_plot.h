// fabatlas/precompute/cache_curves_plot.h — Fab Forms Fig. 13 as a PNG: mean
// (Eq. 3) and worst preview time against cache size for the cache
// strategies, from the artifact's cache_curves table (docs/artifact.md).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "fabatlas/artifact/artifact.h"
#include "fabatlas/picture/true_type_font.h"

namespace fabatlas::precompute {

struct CacheCurvesPlotOptions {
  int width = 900, height = 560;  // pixels
  std::string title;              // e.g. the design name
  // The TrueType font of every label, as Fig. 14's (preview_times_plot.h).
  std::filesystem::path font_file = picture::kDefaultFontFile;
};

// x: cache size in MiB, y: preview time in seconds; per strategy a solid
// line for the worst time and a lighter line for the mean (NAIVE red,
// OPT-AVE purple, OPT-MAX blue, as in Fig. 13), with a legend and axis
// ticks; the title above the plot area, the y label upright beside the axis.
// Written atomically. Throws InputError when `points` is empty, the font
// cannot be read or the file cannot be written.
void WriteCacheCurvesPng(const std::vector<artifact::CacheCurvePoint>& points, const std::filesystem::path& path,
                         const CacheCurvesPlotOptions& options = {});

}  // namespace fabatlas::precompute
