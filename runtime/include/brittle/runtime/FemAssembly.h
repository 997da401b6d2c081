// FemAssembly.h — linear (P1) tetrahedral finite elements for isotropic linear elasticity.
//
// Degrees of freedom are interleaved per node: dof 3n+i is displacement component i (x, y, z) of
// node n. Strains and stresses use Voigt order (xx, yy, zz, yz, xz, xy) with engineering shear
// strains (γ = 2ε). Units: m, Pa, kg; K in N/m, M in kg.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include "brittle/database/Material.h"
#include "brittle/database/ObjectAsset.h"
#include "brittle/core/MeshTypes.h"
#include "brittle/core/Result.h"

namespace brittle {

using SparseMatrixd = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

struct FemSettings {
  bool lumpedMass = false;  ///< row-sum lumping (ρV/4 per node) instead of the consistent mass
};

struct FemSystem {
  SparseMatrixd stiffness;  ///< K, 3N by 3N, symmetric, both triangles stored
  SparseMatrixd mass;       ///< M, 3N by 3N, symmetric positive definite
};

/// 6 by 12 strain-displacement matrix B of a linear tet (1/m), and its volume (m³, signed).
Eigen::Matrix<double, 6, 12> tetStrainDisplacement(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1,
                                                   const Eigen::Vector3d& p2, const Eigen::Vector3d& p3,
                                                   double* volumeM3);

/// The volume (m³) at or below which a tet of a mesh with these nodes (#N by 3) is degenerate:
/// 1e-12 × the volume of the nodes' bounding box. assembleFem refuses such a tet; the tet mesher
/// retries rather than hand one over.
double degenerateTetVolumeM3(const Points& nodes);

/// Assembles K and M. Error: DegenerateElement (a tet with volume ≤ degenerateTetVolumeM3(nodes)
/// or inverted, naming the tet), InvalidMaterial.
Result<FemSystem> assembleFem(const TetMesh& mesh, const Material& material, const FemSettings& settings);

/// Per-element stress modes S_e = C B_e Φ_e: returns a 6T by r matrix whose rows 6e..6e+5 give
/// the stress (Pa) of element e per unit modal coordinate. modes is 3N by r.
MatrixXdRow computeStressModes(const TetMesh& mesh, const Material& material, const MatrixXdRow& modes);

/// The six rigid-body modes of the mesh (3 translations, 3 infinitesimal rotations about the
/// centroid of the nodes), as a 3N by 6 matrix with M-orthonormal columns.
Eigen::MatrixXd rigidBodyModes(const Points& nodes, const SparseMatrixd& mass);

}  // namespace brittle
