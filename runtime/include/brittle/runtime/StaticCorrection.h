// StaticCorrection.h — the quasi-static contribution of the modes a truncated basis leaves out
// (mode acceleration). A short contact excites many more modes than r; their response is nearly
// static, u_t(t) ≈ F(t) Σ_{j>r} φ_j φ_jᵀ f / λ_j, and near the contact it carries most of the stress.
//
//   Σ_{j>r} φ_j φ_jᵀ f/λ_j = K⁺ f_e − Σ_{j≤r} φ_j φ_jᵀ f/λ_j,   f_e = f − M Ψ Ψᵀ f,
// where f is the load pattern per newton, Ψ the six M-orthonormal rigid modes (f_e is the load
// in equilibrium with the body's rigid acceleration: inertia relief) and K⁺ the inverse of K on
// the elastic modes, computed as (K + μM)⁻¹ with a tiny shift μ = 10⁻⁶ λ₁ and the rigid part
// projected out (relative error μ/λ_j ≤ 10⁻⁶). The stress per newton, σ̂ = C B u_t, is added to the
// modal stress as σ_e(t) = S_e q(t) + σ̂_e F(t).
//
// The kept modes are taken out of the load, not out of the answer: since (K + μM)Φ = MΦ(Λ + μ),
//   u_t = (K + μM)⁻¹ f̃,   f̃ = f_e − MΦ Φᵀf_e,
// the static response to the load less its share in the kept modes. The solve's result is then the
// correction itself, not the full static response (10–20 times larger on the plate) less the kept
// modes' share, so rounding in the solve is relative to the correction: L's values can be read in
// float (CorrectionStorage::Float, the default: the plate's stress moves by 5e-7 of its peak,
// against 5e-5 when the modes are taken out of the answer).
//
// K and M are assembled and K + μM is factorised (sparse LDLᵀ) once per object when it is loaded;
// H = L⁻¹PM[Ψ Φ] (the inertia relief's and the kept modes' share of every forward solve) and each
// element's stress recovery (ElementStresses: C B_e for P1, the corners' B for P2) are kept. The
// load is any set of FEM nodes (for P2, the contact's consistent load puts most of a pressure on
// mid-edge nodes). An impact then solves with its own sparse load: a forward solve over the load's
// reach in the elimination tree, one pass over H, one full backward solve, and one pass over the
// elements. With a Workspace reused across impacts, that costs no heap allocation.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCholesky>
#include <memory>
#include <utility>
#include <vector>

#include "brittle/database/Material.h"
#include "brittle/database/ObjectAsset.h"
#include "brittle/core/Result.h"
#include "brittle/runtime/FemAssembly.h"

namespace brittle {

/// A sparse LDLᵀ factorisation of K + μM (μ > 0), in Eigen's form.
using ShiftedFactor = Eigen::SimplicialLDLT<SparseMatrixd>;

/// The factorisation of `a` (its lower triangle) eliminating its rows in `order`
/// (ObjectAsset::eliminationOrder: position k holds the row eliminated k-th), or in Eigen's AMD
/// order where `order` is empty. It is computed by supernodes (dense panels, runtime/src/
/// SupernodalCholesky.h) and handed over as SimplicialLDLT's state: the same pattern as Eigen's own
/// factorisation, in a fraction of the time, and not its bits. Errors: InvalidArgument (an order
/// that is not a permutation of a's rows), FactorizationFailed (a not positive definite, or not
/// finite: K + μM with μ > 0 is).
Result<std::shared_ptr<const ShiftedFactor>> factorInOrder(const SparseMatrixd& a, const Eigen::VectorXi& order);
/// Non-zeros of that factor's strict lower L, from the symbolic analysis alone (what the bake
/// compares orders by). `order` as above; one that is not a permutation gives −1.
Eigen::Index factorNonZeros(const SparseMatrixd& a, const Eigen::VectorXi& order);

/// How a correction keeps what every impact reads: L's values and H = L⁻¹PM[Ψ Φ].
enum class CorrectionStorage {
  Float,   ///< rounded to float, every sum in double: half the bytes (the P2 plate: 40 MB against 79 MB
           ///< an impact); the stress moves by rounding only, 5e-7 of its peak on the default plate
  Double,  ///< as factorised: the reference that the tests hold to double rounding
};

class StaticCorrection {
 public:
  /// Factorises the object's K + μM, μ = 10⁻⁶ λ₁, for the first `modes` stored modes.
  /// Errors: those of assembleFem, FactorizationFailed, InvalidArgument (no modes).
  static Result<StaticCorrection> build(const ObjectAsset& asset, const Material& material, int modes,
                                        CorrectionStorage storage = CorrectionStorage::Float);
  /// The same on a factorisation the caller made already: `factor` of K + μM, where `fem` holds
  /// the asset's K and M. The correction's relative error is at most μ/λ_{r+1}, the shift over
  /// the first mode left out: the exact path hands over the factor of its own modal analysis
  /// (μ = 10⁻³ (c/L)²), which saves the fragment's second factorisation.
  /// Errors: InvalidArgument (no factor, one of another size, μ ≤ 0, modes of the wrong size).
  static Result<StaticCorrection> build(const ObjectAsset& asset, const Material& material, int modes,
                                        const FemSystem& fem, std::shared_ptr<const ShiftedFactor> factor, double mu,
                                        CorrectionStorage storage = CorrectionStorage::Float);

