// fabatlas/cache/starting_points.h — customisation starting points (Fab Forms
// Sec. 7.4).
//
// The graph: every valid sample of the form; an edge between two valid
// samples that are the ends of an edge of a leaf hypercube, weighted by the
// ΔG stored for them. Randomised farthest-point sampling with graph distance
// (Dijkstra) picks `count` seeds: the first uniformly at random (std::mt19937_64
// seeded with `seed`), each next one the sample farthest from all seeds so
// far, where a sample of a component without a seed is infinitely far (so
// every connected component gets a seed; ties to the lower sample id). Every
// sample joins its nearest seed's segment; the starting point of a segment is
// its graph centroid: the sample with the least sum of graph distances to
// the segment's samples, within the segment.
#pragma once

#include <cstdint>
#include <vector>

#include "fabatlas/sampling/form.h"

namespace fabatlas::cache {

struct StartingPointOptions {
  int count = 8;           // seeds; raised to the number of components
  std::uint64_t seed = 1;  // random seed of the first pick
  // Segments with up to this many samples get the exact centroid (one
  // Dijkstra per sample). Larger ones start at the middle of a double sweep
  // (farthest from the seed, then farthest from that) and move to a
  // neighbour while the sum of distances drops (a local minimum).
  std::int64_t max_exact_centroid = 2000;
};

struct StartingPoint {
  std::int64_t sample_id = -1;  // form sample id
  std::vector<double> u;        // its coordinates (form.samples[id].u)
  std::int64_t seed_id = -1;    // the farthest-point seed of its segment
  int component = -1;           // connected component, numbered by lowest sample id
  std::int64_t segment_size = 0;
};

// In order of the seeds' picks. Empty when the form has no valid sample.
std::vector<StartingPoint> ChooseStartingPoints(const sampling::Form& form, const StartingPointOptions& options = {});

}  // namespace fabatlas::cache
