#include "brittle/core/TriangleGeometry.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace brittle {
namespace {

// Each Voronoi region of a right triangle gives its known closest point and weights.
TEST(TriangleGeometry, ClosestPointInEachRegion) {
  const Eigen::Vector3d a(0, 0, 0), b(2, 0, 0), c(0, 2, 0);
  Eigen::Vector3d bary;
  EXPECT_EQ(closestOnTriangle({0.5, 0.5, 3}, a, b, c, bary), Eigen::Vector3d(0.5, 0.5, 0));  // face
  EXPECT_EQ(bary, Eigen::Vector3d(0.5, 0.25, 0.25));
  EXPECT_EQ(closestOnTriangle({-1, -1, 1}, a, b, c, bary), a);  // vertex a
  EXPECT_EQ(bary, Eigen::Vector3d(1, 0, 0));
  EXPECT_EQ(closestOnTriangle({1, -3, 0}, a, b, c, bary), Eigen::Vector3d(1, 0, 0));  // edge ab
  EXPECT_EQ(bary, Eigen::Vector3d(0.5, 0.5, 0));
  EXPECT_EQ(closestOnTriangle({2, 2, 0}, a, b, c, bary), Eigen::Vector3d(1, 1, 0));  // edge bc
  EXPECT_EQ(bary, Eigen::Vector3d(0, 0.5, 0.5));
}

// A triangle without area (corners on a line, two equal, or all one point) has no face region:
// from any point, the nearest point of its edges (the segments' own nearest, by brute force), with
// weights that sum to 1 and give that point, never a NaN.
TEST(TriangleGeometry, ClosestPointOfATriangleWithoutArea) {
  const auto toSegment = [](const Eigen::Vector3d& p, const Eigen::Vector3d& u, const Eigen::Vector3d& v) {
    double best = (p - u).norm();
    for (int i = 1; i <= 10000; ++i) best = std::min(best, (p - (u + (v - u) * (i / 10000.0))).norm());
    return best;
  };
  const Eigen::Vector3d triangles[][3] = {{{0, 0, 0}, {1, 0, 0}, {3, 0, 0}},
                                          {{0, 0, 0}, {3, 0, 0}, {1, 0, 0}},
                                          {{1, 2, 0}, {1, 2, 0}, {2, 2, 1}},
                                          {{1, 1, 1}, {1, 1, 1}, {1, 1, 1}}};
  int tried = 0;
  for (const auto& t : triangles) {
    for (double x = -1.0; x <= 4.0; x += 0.5) {
      for (double y = -1.0; y <= 3.0; y += 1.0) {
        const Eigen::Vector3d p(x, y, 0.5);
        Eigen::Vector3d bary;
        const Eigen::Vector3d q = closestOnTriangle(p, t[0], t[1], t[2], bary);
        ASSERT_TRUE(q.allFinite() && bary.allFinite()) << p.transpose();
        EXPECT_NEAR(bary.sum(), 1.0, 1e-12);
        EXPECT_LT((bary[0] * t[0] + bary[1] * t[1] + bary[2] * t[2] - q).norm(), 1e-12);
        const double want = std::min({toSegment(p, t[0], t[1]), toSegment(p, t[1], t[2]), toSegment(p, t[2], t[0])});
        EXPECT_NEAR((q - p).norm(), want, 1e-3) << p.transpose();
        ++tried;
      }
    }
  }
  EXPECT_EQ(tried, 4 * 11 * 5);
}

}  // namespace
}  // namespace brittle
