// Start points of the assembly solve (solve/solver.h): the defaults, Halton
// points over the parameter box or near the defaults (deterministic
// restarts) and the chain-by-chain initial guess (FabHacks Table 5).
#include <algorithm>
#include <vector>

#include "solver.h"

namespace fabatlas::assembly::internal {

namespace {

// The radical inverse of `index` in `base` (the Halton sequence).
double Halton(int index, int base) {
  double f = 1, r = 0;
  while (index > 0) {
    f /= base;
    r += f * (index % base);
    index /= base;
  }
  return r;
}

}  // namespace

void Solver::SetStart(int k) {
  int dim = 0;
  static const int kPrimes[] = {2,   3,   5,   7,   11,  13,  17,  19,  23,  29,  31,  37, 41,
                                43,  47,  53,  59,  61,  67,  71,  73,  79,  83,  89,  97, 101,
                                103, 107, 109, 113, 127, 131, 137, 139, 149, 151, 157, 163};
  const int np = sizeof(kPrimes) / sizeof(int);
  for (size_t b = 0; b < blocks_.size(); ++b) {
    const auto& specs = Spec(static_cast<int>(b));
    Block& s = blocks_[b];
    for (size_t i = 0; i < specs.size(); ++i) {
      if (specs[i].held) {
        s[i] = specs[i].init;
        continue;
      }
      // Start 0: the defaults (PARTS.md §1, spread where primitives are
      // shared); odd starts: Halton points over the whole box; even starts:
      // Halton points within ±1/8 of each range around the defaults (the
      // reference starts from its defaults; long chains close only near them).
      const double u = k == 0 ? -1 : Halton(k, kPrimes[dim++ % np]);
      const double w = specs[i].max - specs[i].min;
      s[i] = u < 0        ? specs[i].init
             : k % 2 == 1 ? specs[i].min + u * w
                          : std::clamp(specs[i].init + (u - 0.5) * w / 4, specs[i].min, specs[i].max);
    }
    if (kin_.sym_axis[b] >= 0) s[3] = k == 0 ? 0.0 : 360.0 * Halton(k, kPrimes[dim++ % np]);
  }
}

// Chain-by-chain initial guess (FabHacks, Table 5: for the reading nook
// "the initial guesses are computed from optimizing individual chains in
// the design"; PARTS.md §6: the reference's hand-set start vectors for it).
// From the defaults (start 0):
//  1. the chain from the environment to the target part — the spanning-tree
//     connections on its path — minimises the step-1 target objective alone
//     (no cycle terms), so the target part is placed first;
//  2. each cycle-closing connection in program order closes its own cycle:
//     its closure residual is minimised over its own parameters and those of
//     the tree connections on its two parts' paths from the environment
//     that no earlier chain moved, every earlier chain held where it was
//     solved — each new connection starts from the already-solved chains.
// Connections on no chain keep their defaults. Returns the chains solved.
int Solver::SetChainStart() {
  SetStart(0);
  const int m = static_cast<int>(prog_.connections.size());
  const int n = static_cast<int>(prog_.instances.size());
  std::vector<int> edge_to(n, -1), parent(n, -1);  // tree connection placing each part
  for (const auto& [e, child] : kin_.tree) {
    edge_to[child] = e;
    const auto& c = prog_.connections[e];
    parent[child] = child == c.part_b ? c.part_a : c.part_b;
  }
  std::vector<char> solved(m, 0);
  auto take_path = [&](int part, Chain& chain) {
    for (int u = part; u >= 0 && edge_to[u] >= 0; u = parent[u])
      if (!solved[edge_to[u]]) chain.free[edge_to[u]] = 1;
  };
  auto run = [&](Chain& chain, bool target) {
    bool any = false;
    for (int e = 0; e < m; ++e) any = any || chain.free[e];
    if (!any) return false;
    Run(Phase::kObjective, target ? opt_.penalty_start : 1.0, nullptr, &chain);
    for (int e = 0; e < m; ++e) solved[e] = solved[e] || chain.free[e];
    return true;
  };
  int chains = 0;
  {
    Chain chain{std::vector<char>(m, 0), std::vector<double>(kin_.closing.size(), 0.0)};
    take_path(prog_.target, chain);
    chains += run(chain, true);
  }
  for (size_t k = 0; k < kin_.closing.size(); ++k) {
    const int e = kin_.closing[k];
    const auto& c = prog_.connections[e];
    Chain chain{std::vector<char>(m, 0), std::vector<double>(kin_.closing.size(), 0.0)};
    chain.closing_scale[k] = 1;
    take_path(c.part_a, chain);
    take_path(c.part_b, chain);
    chain.free[e] = 1;
    chains += run(chain, false);
  }
  return chains;
}

}  // namespace fabatlas::assembly::internal
