// Fig. 14 box plots (preview_times_plot.h): the median bar sits where the
// documented log axis puts the median of 1..100 ms (50.5 ms), and labels
// are anti-aliased TrueType text (grey levels between ink and paper, which
// a bitmap font never draws). Fig. 13 curves (cache_curves_plot.h): the
// same text, the title alone in its row, the y label upright left of the
// axis.
#include <gtest/gtest.h>

#include <cmath>
#include <set>

#define STB_IMAGE_STATIC
#define STB_IMAGE_IMPLEMENTATION
#include <stb/stb_image.h>

#include "fabatlas/error.h"
#include "fabatlas/precompute/cache_curves_plot.h"
#include "fabatlas/precompute/preview_times_plot.h"
#include "fabatlas/testing/paths.h"

namespace fabatlas::precompute {
namespace {

TEST(PreviewTimesPlot, MedianBarOnTheLogAxisAndAntiAliasedText) {
  std::vector<double> seconds;
  for (int ms = 1; ms <= 100; ++ms) seconds.push_back(ms / 1000.0);
  const auto path = testing::FreshTempDir("fig14") / "fig14.png";
  PreviewTimesPlotOptions options;
  options.title = "test";
  WritePreviewTimesPng({{"no cache", seconds}}, path, options);
  int w = 0, h = 0, channels = 0;
  unsigned char* rgb = stbi_load(path.c_str(), &w, &h, &channels, 3);
  ASSERT_NE(rgb, nullptr);
  EXPECT_EQ(w, options.width);
  EXPECT_EQ(h, options.height);
  const auto px = [&](int x, int y) {
    const unsigned char* p = rgb + 3 * (y * w + x);
    return p[0] + 256 * p[1] + 65536 * p[2];
  };
  // Axis: decades 1 ms .. 100 ms between y = h - 110 (bottom) and 80 (top).
  const double bottom = h - 110, top = 80;
  const int median_y = static_cast<int>(std::lround(bottom - std::log10(50.5) / 2 * (bottom - top)));
  const int cx = 90 + (w - 30 - 90) / 2;
  EXPECT_EQ(px(cx + 20, median_y), 0) << "no black median bar at y " << median_y;
  EXPECT_NE(px(cx + 20, median_y + 12), 0);
  // Anti-aliased glyphs in the label row under the box.
  std::set<int> greys;
  for (int y = static_cast<int>(bottom) + 8; y < static_cast<int>(bottom) + 30; ++y)
    for (int x = cx - 60; x < cx + 60; ++x) {
      const unsigned char* p = rgb + 3 * (y * w + x);
      if (p[0] == p[1] && p[1] == p[2] && p[0] > 20 && p[0] < 235) greys.insert(p[0]);
    }
  EXPECT_GT(greys.size(), 10u);
  stbi_image_free(rgb);
  // No times at all, or no font: one clear error.
  EXPECT_THROW(WritePreviewTimesPng({{"empty", {}}}, path), InputError);
  options.font_file = "/nonexistent/font.ttf";
  EXPECT_THROW(WritePreviewTimesPng({{"no cache", seconds}}, path, options), InputError);
}

// Grey levels strictly between ink and paper in the box [x0, x1) x [y0, y1).
std::set<int> Greys(const unsigned char* rgb, int w, int x0, int x1, int y0, int y1) {
  std::set<int> greys;
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) {
      const unsigned char* p = rgb + 3 * (y * w + x);
      if (p[0] == p[1] && p[1] == p[2] && p[0] > 20 && p[0] < 235) greys.insert(p[0]);
    }
  return greys;
}

TEST(CacheCurvesPlot, TrueTypeTextTitleApartFromTheUprightAxisLabel) {
  std::vector<artifact::CacheCurvePoint> points;
  for (int i = 0; i <= 10; ++i)
    points.push_back({"opt_max", i, i, std::int64_t{i} << 20, 1.0 - 0.08 * i, 2.0 - 0.15 * i});
  const auto path = testing::FreshTempDir("fig13") / "fig13.png";
  CacheCurvesPlotOptions options;
  options.title = "test";
  WriteCacheCurvesPng(points, path, options);
  int w = 0, h = 0, channels = 0;
  unsigned char* rgb = stbi_load(path.c_str(), &w, &h, &channels, 3);
  ASSERT_NE(rgb, nullptr);
  // Plot area from x = 100, y = 60 (cache_curves_plot.cc). The title row
  // above it has anti-aliased text and nothing left of the axis; the y label
  // runs upright between the left edge and the tick labels, mid-height.
  EXPECT_GT(Greys(rgb, w, 100, w - 200, 10, 45).size(), 10u);
  EXPECT_TRUE(Greys(rgb, w, 0, 95, 0, 45).empty());
  EXPECT_GT(Greys(rgb, w, 5, 40, 60 + (h - 130) / 4, 60 + 3 * (h - 130) / 4).size(), 10u);
  stbi_image_free(rgb);
  options.font_file = "/nonexistent/font.ttf";
  EXPECT_THROW(WriteCacheCurvesPng(points, path, options), InputError);
}

}  // namespace
}  // namespace fabatlas::precompute
