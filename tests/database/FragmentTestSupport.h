// FragmentTestSupport.h — random similarity transforms for the matcher and scaling-law tests
// (small databases: DatabaseFixtures.h).
#pragma once

#include <Eigen/Geometry>
#include <random>

#include "brittle/testing/DatabaseFixtures.h"

namespace brittle::testing {

/// A uniformly random rotation (det +1) from a seeded generator.
inline Eigen::Matrix3d randomRotation(std::mt19937_64& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::Vector4d g;
  for (int c = 0; c < 4; ++c) g[c] = n(rng);  // one draw per statement: fixed order
  return Eigen::Quaterniond(g[0], g[1], g[2], g[3]).normalized().toRotationMatrix();
}

/// x' = scale · R x + t for every vertex.
inline TriangleMesh transformed(const TriangleMesh& m, const Eigen::Matrix3d& r, double scale, const Eigen::Vector3d& t) {
  TriangleMesh out = m;
  out.vertices = ((m.vertices * r.transpose()) * scale).rowwise() + t.transpose();
  return out;
}

}  // namespace brittle::testing
