#include "fabatlas/viewer/optimise.h"

#include <algorithm>
#include <charconv>
#include <stdexcept>
#include <cmath>
#include <limits>
#include <sstream>

#include "fabatlas/error.h"
#include "fabatlas/viewer/property_limits.h"
#include "leaf_search.h"

namespace fabatlas::viewer {

namespace {

double ParseFinite(const std::string& text, const std::string& item) {
  double v = 0;
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, v);
  if (text.empty() || ec != std::errc() || ptr != end || !std::isfinite(v))
    throw InputError("'" + item + "': '" + text + "' is not a finite number");
  return v;
}

// The terms' values of one sample, looked up once (NaN: a term's property is
// not recorded there).
class SampleValues {
 public:
  SampleValues(const sampling::Form& form, const std::vector<sampling::Material>& materials,
               const std::vector<Quantity>& properties)
      : form_(form), materials_(materials), properties_(properties), terms_(properties.size()) {}

  // Nullptr when the sample lacks a term's property.
  const double* of(std::int64_t id) {
    if (looked_up_.empty()) {
      looked_up_.assign(form_.samples.size(), 0);
      values_.assign(form_.samples.size() * terms_, 0.0);
    }
    const std::size_t i = static_cast<std::size_t>(id);
    double* v = values_.data() + i * terms_;
    if (!looked_up_[i]) {
      looked_up_[i] = 1;
      for (std::size_t k = 0; k < terms_; ++k) {
        const auto value = QuantityValue(properties_[k], form_.samples[i], materials_);
        if (!value) {
          looked_up_[i] = 2;
          break;
        }
        v[k] = *value;
      }
    }
    return looked_up_[i] == 1 ? v : nullptr;
  }

 private:
  const sampling::Form& form_;
  const std::vector<sampling::Material>& materials_;
  const std::vector<Quantity>& properties_;
  std::size_t terms_;
  std::vector<unsigned char> looked_up_;  // 0 not yet, 1 all recorded, 2 one missing
  std::vector<double> values_;
};

// The objective being searched: a weighted sum of the terms' values, and the
// best (sign * objective, smallest wins) seen so far.
class Objective {
 public:
  Objective(const std::vector<ObjectiveTerm>& terms, bool maximise) : terms_(terms), sign_(maximise ? -1.0 : 1.0) {}

  double of(const double* v) const {
    double sum = 0;
    for (std::size_t k = 0; k < terms_.size(); ++k) sum += terms_[k].weight * v[k];
    return sum;
  }

  // True, and f becomes the best, when f beats the best so far.
  bool Improves(double f) {
    if (!(sign_ * f < best_)) return false;  // (a NaN never wins)
    best_ = sign_ * f;
    return true;
  }

