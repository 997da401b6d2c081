#include "TriangleDistances.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "brittle/core/TriangleGeometry.h"

namespace brittle::detail {
namespace {

// out ← e · u, lane by lane, as Eigen reduces a 3-vector: (e₀u₀ + e₁u₁) + e₂u₂. (An output argument:
// a 256-bit return type changes the ABI where AVX is not enabled.)
template <class Pack>
[[gnu::always_inline]] inline void dotInto(const Pack u[3], const Eigen::Vector3d& e, Pack& out) {
  out = (e[0] * u[0] + e[1] * u[1]) + e[2] * u[2];
}

// `count` points against the triangle, L at a time. Each region of closestOnTriangle is a mask; a
// lane takes the first region it lies in, in that function's order: vertex a, vertex b, edge ab,
// vertex c, edge ac, edge bc, no area, the face. Each lane makes the one division the scalar code
// makes in its region (an edge's numerator over its denominator, or the face's reciprocal). A dot
// product is dotInto's. A lane in the no-area branch reads NaN (the caller measures it in scalar
// code: an AVX function calls nothing with its registers live).
template <int L>
[[gnu::always_inline]] inline void distancesInLanes(const double* x, const double* y, const double* z, size_t count,
                                                     const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                                                     double* out) {
  using Pack = VectorOf<double, L>;
  using Mask = VectorOf<int64_t, L>;
  const Eigen::Vector3d ab = b - a, ac = c - a, bc = c - b;
  Pack zero = {}, one = {}, nan = {};
  for (int l = 0; l < L; ++l) one[l] = 1.0, nan[l] = std::numeric_limits<double>::quiet_NaN();
  for (size_t i = 0; i < count; i += L) {
    const size_t lanes = std::min<size_t>(L, count - i);
    Pack p[3];
    if (lanes == static_cast<size_t>(L)) {
      loadLanes<L>(x + i, p[0]);
      loadLanes<L>(y + i, p[1]);
      loadLanes<L>(z + i, p[2]);
    } else {  // the last points, the rest of the register filled with the last one
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"  // GCC 12 takes lane stores for reads
      for (int l = 0; l < L; ++l) {
        const size_t j = i + std::min<size_t>(static_cast<size_t>(l), lanes - 1);
        p[0][l] = x[j], p[1][l] = y[j], p[2][l] = z[j];
      }
#pragma GCC diagnostic pop
    }
    Pack ap[3], bp[3], cp[3];
    for (int k = 0; k < 3; ++k) ap[k] = p[k] - a[k], bp[k] = p[k] - b[k], cp[k] = p[k] - c[k];
    Pack d1, d2, d3, d4, d5, d6;
    dotInto(ap, ab, d1), dotInto(ap, ac, d2), dotInto(bp, ab, d3), dotInto(bp, ac, d4), dotInto(cp, ab, d5), dotInto(cp, ac, d6);
    const Pack vc = d1 * d4 - d3 * d2, vb = d5 * d2 - d1 * d6, va = d3 * d6 - d5 * d4;
    const Pack e43 = d4 - d3, e56 = d5 - d6;
    const Mask inA = (d1 <= 0) & (d2 <= 0);
    const Mask inB = ~inA & (d3 >= 0) & (d4 <= d3);
    Mask taken = inA | inB;
    const Mask inAB = ~taken & (vc <= 0) & (d1 >= 0) & (d3 <= 0) & (d1 - d3 > 0);
    taken |= inAB;
    const Mask inC = ~taken & (d6 >= 0) & (d5 <= d6);
    taken |= inC;
    const Mask inAC = ~taken & (vb <= 0) & (d2 >= 0) & (d6 <= 0) & (d2 - d6 > 0);
    taken |= inAC;
    const Mask inBC = ~taken & (va <= 0) & (e43 >= 0) & (e56 >= 0) & (e43 + e56 > 0);
    taken |= inBC;
    const Pack area = va + vb + vc;
    const Mask noArea = ~taken & ~(area > 0);
    // One division a lane: an edge's t = numerator / denominator, from the region's own origin along
    // its own direction, or the face's 1 / (va + vb + vc), then a + ab v + ac w.
    const Mask onEdge = inAB | inAC | inBC;
    const Pack numerator = inAB ? d1 : inAC ? d2 : inBC ? e43 : one;
    const Pack denominator = inAB ? d1 - d3 : inAC ? d2 - d6 : inBC ? e43 + e56 : noArea | taken ? one : area;
    const Pack t = numerator / denominator;
    const Pack v = vb * t, w = vc * t;
    Pack squared = zero;
    for (int k = 0; k < 3; ++k) {
      const Pack face = (a[k] + ab[k] * v) + ac[k] * w;
      const Pack edge = inAB ? a[k] + t * ab[k] : inAC ? a[k] + t * ac[k] : b[k] + t * bc[k];
      Pack q = onEdge ? edge : face;
      q = inA ? a[k] + zero : inB ? b[k] + zero : inC ? c[k] + zero : q;
      const Pack d = q - p[k];
      squared = k == 0 ? d * d : squared + d * d;
    }
    squared = noArea ? nan : squared;
    for (size_t l = 0; l < lanes; ++l) out[i + l] = squared[l];
  }
}

void distancesNarrow(const double* x, const double* y, const double* z, size_t count, const Eigen::Vector3d& a,
                     const Eigen::Vector3d& b, const Eigen::Vector3d& c, double* out) {
  distancesInLanes<2>(x, y, z, count, a, b, c, out);
}

BRITTLE_TARGET_AVX void distancesWide(const double* x, const double* y, const double* z, size_t count, const Eigen::Vector3d& a,
                                      const Eigen::Vector3d& b, const Eigen::Vector3d& c, double* out) {
  distancesInLanes<4>(x, y, z, count, a, b, c, out);
}

}  // namespace

void squaredDistancesToTriangle(const double* x, const double* y, const double* z, size_t count, const Eigen::Vector3d& a,
                                const Eigen::Vector3d& b, const Eigen::Vector3d& c, double* out, Lanes lanes) {
  if (lanes == Lanes::Wide) {
    distancesWide(x, y, z, count, a, b, c, out);
  } else {
    distancesNarrow(x, y, z, count, a, b, c, out);
  }
  for (size_t i = 0; i < count; ++i) {
    if (!std::isnan(out[i])) continue;
    const Eigen::Vector3d p(x[i], y[i], z[i]);
    Eigen::Vector3d bary;
    out[i] = (closestOnTriangle(p, a, b, c, bary) - p).squaredNorm();
  }
}

}  // namespace brittle::detail
