#include "fabatlas/sampling/design_space.h"

#include <algorithm>
#include <cmath>
#include <set>

#include "fabatlas/error.h"

namespace fabatlas::sampling {

const char* DimensionKindName(DimensionKind kind) {
  switch (kind) {
    case DimensionKind::kReal:
      return "real";
    case DimensionKind::kInteger:
      return "integer";
    case DimensionKind::kEnumerated:
      return "enumerated";
  }
  return "real";
}

bool DimensionKindFromName(const std::string& name, DimensionKind* kind) {
  for (DimensionKind k : {DimensionKind::kReal, DimensionKind::kInteger, DimensionKind::kEnumerated})
    if (name == DimensionKindName(k)) {
      *kind = k;
      return true;
    }
  return false;
}

namespace {
constexpr std::int64_t kTicksPerCell = std::int64_t{1} << kDyadicBits;

std::int64_t DiscreteLo(const Dimension& d) {
  return d.kind == DimensionKind::kEnumerated ? 0 : static_cast<std::int64_t>(d.lo);
}
std::int64_t DiscreteHi(const Dimension& d) {
  return d.kind == DimensionKind::kEnumerated ? static_cast<std::int64_t>(d.values.size()) - 1
                                              : static_cast<std::int64_t>(d.hi);
}
}  // namespace

DesignSpace::DesignSpace(std::vector<Dimension> dimensions, int subdivisions)
    : dimensions_(std::move(dimensions)), subdivisions_(subdivisions) {
  if (dimensions_.size() > static_cast<std::size_t>(kMaxDimensions))
    throw InputError("design space: " + std::to_string(dimensions_.size()) + " exposed parameters, at most " +
                     std::to_string(kMaxDimensions) + " are supported");
  if (subdivisions_ < 1 || subdivisions_ > 1000)
    throw InputError("design space: subdivisions must be in [1, 1000], got " + std::to_string(subdivisions_));
  std::set<std::string> names;
  for (auto& d : dimensions_) {
    const std::string where = "design space: parameter '" + d.name + "': ";
    if (d.name.empty()) throw InputError("design space: a parameter has no name");
    if (!names.insert(d.name).second) throw InputError(where + "duplicate name");
    switch (d.kind) {
      case DimensionKind::kReal:
        if (!std::isfinite(d.lo) || !std::isfinite(d.hi) || !(d.hi > d.lo))
          throw InputError(where + "range must be finite with hi > lo");
        cell_counts_.push_back(subdivisions_);
        break;
      case DimensionKind::kInteger:
        if (d.lo != std::floor(d.lo) || d.hi != std::floor(d.hi) || std::abs(d.lo) > 1e15 || std::abs(d.hi) > 1e15)
          throw InputError(where + "integer range bounds must be whole numbers");
        if (!(d.hi > d.lo)) throw InputError(where + "range must have hi > lo");
        cell_counts_.push_back(static_cast<int>(std::min<std::int64_t>(subdivisions_, DiscreteHi(d) - DiscreteLo(d))));
        break;
      case DimensionKind::kEnumerated:
        if (d.values.size() < 2) throw InputError(where + "needs at least two values");
        d.lo = 0.0;
        d.hi = static_cast<double>(d.values.size() - 1);
        cell_counts_.push_back(static_cast<int>(std::min<std::int64_t>(subdivisions_, DiscreteHi(d) - DiscreteLo(d))));
        break;
    }
  }
}

std::int64_t DesignSpace::grid_key(int d, int j) const {
  const Dimension& dim = dimensions_[d];
  if (dim.kind == DimensionKind::kReal) return static_cast<std::int64_t>(j) * kTicksPerCell;
  const std::int64_t lo = DiscreteLo(dim), hi = DiscreteHi(dim);
  return lo + (static_cast<std::int64_t>(j) * (hi - lo)) / cell_counts_[d];
}

double DesignSpace::value(int d, std::int64_t key) const {
  const Dimension& dim = dimensions_[d];
  if (dim.kind != DimensionKind::kReal) return static_cast<double>(key);
  const double total = static_cast<double>(cell_counts_[d]) * static_cast<double>(kTicksPerCell);
  if (key == static_cast<std::int64_t>(cell_counts_[d]) * kTicksPerCell) return dim.hi;
  return dim.lo + (dim.hi - dim.lo) * (static_cast<double>(key) / total);
}

std::vector<double> DesignSpace::point(const PointKey& key) const {
  std::vector<double> u(key.size());
  for (size_t d = 0; d < key.size(); ++d) u[d] = value(static_cast<int>(d), key[d]);
  return u;
}

double DesignSpace::length(int d, std::int64_t a, std::int64_t b) const {
  if (!is_discrete(d)) return value(d, b) - value(d, a);
  return static_cast<double>(b - a);
}

bool DesignSpace::can_split(int, std::int64_t a, std::int64_t b) const { return b - a >= 2; }

std::int64_t DesignSpace::split_key(int, std::int64_t a, std::int64_t b) const { return a + (b - a) / 2; }

double DesignSpace::key_coordinate(int d, double v) const {
  const Dimension& dim = dimensions_[d];
  if (dim.kind != DimensionKind::kReal) return v;
  const double total = static_cast<double>(cell_counts_[d]) * static_cast<double>(kTicksPerCell);
  return (v - dim.lo) / (dim.hi - dim.lo) * total;
}

}  // namespace fabatlas::sampling
