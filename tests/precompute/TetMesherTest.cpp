#include "brittle/precompute/TetMesher.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <set>

#include "brittle/descriptors/MassProperties.h"
#include "brittle/precompute/TetMeshQuality.h"
#include "brittle/testing/Fixtures.h"

namespace brittle {
namespace {

TEST(TetMesher, BoxKeepsItsExactVolumeAndHitsTheTarget) {
  const auto box = testing::makeBoxSurface(0.2, 0.1, 0.05);
  TetMeshSettings s;
  s.targetTets = 3000;
  auto r = tetrahedralize(box, s);
  ASSERT_TRUE(r.ok()) << r.error().message;
  const auto& m = r.value();
  EXPECT_NEAR(static_cast<double>(m.mesh.tets.rows()) / 3000.0, 1.0, s.countTolerance + 1e-9);
  const auto mp = computeTetMassProperties(m.mesh, 1.0);
  EXPECT_NEAR(mp.volumeM3, 0.2 * 0.1 * 0.05, 1e-12);  // sharp features are kept
  EXPECT_TRUE(mp.centerOfMassM.isApprox(Eigen::Vector3d(0.1, 0.05, 0.025), 1e-9));
  // Quality: perturbation + exudation lift every dihedral angle to about the sliver bound
  // (without them this box has angles below 1°).
  EXPECT_GT(m.quality.minDihedralDeg, 0.9 * s.sliverBoundDeg);
  EXPECT_LT(m.quality.maxDihedralDeg, 175.0);
  EXPECT_GT(m.quality.minTetVolumeM3, 0.0);
  EXPECT_EQ(m.quality.tetCount, m.mesh.tets.rows());
  EXPECT_EQ(m.quality.nodeCount, m.mesh.nodes.rows());
  // Its edges are real features, all protected; the first run passes its checks.
  EXPECT_TRUE(m.sharpFeatures);
  EXPECT_EQ(m.meshingRuns, 1);
  EXPECT_TRUE(m.adjustments.empty());
}

TEST(TetMesher, AStretchedTiltedPlateIsTakenBackOntoItsOwnFaces) {
  // A 0.2 × 0.16 × 0.02 m box, turned off every axis and moved: stretched 2.5 times across its
  // thickness for meshing, its nodes must come back inside the box, its surface nodes onto the box's
  // faces, its volume whole and its tets positive; and its tets are wider than thick.
  const Eigen::Vector3d size(0.2, 0.16, 0.02);
  const Eigen::Matrix3d rotation = Eigen::AngleAxisd(0.6, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  const Eigen::Vector3d shift(0.3, -0.2, 0.1);
  TriangleMesh box = testing::makeBoxSurface(size.x(), size.y(), size.z());
  for (Eigen::Index i = 0; i < box.vertices.rows(); ++i) {
    box.vertices.row(i) = (rotation * (box.vertices.row(i).transpose() - size / 2) + shift).transpose();
  }
  TetMeshSettings s;
  s.targetTets = 1500;
  auto regular = tetrahedralize(box, s);
  s.thinStretch = 2.5;
  auto stretched = tetrahedralize(box, s);
  ASSERT_TRUE(regular.ok()) << regular.error().message;
  ASSERT_TRUE(stretched.ok()) << stretched.error().message;
  const TetMesh& m = stretched.value().mesh;
  EXPECT_NEAR(computeTetMassProperties(m, 1.0).volumeM3, size.prod(), 1e-9 * size.prod());
  EXPECT_GT(stretched.value().quality.minTetVolumeM3, 0.0);
  // In the box's own frame: every node inside, every surface node on a face.
  auto local = [&](Eigen::Index node) -> Eigen::Vector3d {
    return rotation.transpose() * (m.nodes.row(node).transpose() - shift);
  };
  for (Eigen::Index i = 0; i < m.nodes.rows(); ++i) {
    EXPECT_TRUE((local(i).cwiseAbs() - size / 2).maxCoeff() < 1e-12) << "node " << i;
  }
  const Triangles& faces = stretched.value().surfaceFaces;
  for (Eigen::Index i = 0; i < faces.size(); ++i) {
    const Eigen::Vector3d q = local(faces.data()[i]);
    EXPECT_LT((q.cwiseAbs() - size / 2).cwiseAbs().minCoeff(), 1e-12) << "surface node " << faces.data()[i];
  }
  // Edge reach along the plate over reach across it, against the near-regular mesh: ~2.5 times.
  auto aspect = [&](const TetMesh& mesh) {
    const Eigen::Vector3d n = rotation.col(2);
    double along = 0.0, across = 0.0;
    for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
      for (int a = 0; a < 4; ++a) {
        for (int b = a + 1; b < 4; ++b) {
          const Eigen::Vector3d e = mesh.nodes.row(mesh.tets(t, a)) - mesh.nodes.row(mesh.tets(t, b));
          across += std::abs(e.dot(n));
          along += (e - e.dot(n) * n).norm();
        }
      }
    }
    return along / across;
  };
  const double ratio = aspect(m) / aspect(regular.value().mesh);
  std::printf("tilted plate: %lld tets stretched 2.5, %lld near-regular; edge aspect ratio %.2f times\n",
              static_cast<long long>(m.tets.rows()), static_cast<long long>(regular.value().mesh.tets.rows()), ratio);
  EXPECT_GT(ratio, 1.8);
}

TEST(TetMesher, AStretchNeedsAFlatPartAndARangeOfOneToSixteen) {
  TetMeshSettings s;
  s.targetTets = 500;
  s.thinStretch = 2.0;
  for (const auto& solid : {testing::makeBoxSurface(0.1, 0.1, 0.1), testing::makeBoxSurface(0.3, 0.05, 0.05),
                            testing::makeIcosphere(0.1, 2)}) {
    auto r = tetrahedralize(solid, s);  // no one thin axis: a cube, a square bar, a ball
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(r.error().code, ErrorCode::InvalidArgument);
  }
  for (const double bad : {0.5, 17.0, std::nan("")}) {
    s.thinStretch = bad;
    auto r = tetrahedralize(testing::makeBoxSurface(0.2, 0.2, 0.01), s);
    ASSERT_FALSE(r.ok()) << bad;
    EXPECT_EQ(r.error().code, ErrorCode::InvalidArgument);
  }
}

TEST(TetMesher, BoundaryIsClosedOutwardAndBoundsTheTets) {
  TetMeshSettings s;
  s.targetTets = 2000;
  auto r = tetrahedralize(testing::makeIcosphere(0.1, 3), s);
  ASSERT_TRUE(r.ok()) << r.error().message;
  const TriangleMesh boundary{r.value().mesh.nodes, r.value().surfaceFaces};
  const auto fromSurface = computeSurfaceMassProperties(boundary, 1.0);
  const auto fromTets = computeTetMassProperties(r.value().mesh, 1.0);
  EXPECT_NEAR(fromSurface.volumeM3, fromTets.volumeM3, 1e-12 * fromTets.volumeM3 + 1e-18);
  EXPECT_GT(fromSurface.volumeM3, 0.0);
  // Euler characteristic of a sphere: V − E + F = 2, with E = 3F/2 on a closed triangle mesh.
  std::set<int32_t> used(boundary.faces.data(), boundary.faces.data() + boundary.faces.size());
  EXPECT_EQ(static_cast<int64_t>(used.size()) - boundary.faces.rows() * 3 / 2 + boundary.faces.rows(), 2);
}

TEST(TetMesher, SphereMassPropertiesMatchAnalyticAndSurfaceValues) {
  const double radius = 0.1, rho = 2500.0;
  const auto sphere = testing::makeIcosphere(radius, 4);
  TetMeshSettings s;
  s.targetTets = 5000;
  auto r = tetrahedralize(sphere, s);
  ASSERT_TRUE(r.ok()) << r.error().message;
  const auto tets = computeTetMassProperties(r.value().mesh, rho);
  const auto exact = computeSurfaceMassProperties(sphere, rho);
  // Mesh_3 re-samples the curved surface within facet_distance d of it, so the volume may move
  // by up to area · d: a relative tolerance of 3 d / r on a sphere.
  const double d = s.facetDistanceFraction * r.value().cellSizeM;
  const double tolerance = 3.0 * d / radius;
  std::printf("cell size %.4f m, facet distance %.5f m, volume error %.3f%% (bound %.3f%%)\n", r.value().cellSizeM, d,
              100.0 * (tets.volumeM3 / exact.volumeM3 - 1.0), 100.0 * tolerance);
  EXPECT_NEAR(tets.volumeM3 / exact.volumeM3, 1.0, tolerance);
  EXPECT_NEAR(tets.massKg / exact.massKg, 1.0, tolerance);
  EXPECT_LT(tets.centerOfMassM.norm(), 1e-3 * radius);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(tets.inertiaKgM2(k, k) / exact.inertiaKgM2(k, k), 1.0, 5.0 * d / radius);
  // Against the smooth sphere, add the icosphere's own faceting error (level 4: 0.3%).
  const double analyticMass = rho * 4.0 / 3.0 * std::numbers::pi * std::pow(radius, 3);
  EXPECT_NEAR(tets.massKg / analyticMass, 1.0, tolerance + 0.004);
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(tets.inertiaKgM2(k, k) / (0.4 * analyticMass * radius * radius), 1.0, 5.0 * d / radius + 0.007);
  }
}

TEST(TetMesher, SameSeedSameMesh) {
  TetMeshSettings s;
  s.targetTets = 1500;
  const auto surface = testing::makeIcosphere(0.1, 2);
  auto a = tetrahedralize(surface, s);
  auto b = tetrahedralize(surface, s);
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_EQ(a.value().mesh.tets, b.value().mesh.tets);
  EXPECT_EQ(a.value().mesh.nodes, b.value().mesh.nodes);
}

TEST(TetMesher, ARunPastItsTimeLimitIsAMeshingFailedAndALimitItMeetsChangesNothing) {
  TetMeshSettings s;
  s.targetTets = 1500;
  const auto surface = testing::makeIcosphere(0.1, 2);
  auto free = tetrahedralize(surface, s);
  s.runTimeLimitS = 600.0;
  auto limited = tetrahedralize(surface, s);
  ASSERT_TRUE(free.ok() && limited.ok());
  EXPECT_EQ(limited.value().mesh.tets, free.value().mesh.tets);
  EXPECT_EQ(limited.value().mesh.nodes, free.value().mesh.nodes);
  // A 20k-tet run (about a second of refinement here) cannot finish in 1 µs: the deadline stops
  // it, and the stopped complex is thrown away, not returned.
  s.targetTets = 20000;
  s.runTimeLimitS = 1e-6;
  auto stopped = tetrahedralize(surface, s);
  ASSERT_FALSE(stopped.ok());
  EXPECT_EQ(stopped.error().code, ErrorCode::MeshingFailed);
  EXPECT_NE(stopped.error().message.find("time limit"), std::string::npos) << stopped.error().message;
}

TEST(TetMesher, CellSizeDrivenAndErrors) {
  TetMeshSettings s;
  s.meshingRuns = 0;
  EXPECT_EQ(tetrahedralize(testing::makeBoxSurface(1, 1, 1), s).error().code, ErrorCode::InvalidArgument);
  s.meshingRuns = 4;
  s.targetTets = 0;
  EXPECT_EQ(tetrahedralize(testing::makeBoxSurface(1, 1, 1), s).error().code, ErrorCode::InvalidArgument);
  s.cellSizeM = 0.25;
  auto r = tetrahedralize(testing::makeBoxSurface(1, 1, 1), s);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r.value().attempts, 1);
  EXPECT_DOUBLE_EQ(r.value().cellSizeM, 0.25);
  s.cellSizeM = 0.125;
  auto finer = tetrahedralize(testing::makeBoxSurface(1, 1, 1), s);
  ASSERT_TRUE(finer.ok());
  EXPECT_GT(finer.value().mesh.tets.rows(), 4 * r.value().mesh.tets.rows());
}

