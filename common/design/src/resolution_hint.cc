// Resolution hints (Reconfigurables, Secs. 6.4–6.5). See resolution_hint.h.
#include "fabatlas/design/resolution_hint.h"

#include <algorithm>
#include <cmath>
#include <set>

#include "contact_energy.h"
#include "fabatlas/error.h"

namespace fabatlas::design {

HintSummary ResolutionHints(const Design& design, const Point& u, const ResolutionOptions& options) {
  if (design.objects.empty() || design.transitions.empty())
    throw InputError(design.file.string() + ": the design has no state graph (objects and transitions) to resolve");
  const std::vector<Freedom> free = Freedoms(design, options);
  InMemorySubtreeCache cache;
  HintSummary out;
  StateGraphResult r = EvaluateWithChecks(design, u, &cache);
  out.evaluations = 1;
  out.sample = std::move(r.sample);
  if (!r.graph.collisions_checked) {
    if (r.graph.objects.empty()) return out;  // no geometry: nothing to resolve
    throw InputError(design.file.string() + ": the design has no collision_free check to resolve");
  }
  const int steps = r.graph.time_steps;
  // Per interval: the spacetime contact normal and the normal at first contact.
  for (const auto& t : r.graph.transitions) {
    std::vector<swept::MovingPart> parts;
    for (std::size_t i = 0; i < r.graph.objects.size(); ++i) parts.push_back({r.graph.objects[i], t.motions[i]});
    for (const auto& c : t.collisions) {
      IntervalNormal n;
      n.transition = t.name;
      n.object_a = r.graph.object_names[c.part_a];
      n.object_b = r.graph.object_names[c.part_b];
      n.t_begin = c.t_begin;
      n.t_end = c.t_end;
      n.where = c.where;
      swept::ContactNormalOptions co;
      co.time_steps = steps;
      n.normal = swept::SpacetimeContactNormal(parts, c.part_a, c.part_b, c.t_begin, c.t_end, co);
      n.normal.forces.clear();
      out.intervals.push_back(std::move(n));
    }
  }
  // Per pair: Eq. 3 and the line search's step.
  const ContactState state = ContactsOf(u, std::move(r.graph), steps);
  out.energy = state.energy;
  std::set<std::pair<int, int>> pairs;
  for (const auto& p : state.pairs) pairs.emplace(p.a, p.b);
  if (pairs.empty() || free.empty()) return out;
  const std::vector<Perturbation> perturbations = Perturb(design, state, free, options, &cache);
  out.evaluations += static_cast<int>(perturbations.size());
  for (const auto& [a, b] : pairs) {
    PairHint h;
    h.object_a = state.graph.object_names[a];
    h.object_b = state.graph.object_names[b];
    h.energy = state.PairEnergy(a, b);
    h.descent = PairDescent(state, perturbations, a, b);
    const LineSearch ls = GoldenSectionSearch(design, state, h.descent, free, options, steps, &cache);
    out.evaluations += ls.evaluations;
    h.energy_after = ls.state.energy;
    if (ls.moved)
      for (const Freedom& f : free)
        if (ls.u.at(f.name) != u.at(f.name)) h.step[f.name] = ls.u.at(f.name) - u.at(f.name);
    out.pairs.push_back(std::move(h));
  }
  std::stable_sort(out.pairs.begin(), out.pairs.end(),
                   [](const PairHint& x, const PairHint& y) { return x.energy > y.energy; });
  return out;
}

}  // namespace fabatlas::design
