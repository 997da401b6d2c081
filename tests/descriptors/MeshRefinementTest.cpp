// Midpoint subdivision: the same closed, consistently oriented polyhedron with four times the faces.
#include "brittle/descriptors/MeshRefinement.h"

#include <gtest/gtest.h>

#include <map>
#include <utility>

#include "DescriptorTestShapes.h"
#include "brittle/descriptors/MassProperties.h"
#include "brittle/testing/Fixtures.h"

namespace brittle {
namespace {

// Every directed edge once, and its reverse once: closed and consistently oriented.
bool closedAndOriented(const TriangleMesh& m) {
  std::map<std::pair<int32_t, int32_t>, int> directed;
  for (Eigen::Index f = 0; f < m.faces.rows(); ++f) {
    for (int k = 0; k < 3; ++k) ++directed[{m.faces(f, k), m.faces(f, (k + 1) % 3)}];
  }
  for (const auto& [edge, count] : directed) {
    const auto back = directed.find({edge.second, edge.first});
    if (count != 1 || back == directed.end() || back->second != 1) return false;
  }
  return true;
}

TEST(MeshRefinement, SubdivisionKeepsTheSolidClosedAndCountsMatchEuler) {
  const TriangleMesh solid = testing::makeIrregularSolid();
  const TriangleMesh fine = subdivideMidpoints(solid);
  const Eigen::Index edges = 3 * solid.faces.rows() / 2;
  EXPECT_EQ(fine.faces.rows(), 4 * solid.faces.rows());
  EXPECT_EQ(fine.vertices.rows(), solid.vertices.rows() + edges);  // one midpoint per shared edge
  EXPECT_TRUE(closedAndOriented(fine));
  const auto a = computeSurfaceMassProperties(solid, 1.0), b = computeSurfaceMassProperties(fine, 1.0);
  EXPECT_NEAR(b.volumeM3, a.volumeM3, 1e-14 * a.volumeM3);
  EXPECT_LT((b.centerOfMassM - a.centerOfMassM).norm(), 1e-14);
  EXPECT_LT((b.secondMomentM5 - a.secondMomentM5).norm(), 1e-14 * a.secondMomentM5.norm());
  // The original vertices come first and are untouched.
  EXPECT_EQ(fine.vertices.topRows(solid.vertices.rows()), solid.vertices);
}

TEST(MeshRefinement, SubdivideToAtLeastStopsAtTheFirstLargeEnoughLevel) {
  const TriangleMesh box = testing::makeBoxSurface(1.0, 2.0, 3.0);  // 12 faces
  EXPECT_EQ(subdivideToAtLeast(box, 12).faces.rows(), 12);
  EXPECT_EQ(subdivideToAtLeast(box, 13).faces.rows(), 48);
  EXPECT_EQ(subdivideToAtLeast(box, 1000).faces.rows(), 3072);
  EXPECT_TRUE(closedAndOriented(subdivideToAtLeast(box, 1000)));
  EXPECT_EQ(subdivideToAtLeast(TriangleMesh{}, 100).faces.rows(), 0);  // nothing to split: no loop
}

}  // namespace
}  // namespace brittle
