// ContactGeometry.h — where an impact lands on a body and how its Hertz load spreads over the
// body's nodes. Private to the runtime (ImpactStages.cpp).
//
// locateContact: the closest point of the body's boundary to the reported point (Ericson,
// Real-Time Collision Detection §5.1.5; the faces searched through the body's box tree,
// TriangleBoxTree.h), its face and barycentric weights, and the local radius of
// curvature at the nearest node, from the normal curvature along each surface edge there,
// κ = 2 n·(x_i − x_j)/|x_i − x_j|², averaged (flat or concave: ∞).
// contactLoadWeights: the consistent nodal loads f_i = ∫ N_i p dA of the Hertz pressure
// p ∝ √(1 − r²/ρ²) over the disc of radius ρ around the contact point (the closest surface point
// to the reported one), on the boundary faces it reaches that face the impactor (not a thin
// plate's other side), with the element's own surface shape
// functions (P1: the corners; P2: corners and mid-edge nodes, where a uniform pressure puts all
// of its load). Weights sum to 1.
//
// ρ = max(a, s·D, h) (contactLoadRadius): Hertz's patch radius a; a length of the object,
// s = the larger of FractureSettings::contactSpreadFraction (0.05) and the object's own
// ObjectAsset::contactSpreadFraction (a fragment inherits its parent's as a length), of its
// bounding-box diagonal D; and the
// longest surface edge h at the contact face's corners, so that the load reaches at least the
// nearest ring of nodes. Why: a mesh of edge h cannot represent stresses that vary over less than
// about h. A load on fewer nodes does not make the answer more exact: it makes the stresses next
// to it a property of the mesh (a nodal point load's field grows as 1/h² under refinement, and
// more so on P2 corner nodes, which a uniform pressure does not load at all). A spread that
// follows the mesh alone (s = 0) still moves with it: ρ shrinks as the mesh is refined, and the
// stress under the load grows as 1/ρ². With s·D above the ring, ρ is a property of the object,
// and refining the mesh converges to the stress of a patch of radius ρ. The spread keeps the
// resultant and its point of action, so by Saint-Venant the stress beyond a few ρ is that of
// the true patch; nearer, the runtime resolves the stress at the length ρ, and what is finer
// (Hertz's edge tension of a small patch, cone cracks) is not modelled. Where the patch is larger
// (a ≥ s·D, a ≥ h) the load is Hertz's own.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <utility>
#include <vector>

#include "Body.h"
#include "brittle/core/TriangleGeometry.h"

namespace brittle::detail {

struct ContactSite {
  Eigen::Index face = -1;                         ///< boundary triangle (row of topology.boundaryTriangles)
  Eigen::Vector3d bary = Eigen::Vector3d::Zero(); ///< barycentric weights of the closest point on it
  int32_t nearestNode = -1;                       ///< the face's corner nearest to the point
  double distanceM = 0.0;                         ///< from the reported point to the surface
};

/// The closest point of triangle abc to p (brittle/core/TriangleGeometry.h).
using brittle::closestOnTriangle;

/// The closest boundary point to `pointLocal` (body frame, m). Errors: InvalidArgument when it is
/// farther than `toleranceM` or the body has no boundary.
Result<ContactSite> locateContact(const Body& body, const Eigen::Vector3d& pointLocal, double toleranceM);

/// The local radius of curvature (m) at the site's nearest node; +∞ where flat or concave.
double surfaceRadiusAt(const Body& body, const ContactSite& site);

/// The ring reach of the spread: ρ ≥ kContactRingReach · h.
inline constexpr double kContactRingReach = 1.0;

/// ρ = max(a, spreadFraction · D, kContactRingReach · h), the radius the contact load is spread
/// over (m).
double contactLoadRadius(const Body& body, const ContactSite& site, double patchRadiusM, double spreadFraction);

/// Node weights of the contact load spread over radius `rho` on the boundary faces that face the
/// impactor (outward normal · normalLocal > 0) (summing to 1; FEM node ids, so
/// mid-edge nodes N + edge for P2; P2 corner weights may be negative) into `weights`, in node
/// order, which keeps its storage. `faces` is scratch for the faces the disc may reach, which
/// keeps its storage too (the impact's workspace: no allocation once it has grown).
void contactLoadWeights(const Body& body, const ContactSite& site, const Eigen::Vector3d& normalLocal, double rho,
                        std::vector<std::pair<int32_t, double>>& weights, std::vector<int32_t>& faces);

}  // namespace brittle::detail
