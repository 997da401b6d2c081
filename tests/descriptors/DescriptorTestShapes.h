// DescriptorTestShapes.h — extra closed meshes and transforms used by the descriptor tests
// (tests/common holds the shared box and icosphere; these are specific to descriptors/).
#pragma once

#include <Eigen/Geometry>
#include <cmath>
#include <map>
#include <numbers>
#include <random>
#include <utility>

#include "brittle/descriptors/MeshRefinement.h"
#include "brittle/core/MeshTypes.h"

namespace brittle::testing {

/// Closed, outward tetrahedron (p0, p1, p2, p3) in any orientation.
inline TriangleMesh makeTetrahedron(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1,
                                    const Eigen::Vector3d& p2, const Eigen::Vector3d& p3) {
  TriangleMesh m;
  m.vertices.resize(4, 3);
  m.vertices << p0.transpose(), p1.transpose(), p2.transpose(), p3.transpose();
  m.faces.resize(4, 3);
  m.faces << 0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3;
  if ((p1 - p0).dot((p2 - p0).cross(p3 - p0)) < 0) m.faces.col(1).swap(m.faces.col(2));
  return m;
}

/// Closed prism: the counter-clockwise polygon `section` (#P by 2, in x-y) extruded over z ∈ [z0, z1].
inline TriangleMesh makePrism(const Eigen::Matrix<double, Eigen::Dynamic, 2>& section, double z0, double z1) {
  const int n = static_cast<int>(section.rows());
  TriangleMesh m;
  m.vertices.resize(2 * n + 2, 3);
  for (int i = 0; i < n; ++i) {
    m.vertices.row(i) << section(i, 0), section(i, 1), z0;
    m.vertices.row(n + i) << section(i, 0), section(i, 1), z1;
  }
  const Eigen::RowVector2d c = section.colwise().mean();
  m.vertices.row(2 * n) << c[0], c[1], z0;
  m.vertices.row(2 * n + 1) << c[0], c[1], z1;
  m.faces.resize(4 * n, 3);
  for (int i = 0; i < n; ++i) {
    const int j = (i + 1) % n;
    m.faces.row(4 * i + 0) << i, j, n + j;
    m.faces.row(4 * i + 1) << i, n + j, n + i;
    m.faces.row(4 * i + 2) << 2 * n, j, i;
    m.faces.row(4 * i + 3) << 2 * n + 1, n + i, n + j;
  }
  return m;
}

/// Regular n-gon prism approximating a cylinder of radius r over z ∈ [0, h].
inline TriangleMesh makeCylinder(double r, double h, int n) {
  Eigen::Matrix<double, Eigen::Dynamic, 2> s(n, 2);
  for (int i = 0; i < n; ++i) {
    const double t = 2.0 * std::numbers::pi * i / n;
    s.row(i) << r * std::cos(t), r * std::sin(t);
  }
  return makePrism(s, 0.0, h);
}

/// A generic (asymmetric) closed polyhedron: an irregular hexahedron, 12 triangles, with distinct
/// principal moments and non-zero skewness along every axis.
inline TriangleMesh makeIrregularSolid() {
  TriangleMesh m;
  m.vertices.resize(8, 3);
  m.vertices << 0.0, 0.0, 0.0, 1.9, 0.1, -0.1, 0.2, 1.1, 0.1, 1.5, 1.3, 0.2,  //
      0.1, -0.2, 0.6, 1.2, 0.2, 0.9, -0.1, 0.8, 0.7, 0.9, 1.0, 0.5;
  m.faces.resize(12, 3);
  m.faces << 0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4, 2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3,
      5, 3, 7, 5;
  return m;
}

/// Similarity x ↦ s Q x + t.
struct Similarity {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  double scale = 1.0;
};

/// Uniformly random rotation, translation in [-10, 10]³ and scale in [0.1, 10], from a seed.
inline Similarity randomSimilarity(unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal;
  std::uniform_real_distribution<double> uniform(-10.0, 10.0), logScale(std::log(0.1), std::log(10.0));
  Similarity s;
  s.rotation = Eigen::Quaterniond(normal(rng), normal(rng), normal(rng), normal(rng)).normalized().toRotationMatrix();
  s.translation = Eigen::Vector3d(uniform(rng), uniform(rng), uniform(rng));
  s.scale = std::exp(logScale(rng));
  return s;
}

inline TriangleMesh transformed(const TriangleMesh& in, const Similarity& s) {
  TriangleMesh out = in;
  out.vertices = ((s.scale * in.vertices * s.rotation.transpose()).rowwise() + s.translation.transpose()).eval();
  return out;
}

}  // namespace brittle::testing
