// fabatlas/viewer/leaf_corners.h — the sample ids at the 2^n corners of every
// leaf of a form's k-d trees, looked up once when a form is loaded.
//
// The validity lookups (valid_region.h) read the corners of every leaf the
// query touches. Finding a corner through Form::sample_ids costs a search of
// a map keyed by n-vectors; on a 10^5-sample form that was most of an
// interval lookup's time. The table answers each corner with one array read.
//
// Memory: one int32 per node of every tree (the leaf's row, -1 for interior
// nodes) plus 2^n int32 ids per leaf: 4 (2 + 2^n) bytes per leaf for n
// dimensions, 40 B for n = 3 (a k-d tree has one interior node fewer than it
// has leaves). Building it costs one Form::sample_ids search per corner
// (O(leaves 2^n log samples)), single-threaded.
//
// A table fits every form with the same trees and sample ids as the one it
// was built from, e.g. the copies viewer::ApplyLimits makes (they change
// validity only).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "fabatlas/sampling/form.h"

namespace fabatlas::viewer {

class LeafCorners {
 public:
  // Throws fabatlas::InputError if a leaf corner has no sample or the form
  // has 2^31 samples or more.
  explicit LeafCorners(const sampling::Form& form);

  // The 2^n corner ids of leaf `node` of tree `tree`, in the order of
  // sampling::CornerSampleIds (corner c has bit d set on the hi side along
  // d). The node must be a leaf of the form the table was built from.
  const std::int32_t* of(int tree, int node) const {
    return corners_.data() + static_cast<std::size_t>(rows_[first_node_[tree] + node]) * per_leaf_;
  }
  // True if the table can serve `form`: same number of trees, nodes and samples.
  bool Fits(const sampling::Form& form) const;
  // Heap bytes of the table.
  std::size_t bytes() const;
  std::size_t leaves() const { return per_leaf_ ? corners_.size() / per_leaf_ : 0; }

 private:
  std::size_t per_leaf_ = 0;  // 2^n
  std::size_t samples_ = 0;
  std::vector<std::size_t> first_node_;  // per tree, index of its node 0 in rows_
  std::vector<std::int32_t> rows_;       // per node: leaf row, -1 interior
  std::vector<std::int32_t> corners_;    // per leaf row: 2^n sample ids
};

}  // namespace fabatlas::viewer