TEST(TetMeshQuality, FaceConnectivityCountsPiecesJoinedOnlyAtAVertex) {
  const auto block = testing::makeBoxTetMesh(1, 1, 1, 2, 2, 2);
  EXPECT_EQ(countFaceConnectedComponents(block), 1);
  // A second block sharing one corner node with the first: one node set, two solids.
  TetMesh two;
  two.nodes.resize(2 * block.nodes.rows(), 3);
  two.nodes << block.nodes, (block.nodes.rowwise() + Eigen::RowVector3d(1, 1, 1));
  two.tets.resize(2 * block.tets.rows(), 4);
  Tetrahedra shifted = (block.tets.array() + static_cast<int32_t>(block.nodes.rows())).matrix();
  const int32_t farCorner = static_cast<int32_t>(block.nodes.rows()) - 1;  // (1,1,1) of the first block
  for (Eigen::Index i = 0; i < shifted.size(); ++i)
    if (shifted.data()[i] == static_cast<int32_t>(block.nodes.rows())) shifted.data()[i] = farCorner;
  two.tets << block.tets, shifted;
  EXPECT_EQ(countFaceConnectedComponents(compactNodes(two)), 2);
  // Labels: the first block's tets are group 0, the second's group 1.
  const auto labels = labelFaceConnectedComponents(compactNodes(two));
  ASSERT_EQ(labels.size(), static_cast<size_t>(two.tets.rows()));
  for (size_t t = 0; t < labels.size(); ++t) EXPECT_EQ(labels[t], t < static_cast<size_t>(block.tets.rows()) ? 0 : 1) << t;
}

TEST(TetMeshQuality, RegularTetValues) {
  TetMesh t;
  t.nodes.resize(4, 3);
  t.nodes << 1, 1, 1, 1, -1, -1, -1, 1, -1, -1, -1, 1;
  t.tets.resize(1, 4);
  t.tets << 0, 1, 2, 3;
  if (computeTetMassProperties(t, 1.0).volumeM3 < 0) t.tets << 0, 1, 3, 2;
  const auto q = computeMeshQuality(t);
  EXPECT_NEAR(q.minDihedralDeg, 70.528779, 1e-5);
  EXPECT_NEAR(q.maxDihedralDeg, 70.528779, 1e-5);
  EXPECT_NEAR(q.maxRadiusEdgeRatio, std::sqrt(6.0) / 4.0, 1e-12);
  EXPECT_EQ(q.surfaceFaceCount, 4);
}

}  // namespace
}  // namespace brittle
