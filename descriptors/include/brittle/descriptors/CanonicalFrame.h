// CanonicalFrame.h — a pose- and size-free frame for a closed solid: centre of mass at the origin,
// principal axes of inertia as coordinate axes, axis signs fixed by third-order moments, unit
// volume. Descriptors computed in this frame are invariant to translation, rotation and uniform
// scale; the search compares shapes there.
//
// Convention (query → canonical):  x_c = s · R (x − t)
//   t  centre of mass of the query solid (query frame, m),
//   R  rotation (det +1); its rows are the canonical axes written in the query frame,
//   s  uniform scale (1/m) with s³ · volume = 1.
//
// Algorithm.
//  1. Exact moments up to order 4 (VolumeMoments.h) give volume, centre of mass and the second
//     moment C = ∫(x−t)(x−t)ᵀ dV. Its eigenvectors are the principal axes, ordered by ascending
//     principal second moment (axis 0 has the least spread, axis 2 the most); right-handed.
//  2. Ambiguity of the axes. Two principal moments whose relative gap (μ_{i+1} − μ_i)/μ_{i+1} is
//     below eigenGapTolerance span a plane in which the eigenvectors are arbitrary (cylinder,
//     square prism); three span all of space (cube, sphere, regular polyhedra). Inside such a
//     subspace the axis is chosen by higher-order moments, which are rotation-covariant:
//       - the direction u that maximises ∫(u·x)³ dV, if that function varies by more than
//         shapeTolerance (dimensionless, relative to μ^{3/2}); this also fixes the axis sign;
//       - otherwise an extremum of ∫(u·x)⁴ dV (the max or the min, whichever lies farther from the
//         mean; both when they are within tieTolerance), if it varies by more than shapeTolerance;
//       - otherwise the subspace is (nearly) rotationally symmetric at order 4, so every choice
//         gives (nearly) the same descriptor; the eigenvectors are kept.
//     Every direction whose objective lies within tieTolerance of the best one is a candidate: the
//     ties of a symmetric shape (the three axes of a cube, the three vertex directions of an
//     equilateral prism) all become candidates. In a 3-d cluster the chosen direction becomes
//     axis 0 and the plane orthogonal to it is treated as a 2-d cluster.
//  3. Axis signs. Along each axis whose sign is not yet fixed, the standardised skewness
//     γ = ∫(e·x)³ / (∫(e·x)²)^{3/2} (volume-normalised) is made positive when |γ| ≥ skewnessTolerance.
//     Axes left free take both signs, subject to det R = +1 (so 0, 1, 2 or 3 free axes give 1, 1,
//     2 or 4 sign patterns). When all three signs are fixed and the result is left-handed (the
//     solid's mirror image is the "positive" one), the least skewed axis is flipped.
//  4. Candidates whose canonical moments up to order 4 agree to duplicateTolerance (relative) are
//     symmetric copies of each other; only the first is kept. At most maxCandidates are returned.
//
// A shape is matched by comparing each of its candidate frames against a database entry stored in
// its first frame: the candidate set of a rotated copy contains the entry's first frame whenever the
// classification in step 2 agrees, which is exact under rigid motion and uniform scale (the
// eigenvalue gaps are invariant) and can change under remeshing only for shapes near a threshold.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "brittle/core/MeshTypes.h"
#include "brittle/core/Result.h"
#include "brittle/descriptors/VolumeMoments.h"

namespace brittle {

/// One rigid-plus-scale transform from the query frame to the canonical frame (see file header).
struct CanonicalFrame {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();    ///< R, det +1
  Eigen::Vector3d translationM = Eigen::Vector3d::Zero();    ///< t, query frame (m)
  double scalePerM = 1.0;                                    ///< s (1/m)

