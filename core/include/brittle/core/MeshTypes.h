// MeshTypes.h — the flat array types every module uses for meshes.
//
// Row-major so that a matrix is one contiguous block that maps 1:1 onto an HDF5 dataset and onto
// the runtime's flat arrays. Indices are 0-based. Coordinates are metres unless a name says
// otherwise.
#pragma once

#include <Eigen/Core>
#include <cstdint>

namespace brittle {

using Points = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;      ///< #V by 3
using Triangles = Eigen::Matrix<int32_t, Eigen::Dynamic, 3, Eigen::RowMajor>;  ///< #F by 3
using Tetrahedra = Eigen::Matrix<int32_t, Eigen::Dynamic, 4, Eigen::RowMajor>; ///< #T by 4

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

}  // namespace brittle
