// DebrisHulls.cpp — convex hulls of fragment surfaces: extreme vertices in fixed directions, capped
// by Bullet's HullLibrary, or the exact hull.
#include "DebrisHulls.h"

#include <LinearMath/btConvexHull.h>
#include <LinearMath/btConvexHullComputer.h>
#include <oneapi/tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "BulletBody.h"

namespace brittle::play {

Hull convexHull(const TriangleMesh& surface, const MassProperties& mass, int maxVertices) {
  Hull h;
  principalAxes(mass.inertiaKgM2, h.axes, h.moments);
  btAlignedObjectArray<btVector3> all;
  all.reserve(static_cast<int>(surface.vertices.rows()));
  for (Eigen::Index v = 0; v < surface.vertices.rows(); ++v) {
    const Eigen::Vector3d x = h.axes.transpose() * (surface.vertices.row(v).transpose() - mass.centerOfMassM);
    h.sizeM = std::max(h.sizeM, x.norm());
    all.push_back(bt(x));
  }
  if (maxVertices > 0) {
    // Candidates: the surface's extreme vertex in each of 4·maxVertices fixed directions of its
    // principal frame (a spherical Fibonacci lattice; ties: the lowest vertex), a pass over the
    // vertices per direction instead of the exact hull of a dense surface. Then at most
    // maxVertices of them, farthest point first (Bullet's HullLibrary, quadratic in its input,
    // hence the candidates): hull vertices all, so the shape lies inside the exact hull.
    const int directions = 4 * maxVertices;
    std::vector<int> chosen;
    chosen.reserve(static_cast<size_t>(directions));
    const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
    for (int k = 0; k < directions; ++k) {
      const double z = 1.0 - (2.0 * k + 1.0) / directions, r = std::sqrt(std::max(0.0, 1.0 - z * z));
      const btVector3 dir(static_cast<btScalar>(r * std::cos(golden * k)), static_cast<btScalar>(r * std::sin(golden * k)),
                          static_cast<btScalar>(z));
      int best = 0;
      btScalar bestDot = all[0].dot(dir);
      for (int v = 1; v < all.size(); ++v) {
        const btScalar d = all[v].dot(dir);
        if (d > bestDot) best = v, bestDot = d;
      }
      if (std::find(chosen.begin(), chosen.end(), best) == chosen.end()) chosen.push_back(best);
    }
    std::sort(chosen.begin(), chosen.end());
    btAlignedObjectArray<btVector3> candidates;
    for (int v : chosen) candidates.push_back(all[v]);
    if (candidates.size() >= 4 && candidates.size() <= maxVertices) {
      h.points = candidates;
      return h;
    }
    if (candidates.size() > maxVertices) {
      HullDesc desc(QF_DEFAULT, static_cast<unsigned>(candidates.size()), &candidates[0]);
      desc.mMaxVertices = static_cast<unsigned>(maxVertices);
      HullLibrary library;
      HullResult result;
      const bool capped = library.CreateConvexHull(desc, result) == QE_OK && result.mNumOutputVertices >= 4;
      if (capped) {
        for (unsigned i = 0; i < result.mNumOutputVertices; ++i) h.points.push_back(result.m_OutputVertices[static_cast<int>(i)]);
      }
      library.ReleaseResult(result);
      if (capped) return h;
    }
    // Fewer than four distinct extremes (a sliver), or a degenerate set: the exact hull below.
  }
  btConvexHullComputer conv;
  conv.compute(&all[0].getX(), sizeof(btVector3), all.size(), 0.f, 0.f);
  for (int i = 0; i < conv.vertices.size(); ++i) h.points.push_back(conv.vertices[i]);
  return h;
}

void buildHulls(const ImpactResult& r, int maxVertices, std::vector<Hull>& hulls) {
  hulls.resize(r.fragments.size());
  tbb::parallel_for(size_t{0}, hulls.size(), [&](size_t i) {
    hulls[i] = convexHull(r.fragments[i].surface, r.fragments[i].massProperties, maxVertices);
  });
}

}  // namespace brittle::play
