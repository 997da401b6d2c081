// FemAssembly.h — tetrahedral finite elements for isotropic linear elasticity: linear (P1,
// 4 nodes) and straight-sided quadratic (P2, 10 nodes, MeshTypes.h's QuadraticTetMesh).
//
// Degrees of freedom are interleaved per node: dof 3n+i is displacement component i (x, y, z) of
// node n. Strains and stresses use Voigt order (xx, yy, zz, yz, xz, xy) with engineering shear
// strains (γ = 2ε). Units: m, Pa, kg; K in N/m, M in kg.
//
// Integration is exact for both orders. P1: B is constant, M has its closed form. P2 (affine
// geometry, so ∇N is linear): K's integrand B^T C B has degree 2 and the 4-point degree-2 rule
// integrates it exactly; the consistent M (degree 4) uses its closed form, ∫N_a N_b dV from
// ∫λ^a λ^b λ^c λ^d dV = 6V a!b!c!d!/(a+b+c+d+3)!. (CalculiX integrates the C3D10 mass with the
// 4-point rule, which is not exact; tests/precompute/CalculixFrequencyTest.cpp says how its deck
// is made to match the exact matrix.)
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <vector>

#include "brittle/database/Material.h"
#include "brittle/database/ObjectAsset.h"
#include "brittle/core/MeshTypes.h"
#include "brittle/core/Result.h"

namespace brittle {

using SparseMatrixd = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

struct FemSettings {
  /// A diagonal mass instead of the consistent one: the consistent diagonal scaled to the element
  /// mass (HRZ lumping). For P1 that is row-sum lumping, ρV/4 per node. For P2 it gives ρV/36
  /// per corner and 4ρV/27 per mid-edge node (row sums would give the corners negative masses).
  bool lumpedMass = false;
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

/// The ten P2 shape functions (C3D10 order) at the point with barycentric coordinates λ (λ_i
/// weighs corner i, Σλ = 1): N_i = λ_i(2λ_i − 1) at the corners, N = 4λ_iλ_j at the midpoint of
/// edge (i, j).
Eigen::Matrix<double, 10, 1> quadraticTetShapeFunctions(const Eigen::Vector4d& barycentric);

/// 6 by 30 strain-displacement matrix B (1/m) of a straight-sided P2 tet with corners p0..p3 at
/// the point with barycentric coordinates λ, and the tet's volume (m³, signed). Columns 3a..3a+2
/// belong to local node a (C3D10 order).
Eigen::Matrix<double, 6, 30> quadraticTetStrainDisplacement(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1,
                                                            const Eigen::Vector3d& p2, const Eigen::Vector3d& p3,
                                                            const Eigen::Vector4d& barycentric, double* volumeM3);

/// The consistent mass of a P2 tet per unit density and volume, ∫N_a N_b dV / V (10 by 10,
/// C3D10 order, entries k/420 with k = 6, 1, −4, −6, 32, 16, 8 by how nodes a and b relate).
const Eigen::Matrix<double, 10, 10>& quadraticTetUnitMass();

/// Assembles K and M of a straight-sided P2 mesh (K and M are 3N by 3N, N = mesh.nodes.rows()).
/// Errors: DegenerateElement (a tet whose corners have volume ≤ degenerateTetVolumeM3(nodes) or
/// are inverted, naming the tet; a node index out of range), InvalidArgument (a mid-edge node off
/// its edge's midpoint by more than 1e-9 of the edge's length: curved P2 is not supported),
/// InvalidMaterial.
Result<FemSystem> assembleFem(const QuadraticTetMesh& mesh, const Material& material, const FemSettings& settings);

/// Stress points of a P2 element: its 4 corners. The stress of a straight-sided P2 tet is linear
/// in space, so it is known everywhere from its corner values, and every convex function of it
/// (a norm, the largest principal stress) takes its maximum over the element at a corner: bounds
/// and maxima taken over these points hold for the whole element.
inline constexpr int kQuadraticTetStressPoints = 4;

/// Per-element stress modes of a P2 mesh: a 24T by r matrix. Rows 24e + 6c .. 24e + 6c + 5 give
/// the stress (Pa, Voigt) at corner c (local node c, c = 0..3) of element e per unit modal
/// coordinate. modes is 3N by r. The mesh must pass assembleFem.
MatrixXdRow computeStressModes(const QuadraticTetMesh& mesh, const Material& material, const MatrixXdRow& modes);

/// A linear tet mesh's finite elements at an element order, made once and shared by the
/// assembly, the stress modes and the stress recovery: P1 is the mesh itself, P2 adds the
/// mid-edge nodes of makeQuadraticTetMesh. It refers to the linear mesh, which must outlive it.
struct FemMesh {
  const TetMesh* linear = nullptr;
  ElementOrder order = ElementOrder::P1;
  QuadraticTetMesh quadratic;  ///< P2 only
  /// The FEM nodes: the linear mesh's (P1), or its corners followed by the mid-edge nodes (P2).
  const Points& nodes() const { return order == ElementOrder::P2 ? quadratic.nodes : linear->nodes; }
};
/// Errors: those of makeQuadraticTetMesh (P2).
Result<FemMesh> makeFemMesh(const TetMesh& mesh, ElementOrder order);

/// K and M at the mesh's order (3 × nodes() rows). Errors: those of the assembleFem above for
/// that order.
Result<FemSystem> assembleFem(const FemMesh& mesh, const Material& material, const FemSettings& settings);

/// Stress modes at the mesh's order (ObjectAsset::stressModes: 6T by r for P1, 24T by r for P2);
/// modes is 3 × nodes() by r.
MatrixXdRow computeStressModes(const FemMesh& mesh, const Material& material, const MatrixXdRow& modes);

/// P2 stresses at the corners, recovered as one value per mesh node: each element's corner
/// stress becomes the volume-weighted mean of the corner stresses of every element at that node.
///
/// Why: a P2 element's own corner stress is its least accurate value (the linear strain
/// extrapolated to a vertex) and jumps from element to element. Next to a contact load those jumps
/// set the peak: the stone ball's and the brick's corrected peaks, with the load spread over the
/// same 0.15 D on four meshes of 0.8k–6.4k tets, read 59/60/37/46 and 18/22/30/12 MPa at the raw
/// corners, and 11.8/12.3/11.0/11.2 and 14.2/11.4/11.2/10.5 as nodal means (docs/decisions.md,
/// "Contact loads").
/// The mean keeps every field P2 represents exactly (a linear strain agrees at a node already),
/// and a thin part's bending, linear through its thickness, keeps its surface value (the default
/// plate's hit 74.9 → 70.3 MPa), where the element centroid would read its mid-plane (41.8). The
/// recovered stress is linear in each element between its corners' values, so its largest
/// principal value over an element is still at a corner, which the scan's bounds rely on.
/// Each node's mean is summed in the order of its points (4e + c ascending): the same bits on any
/// thread count.
class CornerStressMeans {
 public:
  /// From the tets' corners (a P2 mesh's linear tets). Errors: InvalidArgument for a node index
  /// out of range or a tet without volume.
  static Result<CornerStressMeans> make(const TetMesh& mesh);
  /// In place, over a row-major block of 24T rows by `cols` (element e's corner c at rows
  /// 6(4e + c) to 6(4e + c) + 5): stress modes (cols = r) or one stress field (cols = 1).
  void apply(double* rows, Eigen::Index cols) const;
  Eigen::Index elementCount() const { return mElements; }