 private:
  const std::vector<ObjectiveTerm>& terms_;
  double sign_;
  double best_ = std::numeric_limits<double>::infinity();
};

// The terms' properties, each resolved once (their names go to
// result.properties).
std::vector<Quantity> ResolveTerms(const sampling::Form& form, const std::vector<sampling::Material>& materials,
                                   const std::vector<ObjectiveTerm>& terms, OptimiseResult& result) {
  std::vector<Quantity> properties;
  for (const auto& t : terms) {
    if (!std::isfinite(t.weight)) throw InputError("objective: the weight of '" + t.property + "' is not finite");
    properties.push_back(ResolveQuantity(t.property, form, materials));
    result.properties.push_back(properties.back().name);
  }
  return properties;
}

// Which dimensions are held; u0 gets the held values (others: their lowest).
std::vector<bool> HeldDimensions(const sampling::DesignSpace& space, const std::vector<HeldParameter>& holds,
                                 std::vector<double>& u0) {
  const int n = space.dimension_count();
  std::vector<bool> held(n, false);
  u0.assign(n, 0.0);
  for (int d = 0; d < n; ++d) u0[d] = space.value(d, space.key_lo(d));
  for (const auto& h : holds) {
    if (h.dimension < 0 || h.dimension >= n) throw InputError("hold: no parameter " + std::to_string(h.dimension));
    if (held[h.dimension]) throw InputError("hold: " + space.dimension(h.dimension).name + " is held twice");
    held[h.dimension] = true;
    u0[h.dimension] = h.value;
  }
  return held;
}

// Nothing held: every valid sample is a leaf corner and a valid point.
void SearchValidSamples(const sampling::Form& form, SampleValues& values, std::size_t terms, Objective& objective,
                        OptimiseResult& result) {
  for (std::size_t i = 0; i < form.samples.size(); ++i) {
    if (!form.samples[i].outcome.valid) continue;
    const double* v = values.of(static_cast<std::int64_t>(i));
    if (!v) continue;
    ++result.candidates;
    const double f = objective.of(v);
    if (objective.Improves(f)) {
      result.found = true;
      result.u = form.samples[i].u;
      result.objective = f;
      result.values.assign(v, v + terms);
      result.sample = static_cast<std::int64_t>(i);
      result.corners = {result.sample};
    }
  }
}

// Where the held slice (key coordinates x) meets one leaf: along a held
// dimension it lies on the leaf's lo or hi face (bit fixed) or strictly
// inside (interpolated with weight t on hi).
struct LeafSlice {
  std::size_t held_mask = 0, fixed_bits = 0;
  std::vector<int> inside;
  std::vector<double> t;
};

LeafSlice SliceOf(const sampling::FormNode& leaf, const std::vector<bool>& held, const std::vector<double>& x) {
  const int n = static_cast<int>(held.size());
  LeafSlice s;
  s.t.assign(n, 0.0);
  for (int d = 0; d < n; ++d) {
    if (!held[d]) continue;
    s.held_mask |= std::size_t{1} << d;
    const double lo = static_cast<double>(leaf.lo[d]), hi = static_cast<double>(leaf.hi[d]);
    if (x[d] == hi)
      s.fixed_bits |= std::size_t{1} << d;
    else if (x[d] != lo) {
      s.inside.push_back(d);
      s.t[d] = (x[d] - lo) / (hi - lo);
    }
  }
  return s;
}

// The terms' values at slice corner c (its bits along the free dimensions),
// multilinear over the leaf corners around it along the dimensions the slice
// is inside; `used` gets those corners' sample ids. False when one of them
// lacks a term's property.
bool InterpolateAtCorner(SampleValues& values, const std::int32_t* ids, std::size_t c, const LeafSlice& s,
                         std::vector<double>& interpolated, std::vector<std::int64_t>& used) {
  std::fill(interpolated.begin(), interpolated.end(), 0.0);
  used.clear();
  bool recorded = true;
  for (std::size_t combo = 0; combo < (std::size_t{1} << s.inside.size()) && recorded; ++combo) {
    std::size_t corner = c | s.fixed_bits;
    double w = 1;
    for (std::size_t k = 0; k < s.inside.size(); ++k) {
      const int d = s.inside[k];
      if ((combo >> k) & 1) {
        corner |= std::size_t{1} << d;
        w *= s.t[d];
      } else {
        w *= 1 - s.t[d];
      }
    }
    const double* v = values.of(ids[corner]);
    if (!v)
      recorded = false;
    else
      for (std::size_t k = 0; k < interpolated.size(); ++k) interpolated[k] += w * v[k];
    used.push_back(ids[corner]);
  }
  return recorded;
}

// Held: the corners of the slice of every leaf the slice meets.
void SearchHeldSlice(const sampling::Form& form, const LeafCorners& corners, const sampling::DesignSpace& space,
                     const std::vector<double>& x, const std::vector<bool>& held, const std::vector<double>& u0,
                     SampleValues& values, std::size_t terms, Objective& objective, OptimiseResult& result) {
  const int n = space.dimension_count();
  std::vector<double> p(n), interpolated(terms);
  std::vector<std::int64_t> used;
  std::vector<bool> free(n);
  for (int d = 0; d < n; ++d) free[d] = !held[d];
  for (const internal::LeafHit& hit : internal::LeavesMeeting(form, space, x, free)) {
    const sampling::FormNode& leaf = *hit.node;
    const std::int32_t* ids = corners.of(hit.tree, hit.index);
    const LeafSlice slice = SliceOf(leaf, held, x);
    for (std::size_t c = 0; c < (std::size_t{1} << n); ++c) {
      if (c & slice.held_mask) continue;  // c: the slice corner's bits along the free dimensions
      for (int d = 0; d < n; ++d) p[d] = held[d] ? x[d] : static_cast<double>((c >> d) & 1 ? leaf.hi[d] : leaf.lo[d]);
      if (!internal::FaceAllValid(form, leaf, ids, p, -1)) continue;
      if (!InterpolateAtCorner(values, ids, c, slice, interpolated, used)) continue;
      ++result.candidates;
      const double f = objective.of(interpolated.data());
      if (objective.Improves(f)) {
        result.found = true;
        result.u.resize(n);
        for (int d = 0; d < n; ++d) result.u[d] = held[d] ? u0[d] : space.value(d, static_cast<std::int64_t>(p[d]));
        result.objective = f;
        result.values = interpolated;
        result.corners = used;
        result.sample = slice.inside.empty() ? used.front() : -1;
        if (slice.inside.empty()) result.u = form.samples[static_cast<std::size_t>(result.sample)].u;
      }
    }
  }
}

}  // namespace

