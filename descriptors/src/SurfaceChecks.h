// SurfaceChecks.h — the input checks every descriptor runs at the module boundary (private).
#pragma once

#include "brittle/descriptors/CanonicalFrame.h"
#include "brittle/core/MeshTypes.h"
#include "brittle/core/Result.h"

namespace brittle::detail {

/// Checks that a surface can bound a solid: not empty (EmptyMesh), finite coordinates
/// (NonFiniteValue), face indices in range (InvalidArgument), and closed as an oriented surface
/// (OpenMesh): every directed edge (i, j) is cancelled by a reverse edge (j, i).
///
/// Closedness is tested without building an edge map: φ(i, j) = h(i)g(j) − h(j)g(i) with two
/// 64-bit hashes h, g is antisymmetric, so its sum over all face edges, in wrap-around integer
/// arithmetic, is exactly 0 when the edges cancel in pairs. A boundary edge leaves a random 64-bit
/// residue (false pass ≈ 2⁻⁶⁴). This is the exact condition under which the divergence-theorem
/// integrals do not depend on the reference point; pinched (non-manifold) but closed surfaces pass.
Status checkClosedSurface(const TriangleMesh& surface);

/// A usable canonical frame: finite rotation and translation, a finite positive scale
/// (InvalidArgument otherwise).
Status checkFrame(const CanonicalFrame& frame);

}  // namespace brittle::detail