 private:
  Eigen::Index mElements = 0;
  std::vector<int32_t> mStart;    ///< per node, its first entry in mPoints (CSR), and the end
  std::vector<int32_t> mPoints;   ///< 4e + c, node by node, ascending within a node
  std::vector<double> mWeights;   ///< V_e over the node's Σ V, per entry of mPoints
};

/// Stresses at every element's stress points (stressPointsPerElement) from nodal displacements:
/// the recovery of the static correction and of the full-FEM reference. Each element keeps its
/// barycentric gradients and forms ∇u from them when asked: for P1 a sixth of the memory of C B_e
/// (6 by 12), for P2 a tenth of 4 × (6 by 30) matrices at its corners.
class ElementStresses {
 public:
  /// Errors: InvalidMaterial.
  static Result<ElementStresses> make(const FemMesh& mesh, const Material& material);
  int pointsPerElement() const { return stressPointsPerElement(mOrder); }
  Eigen::Index elementCount() const { return mElements.rows(); }
  /// 3 × this is the length of a displacement vector.
  Eigen::Index femNodeCount() const { return mFemNodes; }
  /// The 6P stresses (Pa, Voigt, point by point) of element e for displacements u (3 × femNodeCount, m):
  /// the element's own, for P2 before the corner means below.
  void element(Eigen::Index e, const Eigen::VectorXd& u, double* out) const;
  /// Every element's: stress is resized to 6PT. P2 corners are nodal means (CornerStressMeans),
  /// as a body's stress modes are (makeBody), so that the static correction and the full-FEM
  /// reference read the same recovered field as the modes.
  void all(const Eigen::VectorXd& u, Eigen::VectorXd& stress) const;

 private:
  ElementOrder mOrder = ElementOrder::P1;
  Eigen::Index mFemNodes = 0;
  Eigen::Matrix<double, 6, 6> mElasticity;
  Eigen::Matrix<int32_t, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> mElements;  // #T by 4 or 10 FEM nodes
  std::vector<Eigen::Matrix<double, 4, 3>> mGradients;    // ∇λ per element (rows)
  CornerStressMeans mMeans;                               // P2 only
};

/// The six rigid-body motions of the mesh's nodes, unnormalised: 3N by 6, unit translations along
/// x, y, z, then the infinitesimal rotations e_a × (p − c) about the nodes' mean c (m per rad).
Eigen::MatrixXd rigidBodyMotions(const Points& nodes);

/// The six rigid-body modes of the mesh (3 translations, 3 infinitesimal rotations about the
/// centroid of the nodes), as a 3N by 6 matrix with M-orthonormal columns. Nodal values of the
/// rigid fields, so it holds for any element whose interpolation reproduces linear fields: P1 and
/// straight-sided P2 (pass all P2 nodes, mid-edge ones included).
Eigen::MatrixXd rigidBodyModes(const Points& nodes, const SparseMatrixd& mass);

}  // namespace brittle
