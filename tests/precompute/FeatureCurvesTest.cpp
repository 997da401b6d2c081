#include "brittle/precompute/FeatureCurves.h"

#include <gtest/gtest.h>

#include <set>

#include "brittle/testing/Fixtures.h"

namespace brittle {
namespace {

TEST(FeatureCurves, BoxEdgesAreOneGroupOfTwelveCurvesBetweenItsCorners) {
  const auto box = testing::makeBoxSurface(0.2, 0.1, 0.05);  // creases add up to 4 × 0.35 = 1.4 m
  auto curves = detectFeatureCurves(box, {60.0, 1.3, 30.0});
  EXPECT_EQ(curves.creaseEdges, 12);  // the face diagonals are flat
  EXPECT_EQ(curves.keptEdges, 12);
  EXPECT_EQ(curves.groups, 1);
  EXPECT_EQ(curves.keptGroups, 1);
  EXPECT_FALSE(curves.droppedAny());
  // Every corner has three creases, so each edge is its own curve from corner to corner.
  ASSERT_EQ(curves.polylines.size(), 12u);
  std::set<std::array<double, 3>> ends;
  for (const auto& line : curves.polylines) {
    ASSERT_EQ(line.size(), 2u);
    for (const auto& p : line) ends.insert({p.x(), p.y(), p.z()});
    const double length = (line[1] - line[0]).norm();
    EXPECT_TRUE(length == 0.2 || length == 0.1 || length == 0.05) << length;
  }
  EXPECT_EQ(ends.size(), 8u);

  // The same box seen as too small for its cell size: the group is shorter than the minimum.
  curves = detectFeatureCurves(box, {60.0, 1.5, 30.0});
  EXPECT_EQ(curves.creaseEdges, 12);
  EXPECT_EQ(curves.keptEdges, 0);
  EXPECT_EQ(curves.shortGroups, 1);
  EXPECT_TRUE(curves.droppedAny());
  EXPECT_TRUE(curves.polylines.empty());
}

TEST(FeatureCurves, SmoothSurfaceHasNoCreases) {
  const auto curves = detectFeatureCurves(testing::makeIcosphere(0.1, 3), {60.0, 0.0, 30.0});
  EXPECT_EQ(curves.creaseEdges, 0);
  EXPECT_FALSE(curves.droppedAny());
  EXPECT_TRUE(curves.polylines.empty());
}

TEST(FeatureCurves, AGroupWithANeedleTurnIsDropped) {
  // A tall thin tetrahedron: every edge is a crease, and the three edges at the apex meet at
  // about 5°: curves do not turn back on themselves like that, noise does.
  TriangleMesh needle;
  needle.vertices.resize(4, 3);
  needle.vertices << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0.1, 0.1, 10;
  needle.faces.resize(4, 3);
  needle.faces << 0, 2, 1, 0, 1, 3, 1, 2, 3, 2, 0, 3;
  auto curves = detectFeatureCurves(needle, {60.0, 0.0, 15.0});
  EXPECT_EQ(curves.creaseEdges, 6);
  EXPECT_EQ(curves.groups, 1);
  EXPECT_EQ(curves.needleGroups, 1);
  EXPECT_EQ(curves.keptEdges, 0);
  EXPECT_TRUE(curves.polylines.empty());
  // With the needle test off the group is kept; each vertex has three creases, so each edge is
  // a curve of its own.
  curves = detectFeatureCurves(needle, {60.0, 0.0, 0.0});
  EXPECT_EQ(curves.needleGroups, 0);
  EXPECT_EQ(curves.keptEdges, 6);
  EXPECT_EQ(curves.polylines.size(), 6u);
}

}  // namespace
}  // namespace brittle
