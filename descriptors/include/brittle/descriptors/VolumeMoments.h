// VolumeMoments.h — exact volume moments m_pqr = ∫ x^p y^q z^r dV (p+q+r ≤ N) of the solid
// bounded by a closed triangle mesh, and how they change under an affine change of coordinates.
//
// Exactness. The solid is the signed sum of the tetrahedra (o, a, b, c), one per face (a, b, c),
// with o the chosen origin (the divergence theorem in discrete form; the result does not depend on
// o when the surface is closed). For a tetrahedron T = (0, a, b, c), x = λ₁a + λ₂b + λ₃c maps the
// reference simplex onto T with dV = det[a b c] dλ, and the Dirichlet integral
// ∫ λ₁^i λ₂^j λ₃^k dλ = i! j! k! / (i+j+k+3)! gives, for any direction u,
//
//   ∫_T (u·x)^n dV = det[a b c] · n! / (n+3)! · h_n(u·a, u·b, u·c),
//
// where h_n is the complete homogeneous symmetric polynomial of degree n (the sum of all monomials
// of degree n in its three arguments). Both sides are polynomials in u; matching the coefficient of
// u^α (|α| = n) with ∫ (u·x)^n = Σ_α n!/α! u^α m_α gives
//
//   m_α(T) = det[a b c] · α! / (n+3)! · [u^α] h_n(u·a, u·b, u·c),        α! = p! q! r!.
//
// h_n is built by the recurrences h_n(A) = A h_{n−1}(A), h_n(A,B) = h_n(A) + B h_{n−1}(A,B),
// h_n(A,B,C) = h_n(A,B) + C h_{n−1}(A,B,C), carried out on coefficient arrays in u. Checks:
// n = 0 gives det/6 (the volume), n = 2 gives the V/20 (Σ pₖpₖᵀ + s sᵀ) of MassProperties.h.
// A general tetrahedron (a, b, c, d) is the same with det = (b−a)·((c−a)×(d−a)) and h_n of four
// arguments (one more recurrence): addTetVolumeMoments, for solids given as tets (the runtime sums
// a fragment's moments over its tets and cut cells instead of its dense surface).
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstddef>

#include "brittle/core/MeshTypes.h"
#include "brittle/core/Result.h"

namespace brittle {

/// Highest moment order supported (the monomial tables are built once up to this order).
inline constexpr int kMaxMomentOrder = 10;

/// Number of monomials x^p y^q z^r with p+q+r ≤ maxOrder: (N+1)(N+2)(N+3)/6.
constexpr int monomialCount(int maxOrder) {
  return (maxOrder + 1) * (maxOrder + 2) * (maxOrder + 3) / 6;
}

/// Position of x^p y^q z^r in the graded order used everywhere in descriptors/: by total degree,
/// then by descending p, then by descending q. Degree 0..2 reads 1, x, y, z, xx, xy, xz, yy, yz, zz.
/// Precondition: p, q, r ≥ 0 and p+q+r ≤ kMaxMomentOrder.
int monomialIndex(int p, int q, int r);

/// Exponents (p, q, r) of the monomial at a graded index (inverse of monomialIndex).
std::array<int, 3> monomialExponents(int index);

/// Volume moments up to maxOrder, in some stated frame.
struct VolumeMoments {
  int maxOrder = 0;
  /// monomialCount(maxOrder) values; values[monomialIndex(p,q,r)] = ∫ x^p y^q z^r dV, in
  /// m^(3+p+q+r) for a mesh in metres (dimensionless in a canonical frame).
  Eigen::VectorXd values;

  double operator()(int p, int q, int r) const { return values[monomialIndex(p, q, r)]; }

  /// Directional moment ∫ (u·x)^order dV for a direction u (any length; not normalised).
  /// Precondition: order ≤ maxOrder.
  double directional(const Eigen::Vector3d& u, int order) const;

  /// directional(u[k], order) into out[k] for k < count: the same bits, several directions to a
  /// vector register.
  void directional(const Eigen::Vector3d* u, size_t count, int order, double* out) const;

  /// Gradient of directional(u, order) with respect to u (3-vector).
  Eigen::Vector3d directionalGradient(const Eigen::Vector3d& u, int order) const;
};

/// Exact volume moments of the solid bounded by a closed, outward triangle mesh, about originM
/// (that is, of x − originM). Pick an origin inside or near the mesh (its centre) to keep the
/// sums free of cancellation.
///
/// Inputs: surface (#V by 3 vertices in metres, #F by 3 faces), maxOrder in [0, kMaxMomentOrder].
/// Output: moments in m^(3+p+q+r); an inward mesh gives moments of the opposite sign.
/// Errors: EmptyMesh (no vertex or no face), NonFiniteValue (a coordinate is NaN or infinite),
/// InvalidArgument (a face index out of range, maxOrder out of range), OpenMesh (some directed
/// edge has no reverse partner, i.e. the surface has a boundary).
Result<VolumeMoments> computeVolumeMoments(const TriangleMesh& surface, int maxOrder,
                                           const Eigen::Vector3d& originM);

/// Adds the exact moments up to maxOrder of the tetrahedron (a, b, c, d), its vertices given
/// relative to the moments' origin, into values[0 .. monomialCount(maxOrder)) (the normalisation
/// of VolumeMoments::values). Signed: positive when (b−a)·((c−a)×(d−a)) > 0. Summing it over a
/// tet mesh gives the moments of the solid, as computeVolumeMoments does over its boundary.
/// Precondition: 0 ≤ maxOrder ≤ kMaxMomentOrder. Order 4 (descriptors and frames) has its own
/// unrolled kernel.
void addTetVolumeMoments(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                         const Eigen::Vector3d& d, int maxOrder, double* values);

/// addTetVolumeMoments at order 4 for `count` tets in turn (tets[i] its four vertices, relative to
/// the origin), each one's terms added to values[0 .. 35) in tet order: the same bits as that many
/// calls, several tets at a time in the widest registers the CPU has (two or four).
void addTetVolumeMomentsOrder4(const std::array<Eigen::Vector3d, 4>* tets, int count, double* values);

/// Moments of the same solid in the coordinates y = A (x − b), given its moments in x:
/// ∫ y^β dy = |det A| Σ_α [x^α] (A(x − b))^β · m_α. Exact up to rounding; the order is kept.
/// Inputs: A (3 by 3, any invertible linear map, e.g. s·R), b (3, in the units of x).
VolumeMoments transformVolumeMoments(const VolumeMoments& moments, const Eigen::Matrix3d& linearMap,
                                     const Eigen::Vector3d& offset = Eigen::Vector3d::Zero());

}  // namespace brittle
