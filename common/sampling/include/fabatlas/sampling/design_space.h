// fabatlas/sampling/design_space.h — the exposed-parameter space U of a design
// and its bootstrap grid (Fab Forms, Sec. 5: "We bootstrap adaptive sampling by
// uniformly sampling U inside the region bounded by the rough ranges").
//
// A point of U is identified by an exact integer PointKey, one integer per
// dimension, so that vertices shared by neighbouring cells and leaves are the
// same sample (evaluated once) and results are bit-for-bit reproducible:
//   * real dimension [lo,hi] with m bootstrap cells: key = dyadic tick, the
//     value is lo + (hi-lo) * key / (m * 2^kDyadicBits). A bootstrap cell spans
//     2^kDyadicBits ticks, so a real dimension can be halved kDyadicBits times.
//   * integer dimension [lo,hi]: key = the integer value itself.
//   * enumerated dimension with k values: key = the value's index 0..k-1.
// Discrete dimensions are split only at integer keys (never between values).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace fabatlas::sampling {

enum class DimensionKind { kReal, kInteger, kEnumerated };

// The kind's name in every file format ("real", "integer", "enumerated"), and
// back; DimensionKindFromName returns false for any other text.
const char* DimensionKindName(DimensionKind kind);
bool DimensionKindFromName(const std::string& name, DimensionKind* kind);

// One exposed parameter. For kReal and kInteger, [lo, hi] is the designer's
// rough range (hi > lo; integers must be whole numbers). For kEnumerated,
// `values` holds the k >= 2 value names and lo/hi are ignored (0 and k-1).
struct Dimension {
  std::string name;
  DimensionKind kind = DimensionKind::kReal;
  double lo = 0.0;
  double hi = 1.0;
  std::vector<std::string> values;  // kEnumerated only
};

using PointKey = std::vector<std::int64_t>;

// Most exposed parameters a design space may have. A k-d leaf has 2^d
// corner samples, so the bootstrap grid alone holds (subdivisions + 1)^d
// samples: 8 dimensions at subdivisions 2 is 6,561, at 5 it is 1.7 million.
inline constexpr int kMaxDimensions = 16;

// Number of halvings a real bootstrap cell supports (ticks per cell = 2^40).
inline constexpr int kDyadicBits = 40;

// The design space plus its bootstrap grid. Immutable after construction.
class DesignSpace {
 public:
  // No dimension is a space of one point (a design with nothing exposed: one
  // bootstrap cell, one sample, the empty key).
  // Throws fabatlas::InputError (one line naming the dimension) for more than
  // kMaxDimensions dimensions, hi <= lo, non-integer bounds of an
  // integer dimension, fewer than two enumerated values, duplicate names, or
  // subdivisions < 1.
  // `subdivisions`: bootstrap cells per dimension (Fab Forms suggests 5-7);
  // an integer/enumerated dimension gets min(subdivisions, values - 1) cells.
  explicit DesignSpace(std::vector<Dimension> dimensions, int subdivisions = 5);

  int dimension_count() const { return static_cast<int>(dimensions_.size()); }
  const std::vector<Dimension>& dimensions() const { return dimensions_; }
  const Dimension& dimension(int d) const { return dimensions_[d]; }
  int subdivisions() const { return subdivisions_; }

  // Bootstrap cells along dimension d.
  int cell_count(int d) const { return cell_counts_[d]; }
  // Key of the j-th bootstrap grid line along d (j = 0..cell_count(d)).
  std::int64_t grid_key(int d, int j) const;
  // Smallest and largest key along d.
  std::int64_t key_lo(int d) const { return grid_key(d, 0); }
  std::int64_t key_hi(int d) const { return grid_key(d, cell_counts_[d]); }

  bool is_discrete(int d) const { return dimensions_[d].kind != DimensionKind::kReal; }
  // Parameter value of key k along d (enumerated: the index as a double).
  double value(int d, std::int64_t key) const;
  // The point u of a key (one value per dimension).
  std::vector<double> point(const PointKey& key) const;
  // Length along d of the key interval [a, b] in parameter units (discrete
  // dimensions: number of value steps b - a). Used for valid-volume %.
  double length(int d, std::int64_t a, std::int64_t b) const;
  // Whether [a, b] along d can be halved, and where (key of the midpoint).
  bool can_split(int d, std::int64_t a, std::int64_t b) const;
  std::int64_t split_key(int d, std::int64_t a, std::int64_t b) const;

  // Inverse of value() for locating points: the key interval containment test
  // is done in parameter space, so this returns the continuous key coordinate.
  double key_coordinate(int d, double value) const;

 private:
  std::vector<Dimension> dimensions_;
  int subdivisions_;
  std::vector<int> cell_counts_;
};

}  // namespace fabatlas::sampling
