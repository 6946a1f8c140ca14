// Fig. 14 box plots as a PNG (see preview_times_plot.h): a picture::Canvas
// with picture::TrueTypeFont text, written as PNG.
#include "fabatlas/precompute/preview_times_plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "fabatlas/error.h"
#include "fabatlas/precompute/form_outputs.h"
#include "fabatlas/picture/canvas.h"
#include "fabatlas/picture/true_type_font.h"

namespace fabatlas::precompute {

namespace {

// Quantile q of sorted v by linear interpolation between order statistics.
double Quantile(const std::vector<double>& v, double q) {
  const double at = q * (v.size() - 1);
  const std::size_t i = static_cast<std::size_t>(at);
  return i + 1 < v.size() ? v[i] + (at - i) * (v[i + 1] - v[i]) : v.back();
}

std::string Ms(double seconds) {
  char buf[32];
  const double ms = seconds * 1000;
  std::snprintf(buf, sizeof buf, ms < 10 ? "%.2f ms" : ms < 100 ? "%.1f ms" : "%.0f ms", ms);
  return buf;
}

}  // namespace

void WritePreviewTimesPng(const std::vector<PreviewTimesSeries>& series, const std::filesystem::path& path,
                          const PreviewTimesPlotOptions& options) {
  double lo = INFINITY, hi = 0;
  for (const auto& s : series)
    for (double t : s.seconds)
      if (t > 0) lo = std::min(lo, t), hi = std::max(hi, t);
  if (!(hi > 0)) throw InputError(path.string() + ": no preview time to plot");
  const picture::TrueTypeFont font(options.font_file);
  picture::Canvas img(options.width, options.height);
  const int left = 90, right = options.width - 30, top = 80, bottom = options.height - 110;
  // Log axis over whole decades (ms) around the data.
  const double d0 = std::floor(std::log10(lo * 1000)), d1 = std::max(d0 + 1, std::ceil(std::log10(hi * 1000)));
  const auto Y = [&](double seconds) {
    const double t = (std::log10(std::max(seconds, 1e-9) * 1000) - d0) / (d1 - d0);
    return static_cast<int>(std::lround(bottom - t * (bottom - top)));
  };
  for (double d = d0; d <= d1; ++d)
    for (double m : {1.0, 2.0, 5.0}) {
      const double ms = m * std::pow(10.0, d);
      if (std::log10(ms) > d1 + 1e-9) continue;
      const int y = Y(ms / 1000);
      img.HLine(left, right, y, m == 1 ? 0xCCCCCC : 0xEEEEEE);
      char label[32];
      std::snprintf(label, sizeof label, ms >= 1 ? "%.0f" : "%g", ms);
      font.Draw(img, left - 10 - font.Width(label, 14), y + 5, label, 0x333333, 14);
    }
  img.VLine(left, top, bottom, 0x000000);
  img.HLine(left, right, bottom, 0x000000);
  font.Draw(img, 12, top - 20, "preview time (ms, log scale)", 0x000000, 15);
  font.Draw(img, left, 32, options.title, 0x000000, 18);
  const unsigned colours[] = {0x7F7F7F, 0x1F5FA8, 0x7D3C98, 0x2E8B57};
  const int n = static_cast<int>(series.size());
  const int slot = (right - left) / std::max(1, n), box = std::min(120, slot / 2);
  for (int k = 0; k < n; ++k) {
    const int cx = left + slot * k + slot / 2;
    std::vector<double> v = series[k].seconds;
    std::sort(v.begin(), v.end());
    const unsigned c = colours[k % 4];
    font.DrawCentred(img, cx, bottom + 26, series[k].name, 0x000000, 17);
    if (v.empty()) {
      font.DrawCentred(img, cx, bottom + 48, "n = 0", 0x555555, 14);
      continue;
    }
    double mean = 0;
    for (double t : v) mean += t;
    mean /= v.size();
    const int q1 = Y(Quantile(v, 0.25)), q2 = Y(Quantile(v, 0.5)), q3 = Y(Quantile(v, 0.75));
    img.VLine(cx, Y(v.back()), q3, c, 2);
    img.VLine(cx, q1, Y(v.front()), c, 2);
    img.HLine(cx - box / 4, cx + box / 4, Y(v.back()), c, 2);
    img.HLine(cx - box / 4, cx + box / 4, Y(v.front()), c, 2);
    img.Rect(cx - box / 2, q3, cx + box / 2, q1 + 1, (c & 0xFEFEFE) / 2 + 0x7F7F7F);  // lighter fill
    img.HLine(cx - box / 2, cx + box / 2, q3, c, 2);
    img.HLine(cx - box / 2, cx + box / 2, q1, c, 2);
    img.VLine(cx - box / 2, q3, q1, c, 2);
    img.VLine(cx + box / 2, q3, q1, c, 2);
    img.HLine(cx - box / 2, cx + box / 2, q2, 0x000000, 3);
    const int my = Y(mean);
    for (int r = 0; r <= 6; ++r)
      img.HLine(cx - (6 - r), cx + (6 - r), my - r, 0xC0392B), img.HLine(cx - (6 - r), cx + (6 - r), my + r, 0xC0392B);
    font.DrawCentred(img, cx, bottom + 48, "n = " + std::to_string(v.size()) + ", mean " + Ms(mean), 0x333333, 14);
    font.DrawCentred(img, cx, bottom + 68, "median " + Ms(Quantile(v, 0.5)) + ", worst " + Ms(v.back()), 0x333333, 14);
  }
  font.Draw(img, left, options.height - 14, "box: quartiles, bar: median, whiskers: fastest and worst, diamond: mean",
            0x555555, 13);
  img.WritePng(path);
}

}  // namespace fabatlas::precompute
