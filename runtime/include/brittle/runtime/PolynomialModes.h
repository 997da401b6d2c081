// PolynomialModes.h — a solid's lowest elastic frequencies from its volume moments alone:
// Rayleigh–Ritz over polynomial displacement fields (Visscher et al. 1991, "On the normal modes
// of free vibration of inhomogeneous and anisotropic elastic objects", the xyz algorithm).
//
// The trial space holds every displacement whose components are polynomials of degree ≤ p in
// y = (x − c)/s (c the centroid, s the RMS radius about it): 3 × monomialCount(p) functions
// e_i y^α. For two of them, u = e_i y^α and v = e_j y^β, the isotropic strain energy and the
// kinetic energy are sums of the solid's moments m_γ = ∫ y^γ dV:
//
//   K = λ α_i β_j m[α+β−e_i−e_j] + μ α_j β_i m[α+β−e_i−e_j] + μ δ_ij Σ_k α_k β_k m[α+β−2e_k]
//   M = ρ δ_ij m[α+β]
//
// (over s² for K in physical units), so moments of order ≤ 2p are all the solid contributes, and
// they are exact from its closed surface or its tets (VolumeMoments.h). The space contains the
// six rigid motions (their Ritz values are zero and are dropped) and no mesh, so nothing locks:
// a thin plate's twisting mode w = xy is in it from p = 2. Ritz values bound the solid's own
// frequencies from above and fall as p grows.
//
// What it is for: a fragment's frequencies at runtime, where a database match can be far off
// (runtime fragments are faceted and lean), at a cost that depends on p, not on the fragment's
// size. What it misses: modes localised in a part of the solid (a piece hanging by a thin neck
// swings as a hinge that no low-degree polynomial follows), and every mode above the space's
// reach. Measured against fragments' own P2 modes: docs/results/speed-accuracy.md.
#pragma once

#include <Eigen/Core>

#include "brittle/core/MeshTypes.h"
#include "brittle/core/Result.h"
#include "brittle/database/Material.h"
#include "brittle/database/ObjectAsset.h"
#include "brittle/descriptors/VolumeMoments.h"
#include "brittle/runtime/FemAssembly.h"

namespace brittle {

/// The highest polynomial degree: the moments it needs (order 2p) are those VolumeMoments knows.
inline constexpr int kMaxPolynomialModeDegree = kMaxMomentOrder / 2;

struct PolynomialModes {
  int degree = 0;
  /// The elastic Ritz frequencies (Hz), ascending, the six rigid motions removed: at most
  /// 3 × monomialCount(degree) − 6 of them (fewer when rounding makes directions of the space
  /// indistinguishable; see keptDirections).
  Eigen::VectorXd frequenciesHz;
  Eigen::Index basisSize = 0;       ///< 3 × monomialCount(degree)
  Eigen::Index keptDirections = 0;  ///< directions whose mass is above 1e-13 of the largest (all, in double, up to p = 5)
  /// c: the solid's centroid (m), relative to the moments' origin (the overload from a surface:
  /// in the surface's own coordinates)
  Eigen::Vector3d centreM = Eigen::Vector3d::Zero();
  double scaleM = 0.0;                                ///< s: its RMS radius about c (m)
  /// basisSize by frequenciesHz.size() (empty without shapes): mode k's displacement is
  /// Σ_b coefficients(b, k) e_i y^α for basis function b = 3·(graded index of α) + i, y = (x − c)/s; mass-normalised over the solid
  /// (∫ ρ u_k·u_l dV = δ_kl, u in m per √kg·m as ModalBasis::modes).
  Eigen::MatrixXd coefficients;

