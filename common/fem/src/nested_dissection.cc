// Geometric nested dissection of a hexahedral mesh (nested_dissection.h).
#include "fabatlas/fem/nested_dissection.h"

#include <algorithm>
#include <cstdint>

namespace fabatlas::fem {

namespace {

constexpr std::size_t kLeafNodes = 16;

class Dissection {
 public:
  explicit Dissection(const HexMesh& mesh) : mesh_(mesh), part_(mesh.nodes.size(), 0) {
    // Node adjacency: two nodes are neighbours when they share an element.
    const std::size_t nn = mesh.nodes.size();
    std::vector<std::vector<int>> nbr(nn);
    for (const auto& el : mesh.elements)
      for (int a : el)
        for (int b : el)
          if (a != b) nbr[a].push_back(b);
    offset_.assign(nn + 1, 0);
    for (std::size_t n = 0; n < nn; ++n) {
      auto& v = nbr[n];
      std::sort(v.begin(), v.end());
      v.erase(std::unique(v.begin(), v.end()), v.end());
      offset_[n + 1] = offset_[n] + v.size();
    }
    adjacent_.reserve(offset_[nn]);
    for (auto& v : nbr) {
      adjacent_.insert(adjacent_.end(), v.begin(), v.end());
      std::vector<int>().swap(v);
    }
    order_.reserve(nn);
  }

  std::vector<int> Run() {
    std::vector<int> all(mesh_.nodes.size());
    for (std::size_t n = 0; n < all.size(); ++n) all[n] = static_cast<int>(n);
    Order(std::move(all));
    return std::move(order_);
  }

 private:
  // Appends the nodes of `part` (ascending indices) to order_: lower part,
  // upper part less the separator, separator.
  void Order(std::vector<int> part) {
    if (part.size() <= kLeafNodes) {
      order_.insert(order_.end(), part.begin(), part.end());
      return;
    }
    // The split: along each axis, every node layer (distinct coordinate)
    // that leaves at least a third of the part on either side is a
    // candidate; its node count bounds the separator (on voxel meshes it is
    // the separator). The smallest wins; ties go to the more balanced split,
    // then to the lower axis.
    int axis = -1;
    double split = 0;
    std::size_t best_layer = 0, best_imbalance = 0;
    std::vector<double> coordinate(part.size());
    for (int k = 0; k < 3; ++k) {
      for (std::size_t i = 0; i < part.size(); ++i) coordinate[i] = mesh_.nodes[part[i]][k];
      std::sort(coordinate.begin(), coordinate.end());
      for (std::size_t i = 0; i < coordinate.size();) {
        std::size_t j = i;
        while (j < coordinate.size() && coordinate[j] == coordinate[i]) ++j;
        const std::size_t below = i, layer = j - i, above = coordinate.size() - j;
        if (3 * below >= part.size() && 3 * (layer + above) >= part.size()) {
          const std::size_t imbalance = below > layer + above ? below - layer - above : layer + above - below;
          if (axis < 0 || layer < best_layer || (layer == best_layer && imbalance < best_imbalance)) {
            axis = k;
            split = coordinate[i];
            best_layer = layer;
            best_imbalance = imbalance;
          }
        }
        i = j;
      }
    }
    if (axis < 0) {  // no balanced layer (e.g. all nodes on one or two layers)
      order_.insert(order_.end(), part.begin(), part.end());
      return;
    }
    std::vector<int> lower, upper, separator;
    for (int n : part) (mesh_.nodes[n][axis] < split ? lower : upper).push_back(n);
    std::vector<int>().swap(part);
    for (int n : lower) part_[n] = 1;
    std::vector<int> rest;  // the upper part less the separator
    for (int n : upper) {
      bool touches = false;
      for (std::size_t i = offset_[n]; i < offset_[n + 1] && !touches; ++i) touches = part_[adjacent_[i]] == 1;
      (touches ? separator : rest).push_back(n);
    }
    for (int n : lower) part_[n] = 0;
    std::vector<int>().swap(upper);
    Order(std::move(lower));
    Order(std::move(rest));
    order_.insert(order_.end(), separator.begin(), separator.end());
  }

  const HexMesh& mesh_;
  std::vector<std::size_t> offset_;  // CSR adjacency
  std::vector<int> adjacent_;
  std::vector<std::uint8_t> part_;  // 1: in the lower part being split
  std::vector<int> order_;
};

}  // namespace

std::vector<int> NestedDissectionOrder(const HexMesh& mesh) { return Dissection(mesh).Run(); }

}  // namespace fabatlas::fem
