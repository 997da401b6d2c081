// FragmentTestSupport.h — small databases and random similarity transforms for the fragment tests.
#pragma once

#include <Eigen/Geometry>
#include <random>

#include "brittle/precompute/FragmentDatabaseBake.h"
#include "brittle/testing/Fixtures.h"

namespace brittle::testing {

/// The base shapes the project ships (assets/shapes/base-shapes.json).
inline std::vector<BaseShapeDefinition> shippedBaseShapes() {
  auto shapes = loadBaseShapes(sourceDir() / "assets" / "shapes" / "base-shapes.json");
  return shapes ? shapes.value() : std::vector<BaseShapeDefinition>{};
}

/// Settings for a small, fast database: coarse tets and few modes.
inline DatabaseBakeSettings smallDatabaseSettings(int64_t entries, bool physics) {
  DatabaseBakeSettings s;
  s.shapes = shippedBaseShapes();
  s.entryCount = entries;
  s.seed = 7;
  s.physics = physics;
  s.tetMesh.targetTets = 400;
  s.modeCount = 6;
  s.descriptors.voxel.resolution = s.descriptors.voxelImproved.resolution = 12;
  return s;
}

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
