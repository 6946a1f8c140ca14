#include "fabatlas/viewer/pareto_front.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "fabatlas/error.h"
#include "fabatlas/picture/axis_ticks.h"
#include "fabatlas/picture/canvas.h"
#include "fabatlas/viewer/property_limits.h"

namespace fabatlas::viewer {

ParetoOptions ParseParetoAxes(const std::string& text) {
  // Split at the comma between the two axes (names have no commas).
  const auto comma = text.find(',');
  if (comma == std::string::npos || text.find(',', comma + 1) != std::string::npos)
    throw InputError("pareto '" + text + "': expected two properties, A,B (each optionally min: or max:)");
  const auto axis = [&](const std::string& item) {
    ParetoAxis a;
    a.property = item;
    if (item.rfind("max:", 0) == 0)
      a.maximise = true, a.property = item.substr(4);
    else if (item.rfind("min:", 0) == 0)
      a.property = item.substr(4);
    if (a.property.empty()) throw InputError("pareto '" + text + "': an axis names no property");
    return a;
  };
  ParetoOptions options;
  options.a = axis(text.substr(0, comma));
  options.b = axis(text.substr(comma + 1));
  return options;
}

ParetoFront ParetoFrontOf(const sampling::Form& form, const std::vector<sampling::Material>& materials,
                          const ParetoOptions& options) {
  ParetoFront front;
  const Quantity a = ResolveQuantity(options.a.property, form, materials);
  const Quantity b = ResolveQuantity(options.b.property, form, materials);
  if (a.name == b.name && options.a.maximise == options.b.maximise)
    throw InputError("pareto: both axes " + std::string(options.a.maximise ? "maximise" : "minimise") + " '" + a.name +
                     "': nothing to trade off");
  front.a = a.name;
  front.b = b.name;
  const double sa = options.a.maximise ? -1 : 1, sb = options.b.maximise ? -1 : 1;
  std::vector<ParetoPoint> all;
  for (std::size_t i = 0; i < form.samples.size(); ++i) {
    const auto& s = form.samples[i];
    if (!s.outcome.valid) continue;
    const auto va = QuantityValue(a, s, materials);
    const auto vb = QuantityValue(b, s, materials);
    if (va && vb) all.push_back({static_cast<std::int64_t>(i), *va, *vb});
  }
  front.candidates = static_cast<std::int64_t>(all.size());
  // Best on a first, then best on b, then lowest id; a sweep keeps each
  // point strictly better on b than every point before it.
  std::sort(all.begin(), all.end(), [&](const ParetoPoint& p, const ParetoPoint& q) {
    if (sa * p.a != sa * q.a) return sa * p.a < sa * q.a;
    if (sb * p.b != sb * q.b) return sb * p.b < sb * q.b;
    return p.sample < q.sample;
  });
  double best_b = 0;
  for (const ParetoPoint& p : all) {
    if (!front.points.empty() && !(sb * p.b < best_b)) {
      if (options.keep_dominated) front.dominated.push_back(p);
      continue;
    }
    front.points.push_back(p);
    best_b = sb * p.b;
  }
  return front;
}

std::string ParetoCsv(const sampling::Form& form, const ParetoFront& front) {
  std::ostringstream out;
  out.precision(17);
  out << "sample," << front.a << "," << front.b;
  for (const auto& d : form.dimensions) out << "," << d.name;
  out << "\n";
  for (const auto& p : front.points) {
    out << p.sample << "," << p.a << "," << p.b;
    for (double v : form.samples.at(static_cast<std::size_t>(p.sample)).u) out << "," << v;
    out << "\n";
  }
  return out.str();
}

void WriteParetoPng(const ParetoFront& front, const std::filesystem::path& path, const ParetoPlotOptions& options) {
  if (front.points.empty()) throw InputError(path.string() + ": no valid sample records both properties");
  double a_lo = front.points[0].a, a_hi = a_lo, b_lo = front.points[0].b, b_hi = b_lo;
  for (const auto* set : {&front.points, &front.dominated})
    for (const auto& p : *set) {
      a_lo = std::min(a_lo, p.a), a_hi = std::max(a_hi, p.a);
      b_lo = std::min(b_lo, p.b), b_hi = std::max(b_hi, p.b);
    }
  if (!(a_hi > a_lo)) a_lo -= 0.5, a_hi += 0.5;
  if (!(b_hi > b_lo)) b_lo -= 0.5, b_hi += 0.5;
  const double a_step = picture::NiceStep(a_hi - a_lo, 6), b_step = picture::NiceStep(b_hi - b_lo, 6);
  a_lo = std::floor(a_lo / a_step) * a_step, a_hi = std::ceil(a_hi / a_step) * a_step;
  b_lo = std::floor(b_lo / b_step) * b_step, b_hi = std::ceil(b_hi / b_step) * b_step;

  using picture::Canvas;
  Canvas img(options.width, options.height);
  const int left = 100, right = options.width - 30, top = 50, bottom = options.height - 70;
  const auto X = [&](double a) { return left + (right - left) * (a - a_lo) / (a_hi - a_lo); };
  const auto Y = [&](double b) { return bottom - (bottom - top) * (b - b_lo) / (b_hi - b_lo); };
  for (double v = a_lo; v <= a_hi + 1e-9 * a_step; v += a_step) {
    img.Line(X(v), top, X(v), bottom, 0xEEEEEE, 1);
    const std::string t = picture::TickLabel(v);
    img.Text(static_cast<int>(X(v)) - Canvas::TextWidth(t) / 2, bottom + 10, t, 0x333333);
  }
  for (double v = b_lo; v <= b_hi + 1e-9 * b_step; v += b_step) {
    img.Line(left, Y(v), right, Y(v), 0xEEEEEE, 1);
    const std::string t = picture::TickLabel(v);
    img.Text(left - 10 - Canvas::TextWidth(t), static_cast<int>(Y(v)) - 6, t, 0x333333);
  }
  img.Line(left, top, left, bottom, 0x000000, 2);
  img.Line(left, bottom, right, bottom, 0x000000, 2);
  img.Text(left + (right - left) / 2 - Canvas::TextWidth(front.a) / 2, bottom + 40, front.a, 0x000000);
  img.Text(10, top - 30, front.b, 0x000000);
  const std::string title = (options.title.empty() ? std::string() : options.title + ": ") + "Pareto front of " +
                            front.a + " and " + front.b + " (" + std::to_string(front.points.size()) + " of " +
                            std::to_string(front.candidates) + " valid samples)";
  img.Text(left, 12, title, 0x000000);
  for (const auto& p : front.dominated)
    img.Rect(static_cast<int>(X(p.a)) - 1, static_cast<int>(Y(p.b)) - 1, static_cast<int>(X(p.a)) + 2,
             static_cast<int>(Y(p.b)) + 2, 0xAAAAAA);
  // A staircase: from each point along a to the next one's a, then along b.
  for (std::size_t k = 1; k < front.points.size(); ++k) {
    const auto &p = front.points[k - 1], &q = front.points[k];
    img.Line(X(p.a), Y(p.b), X(q.a), Y(p.b), 0x1F5FA8, 2);
    img.Line(X(q.a), Y(p.b), X(q.a), Y(q.b), 0x1F5FA8, 2);
  }
  for (const auto& p : front.points)
    img.Rect(static_cast<int>(X(p.a)) - 3, static_cast<int>(Y(p.b)) - 3, static_cast<int>(X(p.a)) + 4,
             static_cast<int>(Y(p.b)) + 4, 0x1F5FA8);
  img.WritePng(path);
}

}  // namespace fabatlas::viewer
