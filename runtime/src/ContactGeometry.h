// ContactGeometry.h — where an impact lands on a body and how its Hertz load spreads over the
// body's nodes. Private to the runtime (ImpactStages.cpp).
//
// locateContact: the closest point of the body's boundary to the reported point (Ericson,
// Real-Time Collision Detection §5.1.5), its face and barycentric weights, and the local radius of
// curvature at the nearest node, from the normal curvature along each surface edge there,
// κ = 2 n·(x_i − x_j)/|x_i − x_j|², averaged (flat or concave: ∞).
// contactLoadWeights: the Hertz pressure √(1 − r²/a²) on the boundary nodes inside the patch of
// radius a, weighted by each node's area; a patch smaller than the mesh loads the nearest face's
// nodes barycentrically. Weights sum to 1.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <utility>
#include <vector>

#include "Body.h"

namespace brittle::detail {

struct ContactSite {
  Eigen::Index face = -1;                         ///< boundary triangle (row of topology.boundaryTriangles)
  Eigen::Vector3d bary = Eigen::Vector3d::Zero(); ///< barycentric weights of the closest point on it
  int32_t nearestNode = -1;                       ///< the face's corner nearest to the point
  double distanceM = 0.0;                         ///< from the reported point to the surface
};

/// The closest boundary point to `pointLocal` (body frame, m). Errors: InvalidArgument when it is
/// farther than `toleranceM` or the body has no boundary.
Result<ContactSite> locateContact(const Body& body, const Eigen::Vector3d& pointLocal, double toleranceM);

/// The local radius of curvature (m) at the site's nearest node; +∞ where flat or concave.
double surfaceRadiusAt(const Body& body, const ContactSite& site);

/// Node weights of the contact load (summing to 1) into `weights`, which keeps its storage.
void contactLoadWeights(const Body& body, const ContactSite& site, const Eigen::Vector3d& pointLocal,
                        double patchRadiusM, std::vector<std::pair<int32_t, double>>& weights);

}  // namespace brittle::detail
