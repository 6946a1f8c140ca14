#include "fabatlas/sampling/form.h"

#include <cmath>

namespace fabatlas::sampling {

std::vector<std::int64_t> CornerSampleIds(const Form& form, const FormNode& node) {
  const int n = static_cast<int>(node.lo.size());
  std::vector<std::int64_t> ids(size_t{1} << n);
  PointKey key(n);
  for (size_t c = 0; c < ids.size(); ++c) {
    for (int d = 0; d < n; ++d) key[d] = (c >> d) & 1 ? node.hi[d] : node.lo[d];
    ids[c] = form.sample_ids.at(key);
  }
  return ids;
}

bool IsAllValidLeaf(const Form& form, const FormNode& node) {
  for (std::int64_t id : CornerSampleIds(form, node))
    if (!form.samples[id].outcome.valid) return false;
  return true;
}

std::optional<LeafRef> LocateLeaf(const Form& form, const std::vector<double>& u) {
  return LocateLeaf(form, form.space(), u);
}

std::optional<LeafRef> LocateLeaf(const Form& form, const DesignSpace& space, const std::vector<double>& u) {
  const int n = space.dimension_count();
  if (static_cast<int>(u.size()) != n) return std::nullopt;
  std::vector<double> x(n);
  int tree = 0;
  for (int d = 0; d < n; ++d) {
    x[d] = space.key_coordinate(d, u[d]);
    if (!(x[d] >= static_cast<double>(space.key_lo(d)) && x[d] <= static_cast<double>(space.key_hi(d))))
      return std::nullopt;
    int j = 0;
    while (j + 1 < space.cell_count(d) && x[d] >= static_cast<double>(space.grid_key(d, j + 1))) ++j;
    tree = tree * space.cell_count(d) + j;
  }
  const FormTree& t = form.trees[tree];
  int node = 0;
  while (t.nodes[node].split_dimension >= 0) {
    const FormNode& nd = t.nodes[node];
    node = x[nd.split_dimension] >= static_cast<double>(nd.split_key) ? nd.children[1] : nd.children[0];
  }
  return LeafRef{tree, node};
}

bool InEstimatedValidRegion(const Form& form, const std::vector<double>& u) {
  return InEstimatedValidRegion(form, form.space(), u);
}

bool InEstimatedValidRegion(const Form& form, const DesignSpace& space, const std::vector<double>& u) {
  const auto leaf = LocateLeaf(form, space, u);
  if (!leaf) return false;
  return IsAllValidLeaf(form, form.trees[leaf->tree].nodes[leaf->node]);
}

}  // namespace fabatlas::sampling
