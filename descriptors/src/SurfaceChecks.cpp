#include "SurfaceChecks.h"

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "brittle/core/Random.h"

namespace brittle::detail {

Status checkClosedSurface(const TriangleMesh& surface) {
  const Eigen::Index nv = surface.vertices.rows(), nf = surface.faces.rows();
  if (nv == 0 || nf == 0) {
    return makeError(ErrorCode::EmptyMesh, "surface has " + std::to_string(nv) + " vertices and " +
                                               std::to_string(nf) + " faces");
  }
  if (!surface.vertices.allFinite()) {  // one vectorised pass; the culprit only on failure
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
    for (int k = 0; k < 3; ++k) {
      const int l = (k + 1) % 3;
      residue += h[k] * g[l] - h[l] * g[k];
    }
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
