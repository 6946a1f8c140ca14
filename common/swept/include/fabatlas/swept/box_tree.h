// fabatlas/swept/box_tree.h — a bounding volume hierarchy over axis-aligned
// boxes in D dimensions: the spacetime proxies' 4D boxes of
// spacetime_collision.cc (Reconfigurables Sec. 5) and the triangle boxes of
// the dense swept-volume baseline in bench/swept.
//
// Build: each node's box bounds its boxes; a node of more than 4 boxes is
// split at the median of their centres along its widest axis (nth_element,
// so the tree is a pure function of the boxes and their order). O(n log n)
// time, O(n) memory. Traversal is the caller's: nodes()[0] is the root, a
// leaf (count > 0) holds items order()[first .. first + count).
//
// Threading: built by one thread; const methods may be called concurrently.
#pragma once

#include <algorithm>
#include <array>
#include <numeric>
#include <utility>
#include <vector>

namespace fabatlas::swept {

template <int D>
class BoxTree {
 public:
  using Box = std::array<std::array<double, D>, 2>;  // {min, max}
  struct Node {
    Box box;
    int left = -1, right = -1;  // children (inner nodes)
    int first = 0, count = 0;   // items order()[first, first + count) (leaves)
  };

  // Input: one box per item, item i = boxes[i]. An empty input gives a tree
  // without nodes.
  explicit BoxTree(std::vector<Box> boxes) : boxes_(std::move(boxes)), order_(boxes_.size()) {
    std::iota(order_.begin(), order_.end(), 0);
    nodes_.reserve(2 * boxes_.size());
    if (!boxes_.empty()) Build(0, static_cast<int>(boxes_.size()));
  }

  const std::vector<Node>& nodes() const { return nodes_; }
  const std::vector<int>& order() const { return order_; }
  const Box& box(int item) const { return boxes_[item]; }

 private:
  int Build(int first, int last) {
    const int id = static_cast<int>(nodes_.size());
    nodes_.emplace_back();
    Node n;
    n.box = boxes_[order_[first]];
    for (int i = first + 1; i < last; ++i)
      for (int k = 0; k < D; ++k) {
        n.box[0][k] = std::min(n.box[0][k], boxes_[order_[i]][0][k]);
        n.box[1][k] = std::max(n.box[1][k], boxes_[order_[i]][1][k]);
      }
    if (last - first <= 4) {
      n.first = first;
      n.count = last - first;
      nodes_[id] = n;
      return id;
    }
    int axis = 0;
    for (int k = 1; k < D; ++k)
      if (n.box[1][k] - n.box[0][k] > n.box[1][axis] - n.box[0][axis]) axis = k;
    const int mid = (first + last) / 2;
    std::nth_element(order_.begin() + first, order_.begin() + mid, order_.begin() + last, [&](int a, int b) {
      return boxes_[a][0][axis] + boxes_[a][1][axis] < boxes_[b][0][axis] + boxes_[b][1][axis];
    });
    n.left = Build(first, mid);
    n.right = Build(mid, last);
    nodes_[id] = n;
    return id;
  }

  std::vector<Box> boxes_;
  std::vector<int> order_;
  std::vector<Node> nodes_;
};

}  // namespace fabatlas::swept
