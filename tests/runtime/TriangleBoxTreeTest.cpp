// The box tree over a body's boundary faces (runtime/src/TriangleBoxTree.h): its two searches give
// what the scans over every face gave, bit for bit, on a mesh full of exact ties (a structured
// box, points on its lattice) and on a curved one, offset far from the origin.
#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <vector>

#include "ContactGeometry.h"
#include "TriangleBoxTree.h"
#include "brittle/core/Random.h"
#include "brittle/runtime/TetTopology.h"
#include "brittle/testing/Fixtures.h"

namespace brittle {
namespace {

struct Faces {
  Points nodes;
  Triangles tri;
};

Faces boundaryOf(const TetMesh& mesh) {
  auto topology = buildTetTopology(mesh);
  EXPECT_TRUE(topology) << topology.error().message;
  if (!topology) return {mesh.nodes, Triangles(0, 3)};  // the callers' face-count checks then fail
  return {mesh.nodes, topology.value().boundaryTriangles};
}

double faceDistance2(const Faces& m, Eigen::Index f, const Eigen::Vector3d& p) {
  Eigen::Vector3d bary;
  return (detail::closestOnTriangle(p, m.nodes.row(m.tri(f, 0)), m.nodes.row(m.tri(f, 1)), m.nodes.row(m.tri(f, 2)), bary) - p)
      .squaredNorm();
}

// The scans the tree replaces (ContactGeometry.cpp before it): every face in row order.
Eigen::Index scanNearest(const Faces& m, const Eigen::Vector3d& p, double& best) {
  best = std::numeric_limits<double>::infinity();
  Eigen::Index found = -1;
  for (Eigen::Index f = 0; f < m.tri.rows(); ++f) {
    const double d = faceDistance2(m, f, p);
    if (d < best) best = d, found = f;
  }
  return found;
}

// Checks both searches at p; returns how many faces the scan found within r.
int checkAt(const Faces& m, const detail::TriangleBoxTree& tree, const Eigen::Vector3d& p, double r) {
  double scanned = 0.0, searched = 0.0;
  const Eigen::Index expected = scanNearest(m, p, scanned);
  const Eigen::Index got = tree.nearest(p, [&](int32_t f) { return faceDistance2(m, f, p); }, searched);
  EXPECT_EQ(got, expected) << "at " << p.transpose();
  EXPECT_EQ(searched, scanned);  // the same face's own arithmetic: the same bits
  std::vector<int32_t> rows;
  tree.within(p, r, rows);
  EXPECT_TRUE(std::is_sorted(rows.begin(), rows.end()));
  EXPECT_EQ(std::adjacent_find(rows.begin(), rows.end()), rows.end()) << "a face listed twice";
  int inside = 0;
  for (Eigen::Index f = 0; f < m.tri.rows(); ++f) {
    if (faceDistance2(m, f, p) >= r * r) continue;  // the load's own test
    ++inside;
    EXPECT_TRUE(std::binary_search(rows.begin(), rows.end(), static_cast<int32_t>(f))) << "face " << f << " left out";
  }
  return inside;
}

TEST(TriangleBoxTree, FindsTheScansFaceOnALatticeOfTies) {
  // A structured box: every lattice point is a corner of up to 12 boundary faces at distance
  // exactly 0, and points off the lattice sit at equal distances from faces sharing an edge. The
  // scan keeps the lowest such row; the tree must too.
  const Faces m = boundaryOf(testing::makeBoxTetMesh(0.3, 0.2, 0.1, 6, 4, 2));
  const auto tree = detail::TriangleBoxTree::build(m.nodes, m.tri);
  ASSERT_FALSE(tree.empty());
  int reached = 0;
  for (int i = -1; i <= 7; ++i) {
    for (int j = -1; j <= 5; ++j) {
      for (int k = -1; k <= 3; ++k) {
        reached += checkAt(m, tree, Eigen::Vector3d(0.05 * i, 0.05 * j, 0.05 * k), 0.06);
        reached += checkAt(m, tree, Eigen::Vector3d(0.05 * i + 0.025, 0.05 * j, 0.05 * k + 0.0125), 0.03);
      }
    }
  }
  EXPECT_GT(reached, 1000);  // the radius searches were not all empty
}

TEST(TriangleBoxTree, FindsTheScansFaceOnACurvedMeshFarFromTheOrigin) {
  // A tet mesh whose boundary is a sphere's (a 3-level icosphere's nodes, joined to a centre),
  // moved 1 km away: a margin relative to the coordinates must still cover rounding.
  const TriangleMesh sphere = testing::makeIcosphere(0.1, 3);
  TetMesh mesh;
  mesh.nodes.resize(sphere.vertices.rows() + 1, 3);
  mesh.nodes.topRows(sphere.vertices.rows()) = sphere.vertices;
  mesh.nodes.row(sphere.vertices.rows()).setZero();
  mesh.tets.resize(sphere.faces.rows(), 4);
  const auto centre = static_cast<int32_t>(sphere.vertices.rows());
  for (Eigen::Index f = 0; f < sphere.faces.rows(); ++f) {
    mesh.tets.row(f) << centre, sphere.faces(f, 0), sphere.faces(f, 1), sphere.faces(f, 2);  // positive: outward faces
  }
  mesh.nodes.rowwise() += Eigen::RowVector3d(1000.0, -400.0, 20.0);
  const Faces m = boundaryOf(mesh);
  ASSERT_EQ(m.tri.rows(), sphere.faces.rows());
  const auto tree = detail::TriangleBoxTree::build(m.nodes, m.tri);
  SplitMix64 random(7);
  const Eigen::Vector3d offset(1000.0, -400.0, 20.0);
  for (int s = 0; s < 400; ++s) {
    Eigen::Vector3d u;
    for (int a = 0; a < 3; ++a) u[a] = 2.0 * unitInterval(random.next()) - 1.0;
    // Inside, near the surface and outside, up to twice the radius.
    checkAt(m, tree, offset + 0.2 * u, 0.01 + 0.05 * unitInterval(random.next()));
  }
  // On the surface's own corners: distance 0 from every face around them.
  for (Eigen::Index v = 0; v < sphere.vertices.rows(); v += 7) checkAt(m, tree, m.nodes.row(v).transpose(), 0.02);
}

TEST(TriangleBoxTree, NoFacesFindNothing) {
  const auto tree = detail::TriangleBoxTree::build(Points(0, 3), Triangles(0, 3));
  EXPECT_TRUE(tree.empty());
  double best = 0.0;
  EXPECT_EQ(tree.nearest(Eigen::Vector3d::Zero(), [](int32_t) { return 0.0; }, best), -1);
  std::vector<int32_t> rows{1, 2};
  tree.within(Eigen::Vector3d::Zero(), 1.0, rows);
  EXPECT_TRUE(rows.empty());
}

}  // namespace
}  // namespace brittle
