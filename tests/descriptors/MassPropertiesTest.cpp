#include "brittle/descriptors/MassProperties.h"

#include <gtest/gtest.h>

#include <numbers>

#include "brittle/testing/Fixtures.h"

namespace brittle {
namespace {

TEST(MassProperties, BoxSurfaceMatchesAnalyticValues) {
  const double a = 2.0, b = 3.0, c = 0.5, rho = 1000.0;
  const auto mp = computeSurfaceMassProperties(testing::makeBoxSurface(a, b, c), rho);
  const double m = rho * a * b * c;
  EXPECT_NEAR(mp.volumeM3, a * b * c, 1e-12);
  EXPECT_NEAR(mp.massKg, m, 1e-9);
  EXPECT_TRUE(mp.centerOfMassM.isApprox(Eigen::Vector3d(a / 2, b / 2, c / 2), 1e-12));
  EXPECT_NEAR(mp.inertiaKgM2(0, 0), m * (b * b + c * c) / 12.0, 1e-9 * m);
  EXPECT_NEAR(mp.inertiaKgM2(1, 1), m * (a * a + c * c) / 12.0, 1e-9 * m);
  EXPECT_NEAR(mp.inertiaKgM2(2, 2), m * (a * a + b * b) / 12.0, 1e-9 * m);
  EXPECT_NEAR(mp.inertiaKgM2(0, 1), 0.0, 1e-9 * m);
  EXPECT_NEAR(mp.inertiaKgM2(1, 2), 0.0, 1e-9 * m);
}

TEST(MassProperties, InvertedSurfaceHasNegativeVolume) {
  auto box = testing::makeBoxSurface(1, 1, 1);
  box.faces.col(1).swap(box.faces.col(2));
  EXPECT_NEAR(computeSurfaceMassProperties(box, 1.0).volumeM3, -1.0, 1e-12);
}

TEST(MassProperties, FarFromOriginKeepsPrecision) {
  auto box = testing::makeBoxSurface(0.1, 0.2, 0.3);
  box.vertices.rowwise() += Eigen::RowVector3d(1e4, -2e4, 5e3);
  const auto mp = computeSurfaceMassProperties(box, 1.0);
  // Coordinates near 1e4 m carry ~1e-12 m of rounding; accumulating about the box centre keeps
  // the result at that level (about the world origin it would lose ~1e-6 relative).
  EXPECT_NEAR(mp.volumeM3, 0.006, 1e-10 * 0.006);
  EXPECT_NEAR(mp.secondMomentM5(0, 0), 0.006 * 0.01 / 12.0, 1e-9 * 0.006 * 0.01 / 12.0);
}

TEST(MassProperties, SphereConvergesToAnalyticValues) {
  const double r = 0.1, rho = 2500.0;
  double previousError = 1.0;
  for (int level = 2; level <= 5; ++level) {
    const auto mp = computeSurfaceMassProperties(testing::makeIcosphere(r, level), rho);
    const double v = 4.0 / 3.0 * std::numbers::pi * r * r * r;
    const double error = std::abs(mp.volumeM3 / v - 1.0);
    EXPECT_LT(error, previousError);
    previousError = error;
    if (level == 5) {
      EXPECT_LT(error, 2e-3);
      const double i = 0.4 * rho * v * r * r;
      for (int k = 0; k < 3; ++k) EXPECT_NEAR(mp.inertiaKgM2(k, k), i, 5e-3 * i);
      EXPECT_LT(mp.centerOfMassM.norm(), 1e-12);
    }
  }
}

TEST(MassProperties, TetMeshEqualsItsBoundary) {
  const auto tets = testing::makeBoxTetMesh(1.0, 0.5, 0.25, 4, 3, 2);
  const auto fromTets = computeTetMassProperties(tets, 7.0);
  const auto fromSurface = computeSurfaceMassProperties(testing::makeBoxSurface(1.0, 0.5, 0.25), 7.0);
  EXPECT_NEAR(fromTets.volumeM3, fromSurface.volumeM3, 1e-14);
  EXPECT_TRUE(fromTets.centerOfMassM.isApprox(fromSurface.centerOfMassM, 1e-12));
  EXPECT_TRUE(fromTets.inertiaKgM2.isApprox(fromSurface.inertiaKgM2, 1e-12));
}

}  // namespace
}  // namespace brittle
