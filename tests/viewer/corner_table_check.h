// The viewer's corner table (viewer/leaf_corners.h) against the path it
// replaces, on any form: every leaf's row equals sampling::CornerSampleIds
// (the search of Form::sample_ids the lookups made per query before), and at
// random points the lookups through the table agree with
// sampling::InEstimatedValidRegion, which finds the leaf and its corners
// through Form::sample_ids.
#pragma once

#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "fabatlas/sampling/form.h"
#include "fabatlas/viewer/leaf_corners.h"
#include "fabatlas/viewer/valid_region.h"

namespace fabatlas::viewer {

inline void ExpectCornerTableMatchesSampleIdSearch(const sampling::Form& form, const LeafCorners& corners, int points) {
  const sampling::DesignSpace space = form.space();
  ASSERT_TRUE(corners.Fits(form));
  std::size_t leaves = 0;
  for (int t = 0; t < static_cast<int>(form.trees.size()); ++t)
    for (int i = 0; i < static_cast<int>(form.trees[t].nodes.size()); ++i) {
      const sampling::FormNode& node = form.trees[t].nodes[i];
      if (node.split_dimension >= 0) continue;
      ++leaves;
      const std::vector<std::int64_t> expected = sampling::CornerSampleIds(form, node);
      const std::vector<std::int64_t> got(corners.of(t, i), corners.of(t, i) + expected.size());
      ASSERT_EQ(got, expected) << "tree " << t << " node " << i;
    }
  EXPECT_EQ(corners.leaves(), leaves);

  // Random points lie inside a leaf (almost surely), where the valid region
  // is the all-valid leaves; a stretch's midpoint lies inside one too.
  std::mt19937_64 rng(7);
  int valid = 0, invalid = 0;
  for (int k = 0; k < points; ++k) {
    std::vector<double> u;
    for (const auto& d : form.dimensions) u.push_back(std::uniform_real_distribution<double>(d.lo, d.hi)(rng));
    const bool expected = sampling::InEstimatedValidRegion(form, space, u);
    ASSERT_EQ(IsValidPoint(form, space, corners, u), expected) << "point " << k;
    EXPECT_EQ(FailuresAt(form, space, corners, u).empty(), expected) << "point " << k;
    (expected ? valid : invalid) += 1;
    for (int d = 0; d < space.dimension_count(); ++d)
      for (const Stretch& s : LineStretches(form, space, corners, u, d)) {
        if (!(s.lo < s.hi)) continue;
        std::vector<double> mid = u;
        mid[d] = 0.5 * (s.lo + s.hi);
        EXPECT_EQ(sampling::InEstimatedValidRegion(form, space, mid), s.valid) << "point " << k << " dimension " << d;
      }
  }
  // Both answers occurred: the comparison could fail either way.
  EXPECT_GT(valid, points / 20);
  EXPECT_GT(invalid, points / 20);
}

}  // namespace fabatlas::viewer
