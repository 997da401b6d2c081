// ObjectAsset.h — one baked breakable object: tet mesh, mass properties, modal basis and stress
// modes. This is what a pack stores per object and what the runtime reads as flat arrays.
//
// Conventions: SI units; the object's local frame is the frame of its input mesh (no
// re-centring); 0-based indices; stress vectors in Voigt order (xx, yy, zz, yz, xz, xy) in Pa.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>

#include "brittle/descriptors/MassProperties.h"
#include "brittle/core/MeshTypes.h"

namespace brittle {

using MatrixXdRow = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/// Quality of a tetrahedral mesh. Slivers show as dihedral angles near 0° or 180°.
struct MeshQuality {
  int64_t nodeCount = 0;
  int64_t tetCount = 0;
  int64_t surfaceFaceCount = 0;
  double minDihedralDeg = 0.0;
  double maxDihedralDeg = 0.0;
  double maxRadiusEdgeRatio = 0.0;   ///< circumradius / shortest edge; regular tet: 0.612
  double meanRadiusEdgeRatio = 0.0;
  double minTetVolumeM3 = 0.0;
};

/// Lowest r non-rigid vibration modes of K φ = λ M φ, mass-normalised (Φᵀ M Φ = I).
struct ModalBasis {
  Eigen::VectorXd eigenvaluesRad2PerS2;  ///< r, λ = ω², ascending
  Eigen::VectorXd frequenciesHz;         ///< r, f = √λ / 2π
  Eigen::VectorXd residuals;             ///< r, ‖Kφ − λMφ‖ / ‖Kφ‖
  double orthonormalityError = 0.0;      ///< max |ΦᵀMΦ − I|
  /// 3N by r: row 3n+i is the i-th displacement component of node n, per unit modal coordinate
  /// (m per √kg·m, since q has units of √kg·m for mass-normalised modes).
  MatrixXdRow modes;
};

/// Settings and timings of the bake that produced an asset; stored for reproducibility.
struct BakeRecord {
  std::string sourceMesh;             ///< file name the object came from (no directories)
  int64_t targetTets = 0;             ///< requested element count (0 = size-driven)
  double cellSizeM = 0.0;             ///< Mesh_3 cell size actually used
  int64_t requestedModes = 0;
  bool lumpedMass = false;
  bool repaired = false;
  double repairVolumeChange = 0.0;    ///< relative, (V_repaired − V_input)/V_input
  std::string factorization;          ///< "cholmod" or "eigen-ldlt"
  double shift = 0.0;                 ///< ARPACK shift σ (rad²/s²), negative
  int64_t seed = 0;
  double meshingS = 0.0;
  double assemblyS = 0.0;
  double modalS = 0.0;
  double stressModesS = 0.0;
  double totalS = 0.0;
  std::string generator;              ///< "brittle <version>"
};

struct ObjectAsset {
  std::string name;
  std::string materialName;   ///< a material in the same pack
  TetMesh tetMesh;
  Triangles surfaceFaces;     ///< #F by 3, boundary faces of tetMesh, outward, into tetMesh.nodes
  MeshQuality quality;
  MassProperties massProperties;
  ModalBasis modal;
  /// 6T by r: rows 6e..6e+5 are S_e = C B_e Φ_e, stress of element e per unit modal coordinate.
  MatrixXdRow stressModes;
  BakeRecord bake;
};

}  // namespace brittle
