#include "ContactGeometry.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace brittle::detail {
namespace {

// Closest point of triangle abc to p, with its barycentric weights.
Eigen::Vector3d closestOnTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                  const Eigen::Vector3d& c, Eigen::Vector3d& bary) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) { bary = {1, 0, 0}; return a; }
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) { bary = {0, 1, 0}; return b; }
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double v = d1 / (d1 - d3);
    bary = {1 - v, v, 0};
    return a + v * ab;
  }
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) { bary = {0, 0, 1}; return c; }
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double w = d2 / (d2 - d6);
    bary = {1 - w, 0, w};
    return a + w * ac;
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    bary = {0, 1 - w, w};
    return b + w * (c - b);
  }
  const double denom = 1.0 / (va + vb + vc);
  const double v = vb * denom, w = vc * denom;
  bary = {1 - v - w, v, w};
  return a + ab * v + ac * w;
}

}  // namespace

Result<ContactSite> locateContact(const Body& body, const Eigen::Vector3d& p, double toleranceM) {
  const Points& x = body.asset.tetMesh.nodes;
  const Triangles& tri = body.topology.boundaryTriangles;
  double best = std::numeric_limits<double>::infinity();
  ContactSite site;
  for (Eigen::Index f = 0; f < tri.rows(); ++f) {
    Eigen::Vector3d bary;
    const Eigen::Vector3d c = closestOnTriangle(p, x.row(tri(f, 0)), x.row(tri(f, 1)), x.row(tri(f, 2)), bary);
    const double d = (c - p).squaredNorm();
    if (d < best) {
      best = d;
      site.face = f;
      site.bary = bary;
    }
  }
  site.distanceM = std::sqrt(best);
  if (site.face < 0 || site.distanceM > toleranceM) {
    return makeError(ErrorCode::InvalidArgument, "impact: the point is " + std::to_string(site.distanceM) +
                                                     " m from the surface of '" + body.asset.name + "' (tolerance " +
                                                     std::to_string(toleranceM) + " m)");
  }
  Eigen::Index corner;
  site.bary.maxCoeff(&corner);
  site.nearestNode = tri(site.face, corner);
  return site;
}

double surfaceRadiusAt(const Body& body, const ContactSite& site) {
  const Points& x = body.asset.tetMesh.nodes;
  const auto node = static_cast<size_t>(site.nearestNode);
  const Eigen::Vector3d xi = x.row(site.nearestNode), ni = body.nodeNormals.row(site.nearestNode);
  double kappa = 0.0;
  for (int32_t j : body.ring[node]) {
    const Eigen::Vector3d d = xi - x.row(j).transpose();
    kappa += 2.0 * ni.dot(d) / d.squaredNorm();
  }
  kappa /= static_cast<double>(std::max<size_t>(1, body.ring[node].size()));
  return kappa > 1e-3 / body.sizeM ? 1.0 / kappa : std::numeric_limits<double>::infinity();
}

void contactLoadWeights(const Body& body, const ContactSite& site, const Eigen::Vector3d& p, double patchRadiusM,
                        std::vector<std::pair<int32_t, double>>& weights) {
  const Points& x = body.asset.tetMesh.nodes;
  weights.clear();
  double total = 0.0;
  for (int32_t i : body.boundaryNodes) {
    const double r2 = (x.row(i).transpose() - p).squaredNorm() / (patchRadiusM * patchRadiusM);
    if (r2 >= 1.0) continue;
    const double w = std::sqrt(1.0 - r2) * body.topology.nodeAreasM2[i];
    weights.emplace_back(i, w);
    total += w;
  }
  if (!(total > 0.0)) {
    weights.clear();
    total = 0.0;
    for (int k = 0; k < 3; ++k) {
      weights.emplace_back(body.topology.boundaryTriangles(site.face, k), site.bary[k]);
      total += site.bary[k];
    }
  }
  for (auto& [i, w] : weights) w /= total;
}

}  // namespace brittle::detail
