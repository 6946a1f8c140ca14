#include "leaf_search.h"

#include <cmath>

namespace fabatlas::viewer::internal {

using sampling::DesignSpace;
using sampling::Form;
using sampling::FormNode;

std::optional<std::vector<double>> KeyCoordinates(const DesignSpace& space, const std::vector<double>& u) {
  const int n = space.dimension_count();
  if (static_cast<int>(u.size()) != n) return std::nullopt;
  std::vector<double> x(n);
  for (int d = 0; d < n; ++d) {
    if (!std::isfinite(u[d])) return std::nullopt;
    x[d] = space.key_coordinate(d, u[d]);
    const double tolerance = 1e-9 * static_cast<double>(space.grid_key(d, 1) - space.grid_key(d, 0));
    const double nearest = std::round(x[d]);
    if (std::abs(x[d] - nearest) <= tolerance) x[d] = nearest;
    if (!(x[d] >= static_cast<double>(space.key_lo(d)) && x[d] <= static_cast<double>(space.key_hi(d))))
      return std::nullopt;
  }
  return x;
}

namespace {

void Descend(const sampling::FormTree& tree, int tree_index, int node, const std::vector<double>& x,
             const std::vector<bool>& free, std::vector<LeafHit>& out) {
  const FormNode& nd = tree.nodes[node];
  if (nd.split_dimension < 0) {
    out.push_back({&nd, tree_index, node});
    return;
  }
  const int e = nd.split_dimension;
  const double split = static_cast<double>(nd.split_key);
  if (free[e] || x[e] <= split) Descend(tree, tree_index, nd.children[0], x, free, out);
  if (free[e] || x[e] >= split) Descend(tree, tree_index, nd.children[1], x, free, out);
}

}  // namespace

std::vector<LeafHit> LeavesTouching(const Form& form, const DesignSpace& space, const std::vector<double>& x,
                                    int free_dimension) {
  std::vector<bool> free(space.dimension_count(), false);
  if (free_dimension >= 0) free[free_dimension] = true;
  return LeavesMeeting(form, space, x, free);
}

std::vector<LeafHit> LeavesMeeting(const Form& form, const DesignSpace& space, const std::vector<double>& x,
                                   const std::vector<bool>& free) {
  const int n = space.dimension_count();
  // Candidate bootstrap cells per dimension (two where x is on a grid line).
  std::vector<std::vector<int>> cells(n);
  for (int d = 0; d < n; ++d) {
    for (int j = 0; j < space.cell_count(d); ++j) {
      if (free[d] ||
          (x[d] >= static_cast<double>(space.grid_key(d, j)) && x[d] <= static_cast<double>(space.grid_key(d, j + 1))))
        cells[d].push_back(j);
    }
  }
  std::vector<LeafHit> out;
  std::vector<size_t> pick(n, 0);
  for (;;) {
    int tree = 0;
    for (int d = 0; d < n; ++d) tree = tree * space.cell_count(d) + cells[d][pick[d]];
    Descend(form.trees[tree], tree, 0, x, free, out);
    int d = n - 1;
    while (d >= 0 && ++pick[d] == cells[d].size()) pick[d--] = 0;
    if (d < 0) break;
  }
  return out;
}

bool FaceAllValid(const Form& form, const FormNode& leaf, const std::int32_t* corners, const std::vector<double>& x,
                  int free_dimension, std::vector<std::string>* failures) {
  const int n = static_cast<int>(leaf.lo.size());
  // fixed[d]: -1 free, 0 corner must be on lo side, 1 on hi side.
  std::vector<int> fixed(n, -1);
  for (int d = 0; d < n; ++d) {
    if (d == free_dimension) continue;
    if (x[d] == static_cast<double>(leaf.lo[d]))
      fixed[d] = 0;
    else if (x[d] == static_cast<double>(leaf.hi[d]))
      fixed[d] = 1;
  }
  bool all_valid = true;
  for (size_t c = 0; c < (size_t{1} << n); ++c) {
    bool on_face = true;
    for (int d = 0; d < n && on_face; ++d)
      if (fixed[d] >= 0 && fixed[d] != static_cast<int>((c >> d) & 1)) on_face = false;
    if (!on_face) continue;
    const auto& sample = form.samples[corners[c]];
    if (!sample.outcome.valid) {
      all_valid = false;
      if (!failures) return false;
      failures->push_back(sample.outcome.failure_type.empty() ? "invalid" : sample.outcome.failure_type);
    }
  }
  return all_valid;
}

}  // namespace fabatlas::viewer::internal
