// fabatlas/viewer/starting_points.h — customisation starting points (seed
// 001, Sec. 7.4 "Navigating the Valid Region", Fig. 12).
#pragma once

#include <cstdint>
#include <vector>

#include "fabatlas/sampling/form.h"

namespace fabatlas::viewer {

struct StartingPointOptions {
  int count = 6;              // at most this many points (fewer if fewer valid samples)
  unsigned seed = 1;          // the farthest-point sampling's first pick
  int centroid_candidates = 64;  // per region, nodes tried as its centroid
};

// The graph: every valid sample is a node; two valid corners of a leaf that
// share a leaf edge are joined with weight ΔG (cached by the sampler; a small
// epsilon keeps ΔG = 0 edges from collapsing distances). Randomised
// farthest-point sampling with graph distance (Dijkstra; unreachable counts
// as farthest, so every connected component gets a seed first) picks up to
// `count` seeds; each valid sample joins its nearest seed's region; the
// starting point of a region is its graph centroid (the candidate node with
// the least sum of distances to the region's nodes). Returns sample ids,
// ordered by region size, largest first. Deterministic for a given seed.
std::vector<std::int64_t> StartingPoints(const sampling::Form& form, const StartingPointOptions& options = {});

}  // namespace fabatlas::viewer