  /// Buffers of stressPerNewton, sized on first use.
  struct Workspace {
    Eigen::VectorXd load, displacement, scratch, modal;
    std::vector<std::vector<double>> gathered;  ///< the backward solve's, one per thread
  };

  /// Stress per newton (6PT as ObjectAsset::stressModes, Voigt, Pa/N) of the truncated modes for a unit force along `direction`
  /// spread over nodes with weights summing to 1, and the work f·u_t (m/N) of that load on them.
  /// `stress` and the workspace keep their storage between calls of the same object.
  /// Errors: InvalidArgument (a node out of range, weights that do not sum to 1).
  Status stressPerNewton(const std::vector<std::pair<int32_t, double>>& weights, const Eigen::Vector3d& direction,
                         Eigen::VectorXd& stress, double& complianceMPerN, Workspace& workspace) const;
  /// The same with a workspace of its own.
  Status stressPerNewton(const std::vector<std::pair<int32_t, double>>& weights, const Eigen::Vector3d& direction,
                         Eigen::VectorXd& stress, double& complianceMPerN) const;

  /// This correction, built on a body x̂, serving the same body placed as x = L R x̂ + t (same
  /// material, same node numbering, its modes the placed ones: ScalingLaws.h's instantiateEntry
  /// with E and ρ unchanged), without a factorisation of its own. Everything transforms exactly:
  /// K + μM = L Q (K̂ + μ̂M̂) Qᵀ with Q the per-node rotation (μ and M follow λ ∝ 1/L² and
  /// M ∝ L³), so u = Q û / L for the load rotated back, f̂ = Qᵀ f; the stress is R σ̂ Rᵀ / L² and
  /// the work f·u = f̂·û / L. The data are shared (a database entry's correction serves every
  /// fragment matched to it). `rotation` orthonormal, `lengthM` > 0; composes with an earlier
  /// placement.
  StaticCorrection placed(const Eigen::Matrix3d& rotation, double lengthM) const;

 private:
  struct Data;
  static Result<StaticCorrection> fromFactor(const ObjectAsset& asset, const Material& material, int modes,
                                             const FemMesh& mesh, const FemSystem& fem,
                                             std::shared_ptr<const ShiftedFactor> factor, double mu,
                                             CorrectionStorage storage);
  explicit StaticCorrection(std::shared_ptr<const Data> data) : mData(std::move(data)) {}
  // stressPerNewton on the body the data were built on.
  Status solvePerNewton(const std::vector<std::pair<int32_t, double>>& weights, const Eigen::Vector3d& direction,
                        Eigen::VectorXd& stress, double& complianceMPerN, Workspace& workspace) const;
  std::shared_ptr<const Data> mData;
  // placed(): x = mLengthM mRotation x̂ + t; identity and 1 for the body the data were built on.
  Eigen::Matrix3d mRotation = Eigen::Matrix3d::Identity();
  double mLengthM = 1.0;
  bool mPlaced = false;
};

}  // namespace brittle
