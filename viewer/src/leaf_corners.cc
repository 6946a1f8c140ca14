#include "fabatlas/viewer/leaf_corners.h"

#include <limits>
#include <string>

#include "fabatlas/error.h"

namespace fabatlas::viewer {

LeafCorners::LeafCorners(const sampling::Form& form) : samples_(form.samples.size()) {
  if (form.samples.size() > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max()))
    throw InputError("the form has " + std::to_string(form.samples.size()) +
                     " samples; the viewer's corner table holds at most 2^31 - 1");
  per_leaf_ = std::size_t{1} << form.dimensions.size();
  std::size_t nodes = 0, leaves = 0;
  first_node_.reserve(form.trees.size());
  for (const sampling::FormTree& tree : form.trees) {
    first_node_.push_back(nodes);
    nodes += tree.nodes.size();
    for (const sampling::FormNode& node : tree.nodes) leaves += node.split_dimension < 0;
  }
  rows_.reserve(nodes);
  corners_.reserve(leaves * per_leaf_);
  std::int32_t row = 0;
  for (const sampling::FormTree& tree : form.trees)
    for (const sampling::FormNode& node : tree.nodes) {
      if (node.split_dimension >= 0) {
        rows_.push_back(-1);
        continue;
      }
      rows_.push_back(row++);
      try {
        for (const std::int64_t id : sampling::CornerSampleIds(form, node))
          corners_.push_back(static_cast<std::int32_t>(id));
      } catch (const std::out_of_range&) {
        throw InputError("the form has a leaf with a corner that is not a sample");
      }
    }
}

bool LeafCorners::Fits(const sampling::Form& form) const {
  if (form.trees.size() != first_node_.size() || form.samples.size() != samples_) return false;
  const std::size_t last = form.trees.empty() ? 0 : first_node_.back() + form.trees.back().nodes.size();
  return last == rows_.size();
}

std::size_t LeafCorners::bytes() const {
  return first_node_.capacity() * sizeof(std::size_t) + rows_.capacity() * sizeof(std::int32_t) +
         corners_.capacity() * sizeof(std::int32_t);
}

}  // namespace fabatlas::viewer
