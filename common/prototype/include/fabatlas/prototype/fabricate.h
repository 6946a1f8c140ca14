// fabatlas/prototype/fabricate.h — printable geometry of a solved works-like
// prototype (Koo et al. Sec. 7): cavities by swept volume, procedural joint
// geometry (hinge pin and yokes, sliding-hinge pin and slots, double-pivot
// pins, link and caps) and print gaps, in the base configuration, as one
// level-set solid for printing in assembled form.
#pragma once

#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "fabatlas/geometry/solid.h"
#include "fabatlas/prototype/prototype.h"
#include "fabatlas/prototype/solve.h"

namespace fabatlas::prototype {

struct FabricateSummary {
  std::map<std::string, double> part_volumes;  // mm^3 per part (with its joint pieces)
  int swept_cavities = 0;                      // fit-inside sweeps carved
  int joint_pieces = 0;                        // pins, yokes, links, caps
  double seconds = 0;
};

struct FabricatedPiece {
  std::string name;       // a part's name (with its joint pieces), or "link:<joint>" for a double-pivot link
  geometry::Solid solid;  // base configuration, world mm
};

// The printable pieces one by one, parts in file order, then the links; for
// checking the parts against each other (e.g. along a joint's motion).
// Throws InputError if `solution` is not satisfiable.
std::vector<FabricatedPiece> FabricatePieces(const Prototype& p, const SolveSummary& solution,
                                             const geometry::GridSpec& grid, FabricateSummary* summary = nullptr);

// Their union, the printable model. Throws InputError if `solution` is not
// satisfiable.
geometry::Solid Fabricate(const Prototype& p, const SolveSummary& solution, const geometry::GridSpec& grid,
                          FabricateSummary* summary = nullptr);

}  // namespace fabatlas::prototype
