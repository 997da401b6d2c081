// DebrisHulls.h — the convex hulls the player collides fragments and debris with, built on the
// runtime's workers as part of an impact and handed over by ticket. Private to the player.
#pragma once

#include <LinearMath/btAlignedObjectArray.h>
#include <LinearMath/btVector3.h>

#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <mutex>
#include <vector>

#include "brittle/runtime/World.h"

namespace brittle::play {

// A body's Bullet shape, computed apart from Bullet's world so that the fragments of a break can
// be done in parallel: principal axes and moments, and the convex hull of the surface in them
// (what btConvexHullShape::optimizeConvexHull keeps, computed the same way; the shape's box is
// then that of the hull's vertices).
struct Hull {
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();
  Eigen::Vector3d moments = Eigen::Vector3d::Zero();
  btAlignedObjectArray<btVector3> points;
  double sizeM = 0.0;  ///< largest distance of a surface point from the centre of mass
};

/// The hull of `surface` in its principal frame, at most maxVertices vertices (0: the exact hull).
Hull convexHull(const TriangleMesh& surface, const MassProperties& mass, int maxVertices);

// The fragments' hulls, in parallel.
void buildHulls(const ImpactResult& r, int maxVertices, std::vector<Hull>& hulls);

// Hulls of submitted impacts' fragments, built on the World's workers as part of each impact's
// work (WorldSettings::onImpactComputed), by ticket until the impact is collected. A hull depends
// on the fragment alone, so where it is built changes nothing.
struct HullStore {
  std::mutex mutex;
  std::map<uint64_t, std::vector<Hull>> byTicket;

  void put(ImpactTicket t, std::vector<Hull> hulls) {
    std::lock_guard<std::mutex> lock(mutex);
    byTicket[t.id] = std::move(hulls);
  }
  bool take(ImpactTicket t, std::vector<Hull>& hulls) {
    std::lock_guard<std::mutex> lock(mutex);
    const auto it = byTicket.find(t.id);
    if (it == byTicket.end()) return false;
    hulls = std::move(it->second);
    byTicket.erase(it);
    return true;
  }
};

}  // namespace brittle::play
