// MomentDescriptor.h — shape descriptor made of the exact volume moments m_pqr of the solid in its
// canonical frame (CanonicalFrame.h), up to a configurable order N.
//
// The moments are exact for the polyhedron (divergence theorem over the closed surface, see
// VolumeMoments.h), so the descriptor is invariant to translation, rotation and uniform scale up
// to rounding, and to remeshing of the same polyhedron exactly.
//
// Layout. In the canonical frame m_000 = 1 (unit volume), m_100 = m_010 = m_001 = 0 (centre of
// mass) and m_110 = m_101 = m_011 = 0 (principal axes) hold by construction, so they are left out.
// The descriptor is [m_200, m_020, m_002, then every m_pqr with p+q+r = 3, …, N in the graded
// order of monomialIndex] — 3 + Σ_{n=3..N} (n+1)(n+2)/2 values (28 for N = 4).
//
// Weights. Component of order n is multiplied by sqrt(w_n), so the plain Euclidean distance
// between two descriptors is the order-weighted distance sqrt(Σ_n w_n Σ_{|α|=n} Δm_α²). Baking the
// weights in keeps the descriptors usable by any L2 index (FLANN) unchanged.
#pragma once

#include <array>
#include <vector>

#include "brittle/descriptors/CanonicalFrame.h"
#include "brittle/descriptors/DescriptorTypes.h"
#include "brittle/core/MeshTypes.h"
#include "brittle/core/Result.h"
#include "brittle/descriptors/VolumeMoments.h"

namespace brittle {

struct MomentDescriptorSettings {
  /// Highest moment order N, in [2, kMaxMomentOrder].
  int maxOrder = 4;
  /// Empty: every order weighs 1. Otherwise maxOrder + 1 finite non-negative weights, entry n for
  /// order n (entries 0 and 1 are unused).
  std::vector<double> orderWeights;
};

/// Checks maxOrder and the weights. Error: InvalidArgument naming the field.
Status validateMomentDescriptorSettings(const MomentDescriptorSettings& settings);

/// Number of values in a moment descriptor of order maxOrder (≥ 2).
int momentDescriptorSize(int maxOrder);

/// Exponents (p, q, r) of each descriptor component, in order (momentDescriptorSize entries).
std::vector<std::array<int, 3>> momentDescriptorLayout(int maxOrder);

/// Moment descriptor of the solid bounded by a closed, outward surface, seen in `frame`.
/// Inputs: surface (#V by 3 vertices in metres, #F by 3 faces); frame, usually one candidate of
/// computeCanonicalFrames on the same surface.
/// Output: momentDescriptorSize(maxOrder) dimensionless values.
/// Errors: those of computeVolumeMoments (EmptyMesh, NonFiniteValue, InvalidArgument, OpenMesh);
/// InvalidArgument for bad settings or a frame with a non-finite or non-positive scale.
Result<Descriptor> computeMomentDescriptor(const TriangleMesh& surface, const CanonicalFrame& frame,
                                           const MomentDescriptorSettings& settings = {});

/// One descriptor per candidate frame (#candidates by momentDescriptorSize), from a single pass
/// over the mesh. Errors as computeMomentDescriptor; InvalidArgument when frames is empty.
Result<DescriptorMatrix> computeMomentDescriptors(const TriangleMesh& surface, const CanonicalFrames& frames,
                                                  const MomentDescriptorSettings& settings = {});

/// One descriptor per candidate frame from the moments computeCanonicalFrames already stored
/// (frames.centralMoments, order 4): no pass over the mesh, so frames + descriptors cost one pass.
/// Errors: InvalidArgument for bad settings, maxOrder > frames.centralMoments.maxOrder, or no frame.
Result<DescriptorMatrix> momentDescriptorsFromFrames(const CanonicalFrames& frames,
                                                     const MomentDescriptorSettings& settings = {});

/// The descriptor from moments already expressed in the canonical frame (order ≥ maxOrder).
/// Errors: InvalidArgument for bad settings or too low an order.
Result<Descriptor> momentDescriptorFromMoments(const VolumeMoments& canonicalMoments,
                                               const MomentDescriptorSettings& settings = {});

/// Distance between two moment descriptors built with the same settings: Euclidean (the order
/// weights are already inside the values).
inline float momentDistance(const Descriptor& a, const Descriptor& b) { return descriptorL2Distance(a, b); }

}  // namespace brittle
