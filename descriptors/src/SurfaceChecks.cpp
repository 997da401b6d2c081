#include "SurfaceChecks.h"

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "brittle/core/Random.h"
#include "brittle/core/Simd.h"

namespace brittle::detail {
namespace {

// Whether every coordinate is finite: x·0 is 0 for a finite x and NaN otherwise, and a NaN stays in
// a sum. Eight coordinates at a time in four SSE2 registers, over the matrix's storage in one
// stream (Eigen's allFinite walks a row-major N × 3 matrix column by column, one value a branch).
bool allFinite(const Points& p) {
  using Pair = VectorOf<double, 2>;
  const double* x = p.data();
  const Eigen::Index n = p.size(), blocks = n / 8;
  Pair acc[4] = {};
  for (Eigen::Index b = 0; b < blocks; ++b) {
    for (int i = 0; i < 4; ++i) {
      Pair v;
      loadLanes<2>(x + 8 * b + 2 * i, v);
      acc[i] += v * 0.0;
    }
  }
  double rest = 0.0;
  for (Eigen::Index i = 8 * blocks; i < n; ++i) rest += x[i] * 0.0;
  const Pair all = (acc[0] + acc[1]) + (acc[2] + acc[3]);
  return std::isfinite(all[0] + all[1] + rest);
}

}  // namespace

Status checkClosedSurface(const TriangleMesh& surface) {
  const Eigen::Index nv = surface.vertices.rows(), nf = surface.faces.rows();
  if (nv == 0 || nf == 0) {
    return makeError(ErrorCode::EmptyMesh, "surface has " + std::to_string(nv) + " vertices and " +
                                               std::to_string(nf) + " faces");
  }
  if (!allFinite(surface.vertices)) {  // the culprit only on failure
    for (Eigen::Index v = 0; v < nv; ++v) {
      if (!surface.vertices.row(v).allFinite()) {
        return makeError(ErrorCode::NonFiniteValue, "vertex " + std::to_string(v) + " has a non-finite coordinate");
      }
    }
  }
  // Every directed edge (i, j) adds h_i g_j − h_j g_i, so an edge and its reverse cancel and a
  // closed, consistently oriented surface sums to zero. splitmix64 is a bijective mix: distinct
  // vertices get unrelated hashes. Each vertex's pair is mixed once (the faces share them).
  std::vector<uint64_t> hashes(static_cast<size_t>(2 * nv));
  for (Eigen::Index v = 0; v < nv; ++v) {
    hashes[static_cast<size_t>(2 * v)] = splitmix64(static_cast<uint64_t>(v));
    hashes[static_cast<size_t>(2 * v + 1)] = splitmix64(static_cast<uint64_t>(v) ^ 0x5bd1e9955bd1e995ULL);
  }
  uint64_t residue = 0;
  for (Eigen::Index f = 0; f < nf; ++f) {
    uint64_t h[3], g[3];
    for (int k = 0; k < 3; ++k) {
      const int32_t i = surface.faces(f, k);
      if (i < 0 || i >= nv) {
        return makeError(ErrorCode::InvalidArgument, "face " + std::to_string(f) + " has vertex index " +
                                                         std::to_string(i) + " out of range [0, " +
                                                         std::to_string(nv) + ")");
      }
      h[k] = hashes[static_cast<size_t>(2 * i)];
      g[k] = hashes[static_cast<size_t>(2 * i + 1)];
    }
    // Σ over the edges ab, bc, ca of h_i g_j − h_j g_i, regrouped by vertex: three products, not six
    // (the same value: arithmetic modulo 2⁶⁴ is a ring).
    residue += h[0] * (g[1] - g[2]) + h[1] * (g[2] - g[0]) + h[2] * (g[0] - g[1]);
  }
  if (residue != 0) {
    return makeError(ErrorCode::OpenMesh,
                     "surface is not closed: some directed edge has no reverse partner (boundary or "
                     "inconsistently oriented faces)");
  }
  return Ok{};
}

Status checkFrame(const CanonicalFrame& f) {
  if (!f.rotation.allFinite() || !f.translationM.allFinite() || !std::isfinite(f.scalePerM) || !(f.scalePerM > 0.0)) {
    return makeError(ErrorCode::InvalidArgument, "canonical frame has a non-finite value or a non-positive scale");
  }
  return Ok{};
}

}  // namespace brittle::detail
