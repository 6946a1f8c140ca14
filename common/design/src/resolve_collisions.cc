// Automatic collision resolution (Reconfigurables, Sec. 6.6). See
// resolve_collisions.h.
#include "fabatlas/design/resolve_collisions.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <set>

#include "contact_energy.h"
#include "fabatlas/error.h"

namespace fabatlas::design {

namespace {

// The direction and bracket of the last step the descent took.
struct LastMove {
  std::map<std::string, double> direction;
  double bracket = 0;
};

// The colliding pairs of objects, each once, by their share of the energy,
// the largest first.
std::vector<std::pair<double, std::pair<int, int>>> PairsByEnergy(const ContactState& state) {
  std::vector<std::pair<double, std::pair<int, int>>> pairs;
  std::set<std::pair<int, int>> seen;
  for (const auto& p : state.pairs)
    if (seen.emplace(p.a, p.b).second) pairs.push_back({state.PairEnergy(p.a, p.b), {p.a, p.b}});
  std::sort(pairs.begin(), pairs.end(), [](const auto& x, const auto& y) { return x.first > y.first; });
  return pairs;
}

// One greedy step: pairs by their share of the energy, the largest first;
// the first whose hint lowers the energy of all pairs is taken (into state,
// out.steps and last). False when none does.
bool DescendOnce(const Design& design, const std::vector<Freedom>& free, const ResolutionOptions& options, int steps,
                 InMemorySubtreeCache& cache, ContactState& state, LastMove& last, ResolveSummary& out) {
  const auto pairs = PairsByEnergy(state);
  const std::vector<Perturbation> perturbations = Perturb(design, state, free, options, &cache);
  out.evaluations += static_cast<int>(perturbations.size());
  for (const auto& [energy, pair] : pairs) {
    const auto descent = PairDescent(state, perturbations, pair.first, pair.second);
    const LineSearch ls = GoldenSectionSearch(design, state, descent, free, options, steps, &cache);
    out.evaluations += ls.evaluations;
    if (!ls.moved) continue;
    ResolveStep s;
    s.object_a = design.objects[pair.first].name;
    s.object_b = design.objects[pair.second].name;
    s.energy_before = state.energy;
    s.energy_after = ls.state.energy;
    for (const Freedom& f : free)
      if (ls.u.at(f.name) != state.u.at(f.name)) s.edit[f.name] = ls.u.at(f.name) - state.u.at(f.name);
    out.steps.push_back(std::move(s));
    last.direction = ls.direction;
    last.bracket = ls.bracket;
    state = ls.state;
    return true;
  }
  return false;
}

// The proof: every check, as precompute runs them, at the descent's end;
// when the energy is 0 but a collision (or too little clearance) remains,
// further steps along the last direction, doubling, until the checks pass,
// the bounds hold the point or max_extra_steps are taken. `at` becomes the
// point proved; the evaluation there is returned.
StateGraphResult Prove(const Design& design, const std::vector<Freedom>& free, const ResolutionOptions& options,
                       InMemorySubtreeCache& cache, const ContactState& state, const LastMove& last_move, Point& at,
                       ResolveSummary& out) {
  at = state.u;
  StateGraphResult last = EvaluateWithChecks(design, at, &cache);
  ++out.evaluations;
  if (last.sample.valid || state.energy != 0 || last_move.direction.empty() ||
      (last.sample.failure != kCollision && last.sample.failure != kTooLittleClearance))
    return last;
  double extra = std::max(last_move.bracket, 1e-3);
  for (int j = 0; j < options.max_extra_steps && !last.sample.valid; ++j, extra *= 2) {
    const Point next = Moved(state.u, last_move.direction, extra, free);
    if (next == at) break;  // held by the bounds
    at = next;
    last = EvaluateWithChecks(design, at, &cache);
    ++out.evaluations;
  }
  return last;
}

// The edit from u to at over the free parameters, and its size (the norm
// of each change over its parameter's range).
void RecordEdit(const std::vector<Freedom>& free, const Point& u, const Point& at, ResolveSummary& out) {
  double size = 0;
  for (const Freedom& f : free) {
    const double d = at.at(f.name) - u.at(f.name);
    if (d != 0) out.edit[f.name] = d;
    size += (d / (f.max - f.min)) * (d / (f.max - f.min));
  }
  out.edit_size = std::sqrt(size);
}

}  // namespace

ResolveSummary ResolveCollisions(const Design& design, const Point& u, const ResolutionOptions& options) {
  if (design.objects.empty() || design.transitions.empty())
    throw InputError(design.file.string() + ": the design has no state graph (objects and transitions) to resolve");
  const auto start = std::chrono::steady_clock::now();
  const std::vector<Freedom> free = Freedoms(design, options);
  InMemorySubtreeCache cache;
  ResolveSummary out;
  out.before = out.after = u;
  StateGraphResult r = EvaluateWithChecks(design, u, &cache);
  out.evaluations = 1;
  out.failure_before = out.failure_after = r.sample.failure;
  out.reason_after = r.sample.failure_reason;
  auto finish = [&] {
    out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return out;
  };
  if (r.sample.valid) {
    out.resolved = true;
    return finish();
  }
  if (!r.graph.collisions_checked) return finish();  // failed before the collision check: nothing to resolve
  const int steps = r.graph.time_steps;
  ContactState state = ContactsOf(u, std::move(r.graph), steps);
  out.energy_before = out.energy_after = state.energy;
  LastMove last_move;
  for (int step = 0; step < options.max_steps && state.energy > 0 && !free.empty(); ++step)
    if (!DescendOnce(design, free, options, steps, cache, state, last_move, out)) break;
  Point at;
  StateGraphResult last = Prove(design, free, options, cache, state, last_move, at, out);
  out.after = at;
  out.energy_after = at == state.u                   ? state.energy
                     : last.graph.collisions_checked ? ContactsOf(at, std::move(last.graph), steps).energy
                                                     : state.energy;
  out.resolved = last.sample.valid;
  out.failure_after = last.sample.failure;
  out.reason_after = last.sample.failure_reason;
  RecordEdit(free, u, at, out);
  return finish();
}

}  // namespace fabatlas::design
