#include "brittle/precompute/MeshRepair.h"

#include <gtest/gtest.h>

#include <numbers>

#include "brittle/descriptors/MassProperties.h"
#include "brittle/precompute/MeshValidation.h"
#include "brittle/testing/Fixtures.h"

namespace brittle {
namespace {

TEST(MeshRepair, InwardSphereComesBackOutwardWithItsVolume) {
  auto sphere = testing::makeIcosphere(0.1, 4);
  sphere.faces.col(1).swap(sphere.faces.col(2));
  ASSERT_EQ(validateSurfaceMesh(sphere).error().code, ErrorCode::InwardFacing);
  RepairReport report;
  auto repaired = repairSurfaceMesh(sphere, {}, &report);
  ASSERT_TRUE(repaired.ok()) << repaired.error().message;
  EXPECT_TRUE(validateSurfaceMesh(repaired.value()).ok());
  EXPECT_NEAR(report.relativeVolumeChange, 0.0, 0.02);
  EXPECT_NEAR(report.voxelSizeM, 0.2 / 128, 1e-6);
  EXPECT_EQ(report.inputFaces, sphere.faces.rows());
  EXPECT_EQ(report.outputFaces, repaired.value().faces.rows());
}

TEST(MeshRepair, OverlappingShellsBecomeTheirUnion) {
  // Two interpenetrating spheres: self-intersecting and two components, repaired to one solid.
  const double r = 0.1, d = 0.1;
  const auto a = testing::makeIcosphere(r, 4);
  TriangleMesh both;
  both.vertices.resize(2 * a.vertices.rows(), 3);
  both.vertices << a.vertices, (a.vertices.rowwise() + Eigen::RowVector3d(d, 0, 0));
  both.faces.resize(2 * a.faces.rows(), 3);
  both.faces << a.faces, (a.faces.array() + static_cast<int32_t>(a.vertices.rows())).matrix();
  ASSERT_FALSE(validateSurfaceMesh(both).ok());
  RepairSettings settings;
  settings.voxelSizeM = 0.002;
  auto repaired = repairSurfaceMesh(both, settings);
  ASSERT_TRUE(repaired.ok()) << repaired.error().message;
  EXPECT_TRUE(validateSurfaceMesh(repaired.value()).ok());
  // Union of two spheres at distance d: 2V − lens, lens = π(4r + d)(2r − d)²/12.
  const double sphereV = 4.0 / 3.0 * std::numbers::pi * r * r * r;
  const double lens = std::numbers::pi * (4 * r + d) * (2 * r - d) * (2 * r - d) / 12.0;
  EXPECT_NEAR(computeSurfaceMassProperties(repaired.value(), 1.0).volumeM3 / (2 * sphereV - lens), 1.0, 0.03);
}

TEST(MeshRepair, TypedErrors) {
  EXPECT_EQ(repairSurfaceMesh(TriangleMesh{}, {}).error().code, ErrorCode::EmptyMesh);
  auto box = testing::makeBoxSurface(1, 1, 1);
  box.vertices(0, 0) = std::numeric_limits<double>::infinity();
  EXPECT_EQ(repairSurfaceMesh(box, {}).error().code, ErrorCode::NonFiniteValue);
}

}  // namespace
}  // namespace brittle
