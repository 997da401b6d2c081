// ScalingLaws.h — maps a database entry (unit volume, canonical frame, reference material) onto a
// query solid of any size, pose and material, without a new modal analysis.
//
// Derivation. Let the entry be a body of volume 1 m³ with material (E₀, ν₀, ρ₀) and the query the
// same shape scaled by L (m, L³ = query volume), rotated by Rᵀ and translated by t, with material
// (E, ν, ρ). Query points are x = Rᵀ x̂ L + t (CanonicalFrame::toQuery with s = 1/L).
//  - Linear tet FEM: B_e (strain from nodal displacement) scales as 1/L, element volume as L³, so
//    K = ∫ Bᵀ C B dV scales as (E/E₀)·L·K̂ and M = ∫ ρ NᵀN dV as (ρ/ρ₀)·L³·M̂ (the rotation acts
//    on each node's 3-block and cancels in Bᵀ C B for an isotropic C).
//  - Eigenvalues: K φ = λ M φ gives λ = λ̂ · (E/E₀) · (ρ₀/ρ) / L², i.e. f = f̂ · √((E/E₀)(ρ₀/ρ)) / L.
//  - Mass-normalised modes: φ = c · Rᵀ φ̂ per node with c = 1/√((ρ/ρ₀) L³), so that φᵀ M φ = 1.
//  - Stress modes: σ = C B φ, so σ = (E/E₀) · (c/L) · Rᵀ σ̂ R (tensor rotation of each element's
//    Voigt vector).
//  - Mass properties: m = ρ L³ V̂, centre of mass maps as a point, inertia = (ρ/ρ₀) L⁵ Rᵀ Î R,
//    second moment = L⁵ Rᵀ Ŝ R.
// These laws are exact for the discrete model (the scaled, rotated mesh has exactly these K, M),
// which the tests check against a direct modal analysis of the transformed mesh.
//
// Poisson's ratio does not scale: ν changes the shape of the eigenproblem. When ν ≠ ν₀, the modes
// are corrected by Rayleigh–Ritz in the stored basis: with ε̂ = Ĉ₀⁻¹ Ŝ (element strains per modal
// coordinate, exact since Ŝ = Ĉ₀ B Φ̂), the reduced stiffness at ν is K_r = Σ_e V̂_e ε̂_eᵀ C(E₀, ν) ε̂_e
// and the reduced mass stays I; its eigenpairs (λ̂', Y) give Φ̂' = Φ̂ Y and Ŝ' = C(E₀, ν) ε̂ Y. Ritz
// values are upper bounds; the error is second order in the basis error (measured in the tests and
// docs/results/fragment-database.md). The analytic laws are then applied with (E/E₀, ρ/ρ₀).
#pragma once

#include <string>

#include "brittle/database/FragmentDatabase.h"
#include "brittle/database/Material.h"
#include "brittle/database/ObjectAsset.h"
#include "brittle/descriptors/CanonicalFrame.h"
#include "brittle/core/Result.h"

namespace brittle {

struct InstantiateReport {
  bool poissonCorrected = false;  ///< ν ≠ ν₀: Rayleigh–Ritz in the stored basis was applied
  double lengthScaleM = 0.0;      ///< L = 1/frame.scalePerM
};

/// An entry's modes and stress modes at another Poisson ratio ν: the Rayleigh–Ritz correction in
/// its stored basis (above), at the entry's unit size, canonical axes, E₀ and ρ₀. It depends on the
/// entry and ν alone, so a runtime that places one entry many times keeps it per (entry, ν) and
/// hands it to instantiateEntry, which then skips the correction (the same bits as computing it).
struct EntryAtPoisson {
  double poissonRatio = 0.0;  ///< ν the basis is corrected for
  ModalBasis modal;           ///< the entry's modes and eigenvalues (rad²/s²) at ν; frequencies not set
  MatrixXdRow stressModes;    ///< 6PT by r, Pa per unit modal coordinate, at ν
};

/// The correction above for `poissonRatio`. Errors: InvalidMaterial (reference, or ν outside
/// (−1, 0.5)), InvalidArgument (an entry without physical data or with inconsistent arrays).
Result<EntryAtPoisson> entryAtPoisson(const FragmentEntry& entry, const Material& reference, double poissonRatio);

/// The entry's physical data placed onto a query: entry points x̂ map to frame.toQuery(x̂).
/// Inputs: entry (canonical, unit volume, baked at `reference`); `target` material; `frame`, the
/// query's canonical frame that matched (rotation, translation in m, scale in 1/m).
/// Output: an ObjectAsset in the query frame with material `target` (nodes in m, modes per unit
/// modal coordinate, stress modes in Pa per unit modal coordinate, exact mass properties).
/// residuals, orthonormalityError and the bake record are those of the stored basis.
/// `atPoisson`, when given for a target whose ν differs from the reference's, is this entry's
/// entryAtPoisson for that ν, used instead of computing it again.
/// Errors: InvalidMaterial (reference or target), InvalidArgument (frame not finite or scale ≤ 0,
/// entry without physical data, stress modes inconsistent with the mesh, `atPoisson` for another
/// ν or of another shape).
Result<ObjectAsset> instantiateEntry(const FragmentEntry& entry, const Material& reference, const Material& target,
                                     const CanonicalFrame& frame, InstantiateReport* report = nullptr,
                                     const EntryAtPoisson* atPoisson = nullptr);

/// Rotates every Voigt stress row block of a 6T by r matrix: σ' = Q σ Qᵀ per element and mode.
/// Takes any row-major view: a stress vector mapped as 6P by 1 too (StaticCorrection::placed).
void rotateVoigtRows(const Eigen::Matrix3d& q, Eigen::Ref<MatrixXdRow> stressModes);

}  // namespace brittle