  /// x_c = s R (x − t). xM in the query frame (m); the result is dimensionless.
  Eigen::Vector3d toCanonical(const Eigen::Vector3d& xM) const {
    return scalePerM * (rotation * (xM - translationM));
  }
  /// Inverse: x = Rᵀ x_c / s + t.
  Eigen::Vector3d toQuery(const Eigen::Vector3d& xCanonical) const {
    return rotation.transpose() * xCanonical / scalePerM + translationM;
  }
  /// Every row mapped by toCanonical (#V by 3 in, #V by 3 out).
  Points pointsToCanonical(const Points& pointsM) const;
};

/// Thresholds of the ambiguity tests. All are dimensionless.
struct CanonicalFrameSettings {
  /// Relative gap between consecutive principal second moments below which the two axes are
  /// treated as interchangeable (and chosen by higher-order moments instead).
  double eigenGapTolerance = 0.05;
  /// |standardised skewness| below which an axis sign is ambiguous.
  double skewnessTolerance = 0.05;
  /// Minimum variation of the standardised 3rd/4th-order directional moment inside a degenerate
  /// subspace for it to define a direction.
  double shapeTolerance = 0.01;
  /// Relative closeness (fraction of the objective's range) under which two extrema tie.
  double tieTolerance = 0.05;
  /// Relative difference of canonical moments (orders ≤ 4) under which two candidates are the
  /// same frame of a symmetric shape. 0 keeps all candidates.
  double duplicateTolerance = 1e-7;
  /// Upper bound on the candidates returned (the first ones are kept).
  int maxCandidates = 24;
};

/// The candidate frames of one solid and the invariants used to choose them.
struct CanonicalFrames {
  /// At least one; the first is the primary frame (the one a database entry is stored in).
  std::vector<CanonicalFrame> candidates;
  double volumeM3 = 0.0;
  Eigen::Vector3d centerOfMassM = Eigen::Vector3d::Zero();
  /// Principal second moments of the unit-volume solid, ascending (dimensionless, invariant).
  Eigen::Vector3d principalSecondMoments = Eigen::Vector3d::Zero();
  /// Standardised skewness along the primary frame's axes.
  Eigen::Vector3d skewness = Eigen::Vector3d::Zero();
  /// True when the first two / last two principal moments were within eigenGapTolerance.
  bool degenerateLowerPair = false;
  bool degenerateUpperPair = false;
  /// Exact moments up to order 4 about centerOfMassM, in the query axes (m^(3+p+q+r)). Lets
  /// momentDescriptorsFromFrames skip a second pass over the mesh.
  VolumeMoments centralMoments;

  bool ambiguous() const { return candidates.size() > 1; }
};

/// Checks the thresholds. Error: InvalidArgument naming the field.
Status validateCanonicalFrameSettings(const CanonicalFrameSettings& settings);

/// Canonical frame candidates of the solid bounded by a closed, outward triangle mesh.
///
/// Inputs: surface (#V by 3 vertices in metres, #F by 3 faces, closed, counter-clockwise seen from
/// outside).
/// Errors: EmptyMesh, NonFiniteValue (vertex coordinate), InvalidArgument (face index out of range;
/// zero volume: flat or degenerate solid; negative volume: faces point inward; settings out of
/// range), OpenMesh (the surface has a boundary).
Result<CanonicalFrames> computeCanonicalFrames(const TriangleMesh& surface,
                                               const CanonicalFrameSettings& settings = {});

/// The same from the solid's moments, given (order ≥ 4, about momentsOriginM, m), e.g. summed over
/// its tetrahedra with addTetVolumeMoments: no pass over the faces. The surface gives only its
/// bounding box (the origin the moments are moved to, and the scale of the zero-volume test), so
/// both forms return the same frames up to rounding (where a symmetry leaves an axis or its sign
/// to rounding, e.g. a box, they may keep different but equivalent candidates). The surface is not
/// checked for closure.
/// Errors: InvalidArgument (order below 4, zero or negative volume, settings), NonFiniteValue.
Result<CanonicalFrames> computeCanonicalFrames(const TriangleMesh& surface, const VolumeMoments& moments,
                                               const Eigen::Vector3d& momentsOriginM,
                                               const CanonicalFrameSettings& settings = {});

}  // namespace brittle
