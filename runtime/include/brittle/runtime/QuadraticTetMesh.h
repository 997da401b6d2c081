// QuadraticTetMesh.h — straight-sided 10-node (P2) tetrahedra from a linear tet mesh.
//
// Every edge of the linear mesh gets one mid-edge node, at its midpoint, shared by all the tets
// around it. Corner nodes keep their indices 0..N−1. The mid-edge nodes follow, one per edge, in
// the order in which the edges first appear over tets 0, 1, … and, within a tet, over the local
// edges (0,1), (0,2), (0,3), (1,2), (1,3), (2,3) (kTetEdges): the order of buildTetTopology's
// edges, so the mid-edge node of topology edge e is node N + e. The numbering therefore depends
// only on the tet array, never on hashing or memory addresses.
#pragma once

#include "brittle/core/MeshTypes.h"
#include "brittle/core/Result.h"

namespace brittle {

/// The P2 mesh of a linear mesh (#N by 3 nodes in m, #T by 4 tets). Output: N + #E nodes, #T by
/// 10 tets in the CalculiX C3D10 order (MeshTypes.h, kQuadraticTetEdges).
/// Errors: InvalidArgument (no tets, a node index out of range).
Result<QuadraticTetMesh> makeQuadraticTetMesh(const TetMesh& mesh);

/// The corner nodes and tets of a P2 mesh (its first cornerNodes nodes, the first 4 columns).
TetMesh linearTetMesh(const QuadraticTetMesh& mesh, Eigen::Index cornerNodes);

}  // namespace brittle
