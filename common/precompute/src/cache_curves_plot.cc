// Fig. 13 curves as a PNG (see cache_curves_plot.h): a picture::Canvas with
// picture::TrueTypeFont text (the font and layout of Fig. 14's box plots,
// preview_times_plot.cc), written as PNG.
#include "fabatlas/precompute/cache_curves_plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

#include "fabatlas/error.h"
#include "fabatlas/precompute/form_outputs.h"
#include "fabatlas/picture/axis_ticks.h"
#include "fabatlas/picture/canvas.h"
#include "fabatlas/picture/true_type_font.h"

namespace fabatlas::precompute {

namespace {

using picture::Canvas;
using picture::NiceStep;
using picture::TickLabel;

unsigned StrategyColour(const std::string& s, bool mean) {
  if (s == "naive" || s == "NAIVE") return mean ? 0xF4A6A6 : 0xC0392B;
  if (s == "opt_ave" || s == "OPT-AVE") return mean ? 0xC9A7E0 : 0x7D3C98;
  if (s == "opt_max" || s == "OPT-MAX") return mean ? 0x9CC9F0 : 0x1F5FA8;
  return mean ? 0xBBBBBB : 0x444444;
}

}  // namespace

void WriteCacheCurvesPng(const std::vector<artifact::CacheCurvePoint>& points, const std::filesystem::path& path,
                         const CacheCurvesPlotOptions& options) {
  if (points.empty()) throw InputError(path.string() + ": no cache curves to plot");
  std::map<std::string, std::vector<artifact::CacheCurvePoint>> curves;
  for (const auto& p : points) curves[p.strategy].push_back(p);
  double max_mib = 0, max_s = 0;
  for (auto& [name, c] : curves) {
    std::sort(c.begin(), c.end(), [](const auto& a, const auto& b) { return a.step < b.step; });
    for (const auto& p : c) {
      max_mib = std::max(max_mib, static_cast<double>(p.bytes) / (1 << 20));
      max_s = std::max({max_s, p.worst_seconds, p.mean_seconds});
    }
  }
  if (!(max_mib > 0)) max_mib = 1;
  if (!(max_s > 0)) max_s = 1;
  const double x_step = NiceStep(max_mib, 6), y_step = NiceStep(max_s, 6);
  max_mib = std::ceil(max_mib / x_step) * x_step;
  max_s = std::ceil(max_s / y_step) * y_step;

  const picture::TrueTypeFont font(options.font_file);
  Canvas img(options.width, options.height);
  // Title on its own line above the plot, the y label upright left of the
  // tick labels, the x label under them (as Fig. 14's layout).
  const int left = 100, right = options.width - 200, top = 60, bottom = options.height - 70;
  auto X = [&](double mib) { return left + (right - left) * mib / max_mib; };
  auto Y = [&](double s) { return bottom - (bottom - top) * s / max_s; };
  for (double v = 0; v <= max_mib + 1e-9; v += x_step) {
    img.Line(X(v), top, X(v), bottom, 0xEEEEEE, 1);
    font.DrawCentred(img, static_cast<int>(X(v)), bottom + 20, TickLabel(v), 0x333333, 14);
  }
  for (double v = 0; v <= max_s + 1e-9; v += y_step) {
    img.Line(left, Y(v), right, Y(v), 0xEEEEEE, 1);
    font.Draw(img, left - 8 - font.Width(TickLabel(v), 14), static_cast<int>(Y(v)) + 5, TickLabel(v), 0x333333, 14);
  }
  img.Line(left, top, left, bottom, 0x000000, 2);
  img.Line(left, bottom, right, bottom, 0x000000, 2);
  font.DrawCentred(img, (left + right) / 2, bottom + 48, "cache size (MiB)", 0x000000, 15);
  font.DrawUpward(img, 24, (top + bottom) / 2 + font.Width("preview time (s)", 15) / 2, "preview time (s)", 0x000000,
                  15);
  const std::string title = (options.title.empty() ? std::string() : options.title + ": ") +
                            "mean and worst preview time vs cache size (Fab Forms Fig. 13)";
  font.Draw(img, left, 32, title, 0x000000, 18);

  int legend_y = top + 10;
  for (const auto& [name, c] : curves) {
    for (bool mean : {false, true}) {
      const unsigned colour = StrategyColour(name, mean);
      for (std::size_t i = 1; i < c.size(); ++i) {
        const double a = mean ? c[i - 1].mean_seconds : c[i - 1].worst_seconds;
        const double b = mean ? c[i].mean_seconds : c[i].worst_seconds;
        const double xa = static_cast<double>(c[i - 1].bytes) / (1 << 20),
                     xb = static_cast<double>(c[i].bytes) / (1 << 20);
        img.Line(X(xa), Y(a), X(xb), Y(b), colour, 3, mean ? 6 : 0);
      }
      if (c.size() == 1) {
        const double v = mean ? c[0].mean_seconds : c[0].worst_seconds;
        img.Rect(static_cast<int>(X(0)) - 3, static_cast<int>(Y(v)) - 3, static_cast<int>(X(0)) + 4,
                 static_cast<int>(Y(v)) + 4, colour);
      }
      img.Line(right + 20, legend_y + 6, right + 50, legend_y + 6, colour, 3, mean ? 6 : 0);
      font.Draw(img, right + 58, legend_y + 11, name + (mean ? " mean" : " worst"), 0x000000, 14);
      legend_y += 24;
    }
  }

  img.WritePng(path);
}

}  // namespace fabatlas::precompute
