// TetTopology.h — adjacency of a tetrahedral mesh, built once when an object is loaded so that
// an impact only walks arrays: global edges, face neighbours, outward boundary faces, element
// volumes and the surface area around each node.
//
// Local numbering of a tet (a, b, c, d) = nodes 0..3: edge k joins kTetEdges[k]; face i is the
// face opposite node i.
#pragma once

#include <Eigen/Core>
#include <array>
#include <vector>

#include "brittle/core/MeshTypes.h"
#include "brittle/core/Result.h"

namespace brittle {

inline constexpr std::array<std::array<int, 2>, 6> kTetEdges = {{{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}}};

struct TetTopology {
  Eigen::Matrix<int32_t, Eigen::Dynamic, 2, Eigen::RowMajor> edges;      ///< #E by 2, node pairs (low, high)
  Eigen::Matrix<int32_t, Eigen::Dynamic, 6, Eigen::RowMajor> tetEdges;   ///< #T by 6, edge ids of kTetEdges
  Eigen::Matrix<int32_t, Eigen::Dynamic, 4, Eigen::RowMajor> neighbours; ///< #T by 4, tet across face i, −1 on the boundary
  /// Boundary faces as (tet, local face), with their outward triangles (node ids).
  std::vector<std::array<int32_t, 2>> boundaryFaces;
  Triangles boundaryTriangles;
  Eigen::VectorXd tetVolumesM3;     ///< #T, positive
  Eigen::VectorXd nodeAreasM2;      ///< #N, a third of the boundary area of the faces around each node
  double volumeM3 = 0.0;
  double meanEdgeLengthM = 0.0;
};

/// The three nodes (local ids) of face i of a tet, ordered so that the face's normal points away
/// from node i when the tet is positively oriented.
std::array<int, 3> tetFaceNodes(int face);

/// The mesh's edges, numbered in order of first appearance over (tet, kTetEdges): node pairs
/// (low, high), and per tet the ids of its edges kTetEdges[0..5]. The numbering TetTopology uses,
/// and the one a quadratic mesh's mid-edge nodes follow (QuadraticTetMesh.h). Node ids must be in
/// range.
struct TetEdges {
  Eigen::Matrix<int32_t, Eigen::Dynamic, 2, Eigen::RowMajor> edges;
  Eigen::Matrix<int32_t, Eigen::Dynamic, 6, Eigen::RowMajor> tetEdges;
};
TetEdges numberTetEdges(const Tetrahedra& tets);

/// Builds the topology. Errors: InvalidArgument (node ids out of range, a non-positive tet, a face
/// shared by more than two tets).
Result<TetTopology> buildTetTopology(const TetMesh& mesh);

/// The same for a mesh whose tets are those `sameTets` was built from (a database entry placed
/// with another size and pose, say): the connectivity (edges, neighbours, boundary faces) is
/// copied, and only what depends on the nodes (volumes, areas, edge lengths) is measured, so the
/// result equals buildTetTopology(mesh) bit for bit, without its hash maps. The caller vouches
/// for the tets being the same; the shapes are checked. Errors: those of buildTetTopology but the
/// shared face, InvalidArgument (connectivity of another shape).
Result<TetTopology> buildTetTopology(const TetMesh& mesh, const TetTopology& sameTets);

}  // namespace brittle
