// FragmentModes.h — the exact path for a new fragment: its own modal analysis, computed at runtime
// from the broken body's tet mesh, instead of the nearest database entry rescaled to it.
//
//   auto sub = fragmentSubMesh(parent.tetMesh, topology, state.nodeLabels, state.edgeCuts, 2);  // Result<FragmentSubMesh>
//   auto asset = exactFragmentAsset(sub.value(), material, ExactModesSettings{}, "plate.f2");  // Result<ObjectAsset>
//
// The fragment's mesh is its exact solid, the same partition FragmentSurfaces.h draws: the parent's
// tets whose four nodes carry the label, as they are, and in each tet the crack crosses, the
// label's corner cells cut into tets (from the tet's centre point to the label's part of each
// face, fanned from the face's centre point). Points on a crossed edge or face are shared by every
// tet around it, so the mesh is conforming, and its volume is the fragment surface's volume.
//
// Modes: K and M of the sub-mesh (FemAssembly.h), then the lowest modeCount + 6 eigenpairs of
// K φ = λ M φ by Spectra's shift-invert Lanczos on a supernodal Cholesky factor of K − σM (σ < 0,
// so it is positive definite; runtime/src/SupernodalCholesky.h, Eigen's dense kernels per panel; no
// ARPACK or CHOLMOD in the runtime), handed on in SimplicialLDLT's form, or by Eigen's dense
// generalised solver when 3N ≤ denseMaxDof. The six rigid modes are dropped, the others are
// mass-normalised, and the stress modes follow (computeStressModes). The cost grows with the
// fragment's size, which is why the World takes this path only below a tet count
// (FractureSettings::exactModesMaxTets; chart 5 in docs/results/speed-accuracy.md picks its default).
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCholesky>
#include <cstdint>
#include <memory>
#include <vector>

#include "brittle/database/Material.h"
#include "brittle/database/ObjectAsset.h"
#include "brittle/core/MeshTypes.h"
#include "brittle/core/Result.h"
#include "brittle/runtime/FemAssembly.h"
#include "brittle/runtime/TetTopology.h"

