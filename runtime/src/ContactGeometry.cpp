#include "ContactGeometry.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace brittle::detail {

Result<ContactSite> locateContact(const Body& body, const Eigen::Vector3d& p, double toleranceM) {
  const Points& x = body.asset.tetMesh.nodes;
  const Triangles& tri = body.topology.boundaryTriangles;
  ContactSite site;
  // The face a scan of every face in row order would keep (the least distance, ties to the lower
  // row), from the faces the tree cannot rule out.
  auto closest = [&](Eigen::Index f, Eigen::Vector3d& bary) {
    return closestOnTriangle(p, x.row(tri(f, 0)), x.row(tri(f, 1)), x.row(tri(f, 2)), bary);
  };
  double best;
  site.face = body.boundaryTree.nearest(
      p, [&](int32_t f) { Eigen::Vector3d bary; return (closest(f, bary) - p).squaredNorm(); }, best);
  if (site.face >= 0) closest(site.face, site.bary);  // the kept face's weights, as the scan kept them
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

double contactLoadRadius(const Body& body, const ContactSite& site, double patchRadiusM, double spreadFraction) {
  const Points& x = body.asset.tetMesh.nodes;
  double h = 0.0;  // the longest surface edge at the contact face's corners: the ring's reach
  for (int k = 0; k < 3; ++k) {
    const int32_t i = body.topology.boundaryTriangles(site.face, k);
    for (int32_t j : body.ring[static_cast<size_t>(i)]) h = std::max(h, (x.row(i) - x.row(j)).norm());
  }
  return std::max({patchRadiusM, spreadFraction * body.sizeM, kContactRingReach * h});
}

void contactLoadWeights(const Body& body, const ContactSite& site, const Eigen::Vector3d& normalLocal, double rho,
                        std::vector<std::pair<int32_t, double>>& weights, std::vector<int32_t>& faces) {
  const Points& x = body.asset.tetMesh.nodes;
  const TetTopology& topo = body.topology;
  const Triangles& tri = topo.boundaryTriangles;
  // The disc's centre: the surface point the contact was placed at.
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  for (int k = 0; k < 3; ++k) p += site.bary[k] * x.row(tri(site.face, k)).transpose();
  const bool quadratic = body.asset.elementOrder == ElementOrder::P2;
  const auto corners = static_cast<int32_t>(x.rows());
  weights.clear();
  // The mid-edge node (N + edge id) between corners a and b of boundary face f.
  auto midEdge = [&](Eigen::Index f, int32_t a, int32_t b) -> int32_t {
    const int32_t tet = topo.boundaryFaces[static_cast<size_t>(f)][0];
    const int32_t lo = std::min(a, b), hi = std::max(a, b);
    for (int k = 0; k < 6; ++k) {
      const int32_t e = topo.tetEdges(tet, k);
      if (topo.edges(e, 0) == lo && topo.edges(e, 1) == hi) return corners + e;
    }
    return -1;  // unreachable: a boundary face's edges are its tet's
  };
  // ∫ N_i p dA over each face the disc reaches: the face split into kSplit² triangles, each with
  // the three-point rule at (2/3, 1/6, 1/6) (exact to degree 2), which follows the pressure's
  // square-root edge closely enough; the total is normalised below, so the resultant is exact.
  constexpr int kSplit = 4;
  // The faces in row order, as a scan of them all, of those whose box the disc reaches.
  body.boundaryTree.within(p, rho, faces);
  for (const int32_t f : faces) {
    const Eigen::Vector3d a = x.row(tri(f, 0)), b = x.row(tri(f, 1)), c = x.row(tri(f, 2));
    Eigen::Vector3d bary;
    if ((closestOnTriangle(p, a, b, c, bary) - p).squaredNorm() >= rho * rho) continue;
    // Only faces that face the impactor: a disc wider than a plate's thickness must not press on
    // its other side.
    if ((b - a).cross(c - a).dot(normalLocal) <= 0.0) continue;
    const double subArea = 0.5 * (b - a).cross(c - a).norm() / (kSplit * kSplit);
    double n[6] = {0, 0, 0, 0, 0, 0};  // corners a, b, c; mid-edges ab, bc, ca
    for (int i = 0; i < kSplit; ++i) {
      for (int j = 0; j < kSplit - i; ++j) {
        // Sub-triangles in barycentric steps: (i, j), (i + 1, j), (i, j + 1), and the flipped one.
        for (int flip = 0; flip < (i + j < kSplit - 1 ? 2 : 1); ++flip) {
          const Eigen::Vector2d v0 = flip ? Eigen::Vector2d(i + 1, j + 1) : Eigen::Vector2d(i, j);
          const Eigen::Vector2d v1(i + 1, j), v2(i, j + 1);
          for (int q = 0; q < 3; ++q) {
            const Eigen::Vector2d uv =
                ((q == 0 ? 4.0 : 1.0) * v0 + (q == 1 ? 4.0 : 1.0) * v1 + (q == 2 ? 4.0 : 1.0) * v2) / (6.0 * kSplit);
            const double l1 = uv[0], l2 = uv[1], l0 = 1.0 - l1 - l2;
            const double r2 = (l0 * a + l1 * b + l2 * c - p).squaredNorm() / (rho * rho);
            if (r2 >= 1.0) continue;
            const double w = std::sqrt(1.0 - r2) * subArea / 3.0;
            if (quadratic) {
              n[0] += w * l0 * (2 * l0 - 1), n[1] += w * l1 * (2 * l1 - 1), n[2] += w * l2 * (2 * l2 - 1);
              n[3] += w * 4 * l0 * l1, n[4] += w * 4 * l1 * l2, n[5] += w * 4 * l2 * l0;
            } else {
              n[0] += w * l0, n[1] += w * l1, n[2] += w * l2;
            }
          }
        }
      }
    }
    for (int k = 0; k < 3; ++k) {
      if (n[k] != 0.0) weights.emplace_back(tri(f, k), n[k]);
      if (quadratic && n[3 + k] != 0.0) weights.emplace_back(midEdge(f, tri(f, k), tri(f, (k + 1) % 3)), n[3 + k]);
    }
  }
  // One weight per node, in node order.
  std::sort(weights.begin(), weights.end(), [](const auto& l, const auto& r) { return l.first < r.first; });
  size_t out = 0;
  for (size_t i = 0; i < weights.size(); ++i) {
    if (out > 0 && weights[out - 1].first == weights[i].first) {
      weights[out - 1].second += weights[i].second;
    } else {
      weights[out++] = weights[i];
    }
  }
  weights.resize(out);
  double total = 0.0;
  for (const auto& [i, w] : weights) total += w;
  if (!(total > 0.0)) {  // unreachable while ρ covers the contact face; kept for a degenerate face
    weights.clear();
    total = 1.0;
    for (int k = 0; k < 3; ++k) weights.emplace_back(tri(site.face, k), site.bary[k]);
  }
  for (auto& [i, w] : weights) w /= total;
}

}  // namespace brittle::detail
