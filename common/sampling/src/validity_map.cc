#include "fabatlas/sampling/validity_map.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <stdexcept>

#include "fabatlas/error.h"
#include "fabatlas/picture/canvas.h"

namespace fabatlas::sampling {

namespace {

// Labels in the canvas's pixel font (picture::Canvas::Text) at scale 2:
// about 12 px a character, 14 px high.
constexpr int kScale = 2;
constexpr int kCharH = 7 * kScale;

int TextWidth(const std::string& s) { return picture::Canvas::TextWidth(s, kScale); }

unsigned Blend(unsigned c, double t) {  // t = 0: c, t = 1: white
  auto ch = [&](int s) {
    const double v = ((c >> s) & 255) * (1 - t) + 255 * t;
    return static_cast<unsigned>(std::lround(v)) << s;
  };
  return ch(16) | ch(8) | ch(0);
}

std::vector<std::string> FailureTypes(const Form& form) {
  std::set<std::string> types;
  for (const FormSample& s : form.samples)
    if (!s.outcome.valid) types.insert(s.outcome.failure_type.empty() ? "invalid" : s.outcome.failure_type);
  return {types.begin(), types.end()};
}

std::string Format(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", v);
  return buf;
}

}  // namespace

unsigned ValidColour() { return 0x2E9E44; }

unsigned FailureColour(const Form& form, const std::string& failure_type) {
  static const unsigned kPalette[] = {0xC0392B, 0x2C5AA0, 0x8E44AD, 0xD68910, 0x6E2C00, 0xC2185B, 0x117A65, 0x555555};
  const auto types = FailureTypes(form);
  const std::string t = failure_type.empty() ? "invalid" : failure_type;
  const auto it = std::find(types.begin(), types.end(), t);
  const size_t i = it == types.end() ? 7 : static_cast<size_t>(it - types.begin());
  return kPalette[std::min<size_t>(i, 7)];
}

namespace {

// The fixed values of every dimension but the plotted two: options.fixed, or
// each range's middle (rounded down on a discrete dimension). Throws
// InputError for a bad dimension choice, count or value.
std::vector<double> FixedValues(const DesignSpace& space, const ValidityMapOptions& options) {
  const int n = space.dimension_count();
  const int xd = options.x_dimension, yd = options.y_dimension;
  if (xd < 0 || yd < 0 || xd >= n || yd >= n || xd == yd)
    throw InputError("validity map: dimensions " + std::to_string(xd) + " and " + std::to_string(yd) +
                     " are not two distinct dimensions of a " + std::to_string(n) + "-D space");
  std::vector<double> fixed = options.fixed;
  if (fixed.empty()) {
    for (int d = 0; d < n; ++d) {
      const double mid = 0.5 * (space.dimension(d).lo + space.dimension(d).hi);
      fixed.push_back(space.is_discrete(d) ? std::floor(mid) : mid);
    }
  }
  if (static_cast<int>(fixed.size()) != n)
    throw InputError("validity map: expected " + std::to_string(n) + " fixed values, got " +
                     std::to_string(fixed.size()));
  for (int d = 0; d < n; ++d)
    if (d != xd && d != yd && !(fixed[d] >= space.dimension(d).lo && fixed[d] <= space.dimension(d).hi))
      throw InputError("validity map: fixed value " + Format(fixed[d]) + " of '" + space.dimension(d).name +
                       "' is outside its range");
  return fixed;
}

// The picture's plot: the form, its space, the plotted dimensions, the
// plot's side P and its top-left corner on the canvas (pixels).
struct Plot {
  const Form& form;
  const DesignSpace& space;
  int xd, yd, P, left, top;
};

// A leaf's colour: valid when all its corner samples are; else the colour of
// its most frequent failure type, blended towards white when some corner is
// valid.
unsigned LeafColour(const Form& form, const FormNode& node) {
  std::map<std::string, int> counts;
  int invalid = 0, total = 0;
  for (std::int64_t s : CornerSampleIds(form, node)) {
    ++total;
    if (form.samples[s].outcome.valid) continue;
    ++invalid;
    ++counts[form.samples[s].outcome.failure_type];
  }
  unsigned c = ValidColour();
  if (invalid > 0) {
    std::string top_type;
    int best = -1;
    for (const auto& [t, k] : counts)
      if (k > best) best = k, top_type = t;
    c = FailureColour(form, top_type);
    if (invalid < total) c = Blend(c, 0.55);
  }
  return c;
}

// Paints each plot pixel in the colour of the leaf its centre falls in (the
// other dimensions at `fixed`); returns each pixel's leaf id (tree << 32 |
// node, -1 for none), row by row, and the leaves hit in *leaves_hit.
std::vector<long long> PaintLeaves(const Plot& plot, const std::vector<double>& fixed, picture::Canvas& img,
                                   std::set<long long>* leaves_hit) {
  const int P = plot.P, xd = plot.xd, yd = plot.yd;
  const Dimension& dx = plot.space.dimension(xd);
  const Dimension& dy = plot.space.dimension(yd);
  auto ux = [&](double px) { return dx.lo + px / P * (dx.hi - dx.lo); };
  auto uy = [&](double py) { return dy.hi - py / P * (dy.hi - dy.lo); };
  std::vector<long long> leaf_id(static_cast<size_t>(P) * P, -1);
  std::map<long long, unsigned> leaf_colour;
  std::vector<double> u = fixed;
  for (int py = 0; py < P; ++py)
    for (int px = 0; px < P; ++px) {
      u[xd] = ux(px + 0.5);
      u[yd] = uy(py + 0.5);
      const auto leaf = LocateLeaf(plot.form, plot.space, u);
      if (!leaf) continue;
      const long long id = (static_cast<long long>(leaf->tree) << 32) | leaf->node;
      leaf_id[static_cast<size_t>(py) * P + px] = id;
      auto it = leaf_colour.find(id);
      if (it == leaf_colour.end()) {
        it = leaf_colour.emplace(id, LeafColour(plot.form, plot.form.trees[leaf->tree].nodes[leaf->node])).first;
        leaves_hit->insert(id);
      }
      img.Set(plot.left + px, plot.top + py, it->second);
    }
  return leaf_id;
}

// Grey pixels where the leaf changes from the pixel to the left or above.
void DrawLeafBoundaries(const Plot& plot, const std::vector<long long>& leaf_id, picture::Canvas& img) {
  const int P = plot.P;
  for (int py = 0; py < P; ++py)
    for (int px = 0; px < P; ++px) {
      const long long id = leaf_id[static_cast<size_t>(py) * P + px];
      const bool edge = (px > 0 && leaf_id[static_cast<size_t>(py) * P + px - 1] != id) ||
                        (py > 0 && leaf_id[static_cast<size_t>(py - 1) * P + px] != id);
      if (edge) img.Set(plot.left + px, plot.top + py, 0x7F7F7F);
    }
}

// Corner dots: a projected corner is valid when every corner of the leaf
// projecting onto it is valid (white dot), else black.
void DrawCornerDots(const Plot& plot, const std::set<long long>& leaves_hit, picture::Canvas& img) {
  const Form& form = plot.form;
  const int P = plot.P, xd = plot.xd, yd = plot.yd;
  const Dimension& dx = plot.space.dimension(xd);
  const Dimension& dy = plot.space.dimension(yd);
  std::map<std::pair<int, int>, bool> dots;
  for (long long id : leaves_hit) {
    const FormNode& node = form.trees[id >> 32].nodes[id & 0xffffffff];
    const auto ids = CornerSampleIds(form, node);
    for (size_t c = 0; c < ids.size(); ++c) {
      const double vx = plot.space.value(xd, (c >> xd) & 1 ? node.hi[xd] : node.lo[xd]);
      const double vy = plot.space.value(yd, (c >> yd) & 1 ? node.hi[yd] : node.lo[yd]);
      const int px = static_cast<int>(std::lround((vx - dx.lo) / (dx.hi - dx.lo) * P));
      const int py = static_cast<int>(std::lround((dy.hi - vy) / (dy.hi - dy.lo) * P));
      auto [it, inserted] = dots.emplace(std::make_pair(px, py), true);
      it->second = it->second && form.samples[ids[c]].outcome.valid;
    }
  }
  for (const auto& [p, valid] : dots) {
    const int cx = plot.left + p.first, cy = plot.top + p.second;
    img.Rect(cx - 2, cy - 2, cx + 3, cy + 3, 0x000000);
    if (valid) img.Rect(cx - 1, cy - 1, cx + 2, cy + 2, 0xFFFFFF);
  }
}

// The plot's frame, ticks at about ten grid keys per axis with their values
// (or enumerated names), and the axis names.
void DrawAxes(const Plot& plot, picture::Canvas& img) {
  const DesignSpace& space = plot.space;
  const int P = plot.P, xd = plot.xd, yd = plot.yd, left = plot.left, top = plot.top;
  const Dimension& dx = space.dimension(xd);
  const Dimension& dy = space.dimension(yd);
  for (int i = -1; i <= P; ++i) {
    img.Set(left + i, top - 1, 0), img.Set(left + i, top + P, 0);
    img.Set(left - 1, top + i, 0), img.Set(left + P, top + i, 0);
  }
  auto ticks = [&](int d) {
    std::vector<std::int64_t> keys;
    const int cells = space.cell_count(d);
    const int step = std::max(1, (cells + 9) / 10);
    for (int j = 0; j <= cells; j += step) keys.push_back(space.grid_key(d, j));
    if (keys.back() != space.key_hi(d)) keys.push_back(space.key_hi(d));
    return keys;
  };
  auto label = [&](int d, std::int64_t key) {
    const Dimension& dim = space.dimension(d);
    if (dim.kind == DimensionKind::kEnumerated) return dim.values[static_cast<size_t>(key)];
    return Format(space.value(d, key));
  };
  for (std::int64_t k : ticks(xd)) {
    const int px = left + static_cast<int>(std::lround((space.value(xd, k) - dx.lo) / (dx.hi - dx.lo) * P));
    img.Rect(px, top + P, px + 1, top + P + 6, 0);
    const std::string s = label(xd, k);
    img.Text(px - TextWidth(s) / 2, top + P + 9, s, 0, kScale);
  }
  for (std::int64_t k : ticks(yd)) {
    const int py = top + static_cast<int>(std::lround((dy.hi - space.value(yd, k)) / (dy.hi - dy.lo) * P));
    img.Rect(left - 6, py, left, py + 1, 0);
    const std::string s = label(yd, k);
    img.Text(left - 8 - TextWidth(s), py - kCharH / 2 + 1, s, 0, kScale);
  }
  img.Text(left + P / 2 - TextWidth(dx.name) / 2, top + P + 9 + 2 * kCharH, dx.name, 0, kScale);
  img.Text(4, 2, dy.name, 0, kScale);  // y axis name, top left
}

// The legend from (lx, ly): a swatch per leaf colour, then the two dots.
void DrawLegend(const Form& form, const std::vector<std::string>& types, int lx, int ly, picture::Canvas& img) {
  auto swatch = [&](unsigned c, const std::string& text) {
    img.Rect(lx, ly, lx + 16, ly + 12, 0);
    img.Rect(lx + 1, ly + 1, lx + 15, ly + 11, c);
    img.Text(lx + 22, ly + 1, text, 0, kScale);
    ly += 2 * kCharH;
  };
  swatch(ValidColour(), "valid");
  for (const auto& t : types) swatch(FailureColour(form, t), t);
  for (const auto& t : types) swatch(Blend(FailureColour(form, t), 0.55), "mixed " + t);
  img.Rect(lx + 5, ly + 2, lx + 11, ly + 8, 0), img.Rect(lx + 6, ly + 3, lx + 10, ly + 7, 0xFFFFFF);
  img.Text(lx + 22, ly + 1, "valid sample", 0, kScale);
  ly += 2 * kCharH;
  img.Rect(lx + 5, ly + 2, lx + 11, ly + 8, 0);
  img.Text(lx + 22, ly + 1, "invalid sample", 0, kScale);
}

}  // namespace

ValidityMapLayout WriteValidityMap(const Form& form, const ValidityMapOptions& options, const std::string& path) {
  const DesignSpace space = form.space();
  const std::vector<double> fixed = FixedValues(space, options);

  const int P = std::max(64, options.plot_pixels);
  const int left = 80, top = 20, bottom = 60, gap = 30;
  const auto types = FailureTypes(form);
  int legend_w = 0;
  for (const auto& t : types) legend_w = std::max(legend_w, TextWidth("mixed " + t));
  legend_w = std::max(legend_w, TextWidth("invalid sample")) + 22 + 8;
  const int W = left + P + gap + legend_w;
  const int H = std::max(top + P + bottom, top + static_cast<int>(types.size() + 6) * 2 * kCharH);
  picture::Canvas img(W, H);
  const Plot plot{form, space, options.x_dimension, options.y_dimension, P, left, top};

  // Leaf colours, boundaries and corner dots.
  std::set<long long> leaves_hit;
  const std::vector<long long> leaf_id = PaintLeaves(plot, fixed, img, &leaves_hit);
  DrawLeafBoundaries(plot, leaf_id, img);
  DrawCornerDots(plot, leaves_hit, img);
  DrawAxes(plot, img);
  DrawLegend(form, types, left + P + gap, top, img);
  img.WritePng(path);
  return ValidityMapLayout{W, H, left, top, P};
}

}  // namespace fabatlas::sampling
