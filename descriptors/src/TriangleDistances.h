// TriangleDistances.h — the squared distances from many points to one triangle, several points to a
// vector register, with the bits of closestOnTriangle (brittle/core/TriangleGeometry.h).
#pragma once

#include <Eigen/Core>
#include <cstddef>

#include "brittle/core/Simd.h"

namespace brittle::detail {

/// out[i] ← |closestOnTriangle(p_i, a, b, c) − p_i|² for i < count, p_i = (x[i], y[i], z[i]): two
/// points to an SSE2 register or four to an AVX one. Each lane takes closestOnTriangle's Voronoi
/// regions in its order and its operations on the region it lands in (no fused multiply-add), so
/// every value is that function's bits (`VoxelDescriptor.TriangleDistancesInLanesAreTheScalarBits`).
/// A point for which the triangle has no area (its no-area branch) is measured by closestOnTriangle
/// itself.
void squaredDistancesToTriangle(const double* x, const double* y, const double* z, size_t count, const Eigen::Vector3d& a,
                                const Eigen::Vector3d& b, const Eigen::Vector3d& c, double* out, Lanes lanes);

}  // namespace brittle::detail
