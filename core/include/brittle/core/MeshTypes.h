// MeshTypes.h — the flat array types every module uses for meshes.
//
// Row-major so that a matrix is one contiguous block that maps 1:1 onto an HDF5 dataset and onto
// the runtime's flat arrays. Indices are 0-based. Coordinates are metres unless a name says
// otherwise.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>

namespace brittle {

using Points = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;      ///< #V by 3
using Triangles = Eigen::Matrix<int32_t, Eigen::Dynamic, 3, Eigen::RowMajor>;  ///< #F by 3
using Tetrahedra = Eigen::Matrix<int32_t, Eigen::Dynamic, 4, Eigen::RowMajor>; ///< #T by 4
using QuadraticTetrahedra = Eigen::Matrix<int32_t, Eigen::Dynamic, 10, Eigen::RowMajor>; ///< #T by 10

/// A triangle surface mesh. Closed meshes face outward: counter-clockwise seen from outside.
struct TriangleMesh {
  Points vertices;   ///< #V by 3
  Triangles faces;   ///< #F by 3, indices into vertices
};

/// A linear tetrahedral mesh. Every tet is positively oriented:
/// (v1 - v0) · ((v2 - v0) × (v3 - v0)) > 0.
struct TetMesh {
  Points nodes;      ///< #N by 3
  Tetrahedra tets;   ///< #T by 4, indices into nodes
};

/// Local node order of a 10-node tet, as CalculiX C3D10 and Abaqus number it: the corners 0..3,
/// then node 4 + k at the midpoint of the edge kQuadraticTetEdges[k] = (0,1), (1,2), (2,0),
/// (0,3), (1,3), (2,3).
inline constexpr std::array<std::array<int, 2>, 6> kQuadraticTetEdges = {{{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}}};

/// A quadratic (P2, 10-node) tetrahedral mesh with straight sides: every mid-edge node sits at the
/// midpoint of its edge, so the map from a reference tet is affine and given by the corners. The
/// corners are positively oriented as in TetMesh. Built from a TetMesh by makeQuadraticTetMesh
/// (runtime/QuadraticTetMesh.h): corner nodes keep their indices, mid-edge nodes follow.
struct QuadraticTetMesh {
  Points nodes;               ///< #N by 3, corner nodes first, then one node per edge
  QuadraticTetrahedra tets;   ///< #T by 10, indices into nodes, in the kQuadraticTetEdges order
};

}  // namespace brittle