  /// The first `count` modes' displacements at `points` (#P by 3, m, in centreM's frame):
  /// 3P by count, row 3p + i the i-th component at point p (ModalBasis::modes' layout).
  /// Preconditions: the modes were computed with shapes, count ≤ frequenciesHz.size().
  MatrixXdRow displacements(const Points& points, Eigen::Index count) const;
};

/// The lowest frequencies of the solid with these moments and material, from degree-p polynomial
/// fields. Inputs: moments in metres (∫ x^α dV, m^(3+|α|)) about any point near the solid (its
/// centre keeps the sums free of cancellation), of order ≥ 2·degree; degree in
/// [1, kMaxPolynomialModeDegree]; withShapes false leaves coefficients empty (the frequencies
/// alone cost about half). Without shapes, `count` > 0 asks for the lowest `count` frequencies
/// only, by shift-invert Lanczos on the Ritz problem instead of its full eigen solve (~0.6 ms
/// against 2 at p = 5; the same values within 1e-9, the full solve's own rounding for the
/// lowest); frequenciesHz then holds at most `count`.
/// Errors: InvalidArgument (degree out of range, moments of too low an order), NonFiniteValue (a
/// moment is not finite), EmptyMesh (volume ≤ 0: an empty or inward solid), InvalidMaterial,
/// EigenNotConverged.
Result<PolynomialModes> polynomialModes(const VolumeMoments& moments, const Material& material, int degree,
                                        bool withShapes = true, Eigen::Index count = -1);

/// The same from a closed, outward surface (#V by 3 vertices in metres, #F by 3 faces): its
/// moments about its vertices' mean, then the above. Errors: those of computeVolumeMoments and
/// the above.
Result<PolynomialModes> polynomialModes(const TriangleMesh& surface, const Material& material, int degree,
                                        bool withShapes = true, Eigen::Index count = -1);

/// The same fields on a finite-element model of the solid: interpolated at its nodes (`nodes`, #N
/// by 3, m) and run through its own K and M (`fem`, 3N by 3N, node-interleaved, FemAssembly.h;
/// at P2, N counts the edge nodes too). Since the interpolated fields are a subspace of the
/// model's, their Ritz frequencies bound the model's own from above mode by mode, and the ratio of
/// the two says what the model's fields gain over the polynomials on the same mesh: near 1 for a
/// compact solid, far below it where a part swings on a thin neck (FragmentModes.h,
/// meshFrequencyRatios). Returns the elastic frequencies (Hz, ascending, the six rigid motions
/// dropped): all, or the lowest `count` (> 0) as polynomialModes computes them without shapes.
/// Errors: InvalidArgument (degree, sizes), NonFiniteValue, EmptyMesh (no extent),
/// EigenNotConverged.
Result<Eigen::VectorXd> polynomialFrequenciesOnMesh(const Points& nodes, const FemSystem& fem, int degree, Eigen::Index count = -1);

/// A matched fragment's body with the fragment's own frequencies: the asset (an entry placed on
/// the fragment, ScalingLaws.h) keeps its mode shapes and stress modes, and its r eigenvalues
/// become the first r of `modes` (r: its own mode count), computed from the fragment's solid.
/// Mode j keeps its place: the entry's j-th shape rings at the fragment's j-th frequency. The
/// shapes stay the entry's, on purpose: they are exact on the entry's mesh, traction-free on its
/// surface, and they are what its stress modes and static correction were made for, where the
/// Ritz fields sampled on the entry's mesh extrapolate beyond the fragment (up to 7× their largest
/// value on the fragment's surface, 1.4× at the 90th percentile, on the default objects' pieces).
/// residuals become ‖Kφ − λMφ‖/‖Kφ‖ for the new λ on the entry's K and M, |1 − λ/λ_entry| (the
/// stored basis taken as exact). Errors: InvalidArgument (fewer modes than r).
Status adoptPolynomialFrequencies(ObjectAsset& asset, const PolynomialModes& modes);
/// The same on a basis alone: its eigenvalues (the entry's) in, the adopted ones out; its modes
/// are not read.
Status adoptPolynomialFrequencies(ModalBasis& basis, const PolynomialModes& modes);

}  // namespace brittle
