// fabatlas/fem/nested_dissection.h — a fill-reducing order of a hexahedral
// mesh's nodes for the sparse Cholesky factorisation of the static solve.
//
// Geometric nested dissection (George 1973, "Nested dissection of a regular
// finite element mesh"; docs/references.md): the nodes are split at a node
// layer (the nodes of one x, y or z coordinate), the smallest that leaves at
// least a third of them on either side; the nodes at or above it that share
// an element with a node below form the separator, numbered after both
// parts; each part is ordered the same way, down to parts of at most 16
// nodes (or without such a layer), which keep their index order. On voxel
// meshes the separator is the layer itself, as in George's regular grid,
// and the smallest layer cuts through a design's narrow parts (the sandal's
// heel and toe blocks) where METIS would.
//
// It replaces METIS in the factorisation's ordering: METIS draws from the C
// library's rand(), one generator for the whole process, which gRPC and
// c-ares also call, so its permutation (and with it the roundings of every
// FEM result) depended on what other threads did meanwhile (docs/fem.md,
// "Determinism"). This order has no random choice and no threads: the same
// mesh gives the same order.
#pragma once

#include <vector>

#include "fabatlas/fem/hex_mesh.h"

namespace fabatlas::fem {

// The nodes of `mesh` (indices into mesh.nodes, each once) in elimination
// order.
// O(N log^2 N) time for N nodes (three sorts per part), O(N) memory besides
// the node adjacency (27 neighbours a node on voxel meshes).
std::vector<int> NestedDissectionOrder(const HexMesh& mesh);

}  // namespace fabatlas::fem
