#include "fabatlas/viewer/valid_region.h"

#include <algorithm>
#include <set>
#include <stdexcept>

#include "fabatlas/error.h"
#include "leaf_search.h"

namespace fabatlas::viewer {

using sampling::DesignSpace;
using sampling::Form;
using sampling::FormNode;

namespace {

void RequireFits(const LeafCorners& corners, const Form& form) {
  if (!corners.Fits(form))
    throw std::invalid_argument("viewer: the corner table was built from a form with other trees or samples");
}

}  // namespace

bool IsValidPoint(const Form& form, const DesignSpace& space, const LeafCorners& corners,
                  const std::vector<double>& u) {
  RequireFits(corners, form);
  const auto x = internal::KeyCoordinates(space, u);
  if (!x) return false;
  for (const internal::LeafHit& leaf : internal::LeavesTouching(form, space, *x))
    if (internal::FaceAllValid(form, *leaf.node, corners.of(leaf.tree, leaf.index), *x, -1)) return true;
  return false;
}

std::vector<std::string> FailuresAt(const Form& form, const DesignSpace& space, const LeafCorners& corners,
                                    const std::vector<double>& u) {
  RequireFits(corners, form);
  const auto x = internal::KeyCoordinates(space, u);
  if (!x) return {};
  std::vector<std::string> failures;
  for (const internal::LeafHit& leaf : internal::LeavesTouching(form, space, *x))
    if (internal::FaceAllValid(form, *leaf.node, corners.of(leaf.tree, leaf.index), *x, -1, &failures)) return {};
  std::set<std::string> distinct(failures.begin(), failures.end());
  return {distinct.begin(), distinct.end()};
}

std::vector<Stretch> LineStretches(const Form& form, const DesignSpace& space, const LeafCorners& corners,
                                   const std::vector<double>& u, int dimension) {
  RequireFits(corners, form);
  const int n = space.dimension_count();
  if (dimension < 0 || dimension >= n)
    throw InputError("dimension index " + std::to_string(dimension) + " out of range");
  auto x = internal::KeyCoordinates(space, u);
  if (!x) throw InputError("point outside the design space (or wrong number of coordinates)");
  const int d = dimension;
  const std::vector<internal::LeafHit> leaves = internal::LeavesTouching(form, space, *x, d);

  // Every cut along d met by the line (Fab Forms Fig. 10 left): the leaf bounds.
  std::vector<std::int64_t> cuts;
  for (const internal::LeafHit& hit : leaves) {
    const FormNode* leaf = hit.node;
    cuts.push_back(leaf->lo[d]);
    cuts.push_back(leaf->hi[d]);
  }
  std::sort(cuts.begin(), cuts.end());
  cuts.erase(std::unique(cuts.begin(), cuts.end()), cuts.end());
  const size_t m = cuts.size();
  // Elements along the line: 2i = the cut i (a point), 2i+1 = the open
  // stretch between cuts i and i+1.
  const size_t elements = 2 * m - 1;
  std::vector<char> valid(elements, 0);
  std::vector<std::set<std::string>> failures(elements);

  std::vector<double> probe = *x;
  std::vector<std::string> leaf_failures;
  for (const internal::LeafHit& hit : leaves) {
    const FormNode* leaf = hit.node;
    const std::int32_t* leaf_corners = corners.of(hit.tree, hit.index);
    const size_t a = std::lower_bound(cuts.begin(), cuts.end(), leaf->lo[d]) - cuts.begin();
    const size_t b = std::lower_bound(cuts.begin(), cuts.end(), leaf->hi[d]) - cuts.begin();
    // Inside the leaf along d (open span): the face free along d.
    leaf_failures.clear();
    const bool inside = internal::FaceAllValid(form, *leaf, leaf_corners, *x, d, &leaf_failures);
    for (size_t e = 2 * a + 1; e < 2 * b; ++e) {
      if (inside)
        valid[e] = 1;
      else
        failures[e].insert(leaf_failures.begin(), leaf_failures.end());
    }
    // Its two end faces along d.
    for (size_t i : {a, b}) {
      probe[d] = static_cast<double>(cuts[i]);
      leaf_failures.clear();
      if (internal::FaceAllValid(form, *leaf, leaf_corners, probe, -1, &leaf_failures))
        valid[2 * i] = 1;
      else
        failures[2 * i].insert(leaf_failures.begin(), leaf_failures.end());
    }
  }

  // Merge runs of equal validity. A valid run always starts and ends on a cut
  // (the closure of an all-valid face is all-valid).
  std::vector<Stretch> out;
  size_t e = 0;
  while (e < elements) {
    size_t f = e;
    while (f + 1 < elements && valid[f + 1] == valid[e]) ++f;
    Stretch s;
    s.valid = valid[e];
    const auto value_at = [&](size_t element, bool upper) {
      const size_t i = element % 2 == 0 ? element / 2 : (upper ? element / 2 + 1 : element / 2);
      return space.value(d, cuts[i]);
    };
    s.lo = value_at(e, false);
    s.hi = value_at(f, true);
    if (!s.valid) {
      std::set<std::string> all;
      for (size_t k = e; k <= f; ++k) all.insert(failures[k].begin(), failures[k].end());
      s.failures.assign(all.begin(), all.end());
    }
    out.push_back(std::move(s));
    e = f + 1;
  }
  return out;
}

std::vector<Stretch> ValidIntervals(const Form& form, const DesignSpace& space, const LeafCorners& corners,
                                    const std::vector<double>& u, int dimension) {
  std::vector<Stretch> all = LineStretches(form, space, corners, u, dimension);
  std::vector<Stretch> out;
  for (Stretch& s : all)
    if (s.valid) out.push_back(std::move(s));
  return out;
}

}  // namespace fabatlas::viewer
