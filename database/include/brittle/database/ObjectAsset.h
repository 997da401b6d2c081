// ObjectAsset.h — one baked breakable object: tet mesh, mass properties, modal basis and stress
// modes. This is what a pack stores per object and what the runtime reads as flat arrays.
//
// Conventions: SI units; the object's local frame is the frame of its input mesh (no
// re-centring); 0-based indices; stress vectors in Voigt order (xx, yy, zz, yz, xz, xy) in Pa.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "brittle/descriptors/MassProperties.h"
#include "brittle/core/MeshTypes.h"

namespace brittle {

using MatrixXdRow = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/// The finite element an object's modal data were computed with. Its geometry is always the
/// linear tet mesh (straight sides); P2 adds one node at the midpoint of every edge.
///   P1: 4-node linear tets. Modes over the tet mesh's N nodes; stress constant per element.
///   P2: 10-node quadratic tets. Modes over N + #E nodes: the corners 0..N−1, then the mid-edge
///       node of each edge in makeQuadraticTetMesh's order (runtime/QuadraticTetMesh.h). Stress
///       is linear in each element and is stored at its 4 corners.
/// Thin parts want P2: linear tets lock in bending (the default plate: +38 % on its first
/// frequency with P1 at 30.8k tets, +0.06 % with P2 at 7.4k).
enum class ElementOrder : int32_t { P1 = 1, P2 = 2 };

/// "p1" or "p2".
inline const char* elementOrderName(ElementOrder order) { return order == ElementOrder::P2 ? "p2" : "p1"; }
/// The order named "p1" or "p2"; nullopt for anything else.
inline std::optional<ElementOrder> parseElementOrder(std::string_view name) {
  if (name == "p1") return ElementOrder::P1;
  if (name == "p2") return ElementOrder::P2;
  return std::nullopt;
}
/// The FEM nodes of a tet mesh at an order: N (P1), N + #E (P2). Tet indices are not checked.
Eigen::Index femNodeCount(const TetMesh& mesh, ElementOrder order);
/// Stress points per element: 1 (P1), 4 (P2, the corners).
inline int stressPointsPerElement(ElementOrder order) { return order == ElementOrder::P2 ? 4 : 1; }

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
  /// 3N by r: row 3n+i is the i-th displacement component of FEM node n (ElementOrder: N is the
  /// tet mesh's node count for P1, corners plus edges for P2), per unit modal coordinate
  /// (m per √kg·m, since q has units of √kg·m for mass-normalised modes).
  MatrixXdRow modes;
};

/// The thin-axis stretch's range (BakeRecord::thinStretch, TetMeshSettings::thinStretch): from 1
/// (near-regular tets) to kMaxThinStretch; NaN is outside it. Every reader of it checks this one.
inline constexpr double kMaxThinStretch = 16.0;
inline bool isThinStretch(double k) { return k >= 1.0 && k <= kMaxThinStretch; }

/// Settings and timings of the bake that produced an asset; stored for reproducibility.
struct BakeRecord {
  std::string sourceMesh;             ///< file name the object came from (no directories)
  int64_t targetTets = 0;             ///< requested element count (0 = size-driven)
  double cellSizeM = 0.0;             ///< Mesh_3 cell size actually used (of the stretched solid, below)
  double thinStretch = 1.0;           ///< tets this many times wider than thick (TetMeshSettings::thinStretch)
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
  TetMesh tetMesh;            ///< the linear (corner) mesh; also the geometry of a P2 object
  ElementOrder elementOrder = ElementOrder::P1;
  Triangles surfaceFaces;     ///< #F by 3, boundary faces of tetMesh, outward, into tetMesh.nodes
  MeshQuality quality;
  MassProperties massProperties;
  ModalBasis modal;
  /// 6PT by r, P = stressPointsPerElement(elementOrder): rows 6(Pe + c)..6(Pe + c)+5 are
  /// C B_e(c) Φ_e, the stress at point c of element e (P2: corner c) per unit modal coordinate.
  MatrixXdRow stressModes;
  /// Optional (empty: none): the order in which a factorisation of K eliminates its 3N rows,
  /// position k holding the row eliminated k-th, baked as the one with less fill than AMD
  /// (FillOrdering.h); the runtime's static correction factorises in it. Pack: the optional
  /// dataset /objects/elimination_order.
  Eigen::VectorXi eliminationOrder;
  /// The object's own floor on the contact load's spread, as a fraction of its bounding-box
  /// diagonal D, in [0, 1): the runtime spreads a hit over ρ = max(a, this × D, the World's
  /// FractureSettings::contactSpreadFraction × D, the ring at the contact). A length the object's
  /// mesh resolves, chosen with it (the manifest's "contact_spread"): the brick's and the stone
  /// ball's default meshes have rings wider than the World's 0.05 D, and their corrected peaks
  /// agree across meshes at 0.15 D (docs/decisions.md, "Contact loads"). 0: the World's alone.
  /// Pack: the optional dataset /objects/contact_spread_fraction (absent: 0).
  double contactSpreadFraction = 0.0;
  BakeRecord bake;
};

/// Whether `fraction` is a valid ObjectAsset::contactSpreadFraction: finite, in [0, 1).
inline bool isContactSpreadFraction(double fraction) { return fraction >= 0.0 && fraction < 1.0; }

/// Whether `order` holds each of 0..n−1 exactly once.
bool isPermutation(const Eigen::VectorXi& order, Eigen::Index n);

}  // namespace brittle
