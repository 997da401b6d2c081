// BulletBody.h — a Bullet rigid body for a pack object, a fragment or an impactor, with the frames
// that map it to the runtime's object, and the conversions between Eigen and Bullet.
// Private to the player.
#pragma once

#include <btBulletDynamicsCommon.h>

#include <Eigen/Core>
#include <limits>
#include <memory>
#include <set>
#include <utility>

#include "brittle/player/Player.h"

namespace brittle::play {

constexpr double kInf = std::numeric_limits<double>::infinity();

inline btVector3 bt(const Eigen::Vector3d& v) { return btVector3(v.x(), v.y(), v.z()); }
inline Eigen::Vector3d eig(const btVector3& v) { return Eigen::Vector3d(v.x(), v.y(), v.z()); }
inline Eigen::Matrix3d eig(const btMatrix3x3& m) {
  Eigen::Matrix3d r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r(i, j) = m[i][j];
  return r;
}
inline btMatrix3x3 bt(const Eigen::Matrix3d& m) {
  return btMatrix3x3(m(0, 0), m(0, 1), m(0, 2), m(1, 0), m(1, 1), m(1, 2), m(2, 0), m(2, 1), m(2, 2));
}

// Principal axes: inertia = P diag(d) Pᵀ with P a rotation (det +1), d clamped away from zero so
// that slivers of debris stay integrable.
void principalAxes(const Eigen::Matrix3d& inertia, Eigen::Matrix3d& axes, Eigen::Vector3d& moments);

// The surface of an asset: its tet mesh's boundary, nodes renumbered compactly.
TriangleMesh assetSurface(const ObjectAsset& asset);

/// One body of the play: its report state, its Bullet body and shape, and its frames.
struct Body {
  BodyState state;
  ObjectId object;                 ///< valid: breakable
  Material material;
  std::unique_ptr<btCollisionShape> shape;
  std::unique_ptr<btRigidBody> rigid;
  bool alive = true;
  // Local (asset) frame relative to the Bullet body frame: x_local = comLocal + axes · x_body.
  Eigen::Vector3d comLocal = Eigen::Vector3d::Zero();
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();
  // The pose the runtime World holds for the object (it never moves there): impacts are mapped
  // from the body's local frame into that pose.
  Eigen::Matrix3d runtimeRotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d runtimeTranslation = Eigen::Vector3d::Zero();
  double sizeM = 0.0;              ///< largest distance of a surface point from the centre of mass
  double radiusForOthersM = kInf;  ///< what an impact on another body sees: sphere radius, else flat
  double cooldownUntilS = -kInf;
  bool fracturing = false;  ///< an impact on it is submitted and not applied yet
  Eigen::Vector3d preVelocity = Eigen::Vector3d::Zero(), preAngular = Eigen::Vector3d::Zero();

  double massKg() const { return state.massKg; }
  Eigen::Vector3d com() const { return eig(rigid->getCenterOfMassPosition()); }
  // Pose of the local frame in the world.
  void localPose(Eigen::Matrix3d& rotation, Eigen::Vector3d& translation) const {
    const btTransform& t = rigid->getCenterOfMassTransform();
    rotation = eig(t.getBasis()) * axes.transpose();
    translation = eig(t.getOrigin()) - rotation * comLocal;
  }
};

// Fragments born in the same step start interpenetrating (the convex hulls of concave fragments
// overlap, and two bodies that broke against each other left their fragments in contact). Bullet
// would push them apart with velocity, out of nothing. So a pair of such bodies whose boxes
// overlap at birth does not collide until their boxes have separated once.
struct SiblingFilter final : btOverlapFilterCallback {
  std::set<std::pair<int, int>> blocked;
  bool needBroadphaseCollision(btBroadphaseProxy* p0, btBroadphaseProxy* p1) const override {
    if ((p0->m_collisionFilterGroup & p1->m_collisionFilterMask) == 0 || (p1->m_collisionFilterGroup & p0->m_collisionFilterMask) == 0) {
      return false;
    }
    const int a = static_cast<const btCollisionObject*>(p0->m_clientObject)->getUserIndex();
    const int b = static_cast<const btCollisionObject*>(p1->m_clientObject)->getUserIndex();
    return a < 0 || b < 0 || !blocked.contains({std::min(a, b), std::max(a, b)});
  }
};

/// Whether the two bodies' boxes overlap.
bool aabbsOverlap(const btRigidBody& a, const btRigidBody& b);

}  // namespace brittle::play
