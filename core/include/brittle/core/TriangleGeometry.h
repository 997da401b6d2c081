// TriangleGeometry.h — the closest point of a triangle to a point, shared by the runtime's contact
// location (ContactGeometry) and the clamped signed distance descriptor (VoxelDescriptor).
#pragma once

#include <Eigen/Core>
#include <algorithm>

namespace brittle {

/// The closest point of triangle abc to p, by the Voronoi region p falls in (a vertex, an edge or
/// the face; Ericson, Real-Time Collision Detection, §5.1.5), with its barycentric weights (a, b,
/// c's) in `bary`. A triangle without area has no face region (nor an edge of no length): the
/// nearest point of its edges. The extra conditions hold on any triangle with area, so its answers
/// are the plain algorithm's, bit for bit.
inline Eigen::Vector3d closestOnTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                         const Eigen::Vector3d& c, Eigen::Vector3d& bary) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) { bary = {1, 0, 0}; return a; }
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) { bary = {0, 1, 0}; return b; }
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0 && d1 - d3 > 0) {  // d1 − d3 = |ab|²
    const double v = d1 / (d1 - d3);
    bary = {1 - v, v, 0};
    return a + v * ab;
  }
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) { bary = {0, 0, 1}; return c; }
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0 && d2 - d6 > 0) {  // d2 − d6 = |ac|²
    const double w = d2 / (d2 - d6);
    bary = {1 - w, 0, w};
    return a + w * ac;
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0 && (d4 - d3) + (d5 - d6) > 0) {  // = |bc|²
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    bary = {0, 1 - w, w};
    return b + w * (c - b);
  }
  if (!(va + vb + vc > 0)) {  // no area: the nearest point of the three edges
    const auto onEdge = [&](const Eigen::Vector3d& u, const Eigen::Vector3d& v) {
      const Eigen::Vector3d e = v - u;
      const double length2 = e.squaredNorm();
      return length2 > 0 ? std::clamp(e.dot(p - u) / length2, 0.0, 1.0) : 0.0;
    };
    const double tab = onEdge(a, b), tbc = onEdge(b, c), tca = onEdge(c, a);
    const Eigen::Vector3d qab = a + tab * ab, qbc = b + tbc * (c - b), qca = c + tca * (a - c);
    const double dab = (qab - p).squaredNorm(), dbc = (qbc - p).squaredNorm(), dca = (qca - p).squaredNorm();
    if (dab <= dbc && dab <= dca) { bary = {1 - tab, tab, 0}; return qab; }
    if (dbc <= dca) { bary = {0, 1 - tbc, tbc}; return qbc; }
    bary = {tca, 0, 1 - tca};
    return qca;
  }
  const double denom = 1.0 / (va + vb + vc);
  const double v = vb * denom, w = vc * denom;
  bary = {1 - v - w, v, w};
  return a + ab * v + ac * w;
}

}  // namespace brittle
