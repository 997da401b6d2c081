// TetMeshQuality.h — quality statistics and boundary extraction for linear tet meshes.
#pragma once

#include <cstdint>
#include <vector>

#include "brittle/database/ObjectAsset.h"
#include "brittle/core/MeshTypes.h"

namespace brittle {

/// Dihedral angles (degrees), radius-edge ratios and counts of a tet mesh (#T ≥ 1).
/// surfaceFaceCount is filled from boundaryFaces(mesh).
MeshQuality computeMeshQuality(const TetMesh& mesh);

/// Faces used by exactly one tet, oriented outward (counter-clockwise seen from outside), in
/// the order of the tets that own them.
Triangles boundaryFaces(const TetMesh& mesh);

/// Labels each tet (#T) with its group of tets connected through shared faces (tets that touch
/// only at an edge or a vertex are in separate groups), numbered 0, 1, … in order of each group's
/// first tet.
std::vector<int32_t> labelFaceConnectedComponents(const TetMesh& mesh);

/// Number of groups of labelFaceConnectedComponents (1 for one solid).
int64_t countFaceConnectedComponents(const TetMesh& mesh);

/// Drops nodes no tet uses and renumbers the rest in their original order.
TetMesh compactNodes(const TetMesh& mesh);

}  // namespace brittle