std::vector<ObjectiveTerm> ParseObjective(const std::string& text) {
  if (text.empty()) throw InputError("objective: empty (name a property, or weights as a=1,b=2)");
  if (text.find('=') == std::string::npos && text.find(',') == std::string::npos) return {{text, 1.0}};
  std::vector<ObjectiveTerm> terms;
  std::istringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    const auto eq = item.rfind('=');
    if (item.empty() || eq == std::string::npos || eq == 0)
      throw InputError("objective item '" + item + "': expected PROPERTY=WEIGHT");
    terms.push_back({item.substr(0, eq), ParseFinite(item.substr(eq + 1), item)});
  }
  if (text.back() == ',') throw InputError("objective '" + text + "' ends with a comma");
  return terms;
}

std::vector<HeldParameter> ParseHolds(const std::string& text, const sampling::DesignSpace& space) {
  std::vector<HeldParameter> holds;
  std::istringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    const auto eq = item.find('=');
    if (eq == std::string::npos || eq == 0) throw InputError("hold '" + item + "': expected PARAMETER=VALUE");
    const std::string name = item.substr(0, eq), value = item.substr(eq + 1);
    int d = 0;
    while (d < space.dimension_count() && space.dimension(d).name != name) ++d;
    if (d == space.dimension_count()) {
      std::string known;
      for (const auto& dim : space.dimensions()) known += (known.empty() ? "" : ", ") + dim.name;
      throw InputError("hold '" + item + "': no parameter '" + name + "' (parameters: " + known + ")");
    }
    const auto& dim = space.dimension(d);
    double v = std::numeric_limits<double>::quiet_NaN();
    if (dim.kind == sampling::DimensionKind::kEnumerated)
      for (std::size_t k = 0; k < dim.values.size(); ++k)
        if (dim.values[k] == value) v = static_cast<double>(k);
    if (std::isnan(v)) v = ParseFinite(value, item);
    const double lo = space.value(d, space.key_lo(d)), hi = space.value(d, space.key_hi(d));
    if (v < lo || v > hi) {
      std::ostringstream msg;
      msg << "hold '" << item << "': " << v << " is outside " << name << "'s range [" << lo << ", " << hi << "]";
      throw InputError(msg.str());
    }
    if (space.is_discrete(d) && v != std::floor(v))
      throw InputError("hold '" + item + "': " + name + " takes whole values (an index for an enumerated one)");
    for (const auto& h : holds)
      if (h.dimension == d) throw InputError("hold '" + item + "': " + name + " is held twice");
    holds.push_back({d, v});
  }
  return holds;
}

OptimiseResult Optimise(const sampling::Form& form, const LeafCorners& corners,
                        const std::vector<sampling::Material>& materials, const OptimiseOptions& options) {
  if (!corners.Fits(form))
    throw std::invalid_argument("viewer: the corner table was built from a form with other trees or samples");
  if (options.terms.empty()) throw InputError("objective: no property named");
  const sampling::DesignSpace space = form.space();
  OptimiseResult result;
  const std::vector<Quantity> properties = ResolveTerms(form, materials, options.terms, result);
  std::vector<double> u0;
  const std::vector<bool> held = HeldDimensions(space, options.hold, u0);
  const auto x = internal::KeyCoordinates(space, u0);
  if (!x) throw InputError("hold: a held value is outside its parameter's range");

  SampleValues values(form, materials, properties);
  Objective objective(options.terms, options.maximise);
  if (options.hold.empty())
    SearchValidSamples(form, values, properties.size(), objective, result);
  else
    SearchHeldSlice(form, corners, space, *x, held, u0, values, properties.size(), objective, result);
  return result;
}

}  // namespace fabatlas::viewer