namespace brittle {

struct FragmentSubMesh {
  TetMesh mesh;                  ///< in the parent's frame (m)
  int64_t wholeTets = 0;         ///< parent tets entirely in the fragment, kept as they are
  int64_t splitTets = 0;         ///< parent tets the crack crosses, of which the fragment's part was split into tets
  double droppedVolumeM3 = 0.0;  ///< parts not face-connected to the largest one (normally none)
};

/// How fragmentSubMesh fills a tet the crack crosses.
enum class CutCells {
  /// The label's corner cells exactly (FragmentSurfaces.h): tets fanned from a point in the tet to
  /// the label's part of each face, itself fanned from a point in the face. The sub-mesh holds the
  /// fragment's own solid (the exact path's mesh).
  Fans,
  /// Where one crack crosses the tet (two labels at its corners), the label's part as the tet or
  /// prism between its corners and the crack points, with no point of its own; fans elsewhere, with
  /// no face point on a face of two labels. The same crack points, a planar crack face per tet: about
  /// half the points and a quarter of the tets of Fans on the runtime's pieces, for the mesh check
  /// (meshFrequencyRatios), which compares two models on one mesh.
  Prisms,
};

/// Per label in [0, labelCount): how many parent tets hold a part of it (whole or split), the size
/// the World compares with exactModesMaxTets before building anything. Labels out of range are
/// not counted.
std::vector<int64_t> fragmentTetCounts(const TetMesh& parent, const Eigen::VectorXi& nodeLabels, int labelCount);

/// Degrees of freedom of fragmentSubMesh(…, label) at `order` (3 × its nodes, P2: with one node per
/// edge), counted from the parent's labels without making the sub-mesh: its points are the label's
/// nodes, a crack point per edge with one end in the label, a point per crossed face and one per
/// crossed tet, and its edges follow from how fragmentSubMesh fans each crossed tet (below). Equal
/// to the sub-mesh's count when no part of it is dropped (droppedVolumeM3 = 0) and no fan tet is
/// flat; with a part dropped, the sub-mesh has fewer. The World checks exactModesMaxDof on this
/// before cutting anything: a P2 fragment of 150 parent tets has 3–9k, and cutting one out and
/// numbering its edges took 0.2–0.7 ms, 2 of the stone ball's 10.5 ms. Labels out of range, or
/// sizes that do not match, give 0. With CutCells::Prisms: the points that fragmentSubMesh makes
/// then (the label's nodes, the crack points, a point per tet of three or four labels and per
/// face of three), P1 only (P2 gives 0).
int64_t fragmentCutDof(const TetMesh& parent, const TetTopology& topology, const Eigen::VectorXi& nodeLabels, int label,
                       ElementOrder order, CutCells cells = CutCells::Fans);

/// The fragment `label` of a cracked parent (labels and cuts as FractureState holds them) as a tet
/// mesh. Errors: InvalidArgument (sizes, a crossed edge without a finite cut, a label that owns no
/// node).
Result<FragmentSubMesh> fragmentSubMesh(const TetMesh& parent, const TetTopology& topology,
                                        const Eigen::VectorXi& nodeLabels, const Eigen::VectorXd& edgeCuts, int label,
                                        CutCells cells = CutCells::Fans);

struct ExactModesSettings {
  int modeCount = 40;        ///< elastic modes kept (fewer if the mesh has fewer degrees of freedom)
  int denseMaxDof = 240;     ///< at or below this 3N, Eigen's dense solver; above, Spectra
  double tolerance = 1e-10;  ///< Spectra's relative tolerance on the Ritz values
  ElementOrder elementOrder = ElementOrder::P1;  ///< the runtime passes the parent's
};

/// What the exact path's modal analysis factorised, handed to the new body's static correction
/// (StaticCorrection::build with a factor) so that the fragment is factorised once: its K and M,
/// and K − σM with the shift σ < 0 it solved with. Empty (no factor) when the dense solver ran.
struct ExactModesFactor {
  FemSystem fem;
  std::shared_ptr<const Eigen::SimplicialLDLT<SparseMatrixd>> factor;
  double shiftRad2PerS2 = 0.0;
};

/// The fragment as an object the runtime can break: the sub-mesh, its modes and stress modes at
/// settings.elementOrder, with `material`. massProperties are those of the sub-mesh's boundary. The asset's name is
/// `name`. Errors: InvalidArgument (settings, a sub-mesh with fewer than 4 nodes),
/// DegenerateElement, FactorizationFailed, EigenNotConverged, RigidModeMismatch (not exactly six
/// near-zero modes: the sub-mesh hangs together by an edge or a node).
Result<ObjectAsset> exactFragmentAsset(const FragmentSubMesh& sub, const Material& material,
                                       const ExactModesSettings& settings, const std::string& name,
                                       ExactModesFactor* factor = nullptr);

/// What a fragment's own mesh says of its polynomial Ritz frequencies (PolynomialModes.h). The
/// polynomial fields miss what a runtime fragment does most often: a part that swings on a thin
/// neck, or a thin flap, moves in a field no low-degree polynomial follows, and the Ritz values are
/// then too high (up to 35 times on the measured pieces). The fragment's sub-mesh in linear tets
/// holds such fields. On that one mesh, its own lowest frequencies f_h and the polynomial fields'
/// f_p (interpolated at its nodes: a subspace of its fields, so f_h ≤ f_p mode by mode) differ only
/// by what the mesh's fields gain over the polynomials, and the mesh's own error, linear tets'
/// locking in bending, is in both and cancels in their ratio. So a polynomial Ritz frequency f
/// (moments: exact geometry, no locking) is taken to f · f_h / f_p, mode by mode
/// (applyMeshRatios). Measured against the pieces' own P2 modes: docs/results/speed-accuracy.md,
/// "A fragment's own frequencies from its moments".
/// How many of a matched fragment's lowest modes the World corrects by its mesh's ratios: the
/// three that chart 5 measures (the fourth and above keep their Ritz values).
inline constexpr int kMeshRatioModes = 3;

struct MeshFrequencyRatios {
  Eigen::VectorXd meshHz;        ///< the sub-mesh's own lowest elastic frequencies (linear tets, Hz)
  Eigen::VectorXd polynomialHz;  ///< the polynomial fields' on the same mesh (Hz), as many
  Eigen::VectorXd ratios;        ///< meshHz / polynomialHz, each in (0, 1]
};

/// The lowest `count` ratios at polynomial degree `degree`. Errors: InvalidArgument (degree
/// outside [1, kMaxPolynomialModeDegree], count < 1, a sub-mesh too small for `count` modes),
/// those of exactFragmentAsset's analysis (DegenerateElement, FactorizationFailed,
/// EigenNotConverged, RigidModeMismatch: the sub-mesh hangs together by an edge or a node) and
/// of polynomialFrequenciesOnMesh.
Result<MeshFrequencyRatios> meshFrequencyRatios(const FragmentSubMesh& sub, const Material& material, int degree, int count,
                                                ElementOrder order = ElementOrder::P1);

/// Polynomial Ritz frequencies (ascending, Hz) times the ratios, mode by mode, for as many modes as
/// there are ratios, then in ascending order again. The modes above keep their values: each is at
/// least the highest of those scaled, since the ratios are at most 1.
void applyMeshRatios(Eigen::VectorXd& frequenciesHz, const MeshFrequencyRatios& ratios);

/// What the mesh gained over the polynomials: 1 − the smallest ratio, in [0, 1). The indicator of a
/// checked body's error (FrequencyErrorModels::checked, MatchErrors.h): on the default objects'
/// pieces its rank correlation with the checked frequencies' error is 0.72. NaN without ratios.
double meshGain(const MeshFrequencyRatios& ratios);

}  // namespace brittle
