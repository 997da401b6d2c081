// The contact load (runtime/src/ContactGeometry.h): Hertz's pressure spread over a disc of radius
// ρ = max(a, 0.05 × the body's diagonal, the nearest ring), as consistent nodal loads. Its
// resultant and point of action, its convergence under mesh refinement, and its typed error.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "brittle/runtime/FemAssembly.h"
#include "brittle/runtime/World.h"
#include "brittle/testing/BakeFixtures.h"

namespace brittle {
namespace {

ImpactDesc ballOnPlate(ObjectId id, const Eigen::Vector3d& point, double speed) {
  ImpactDesc d;
  d.object = id;
  d.pointWorld = point;
  d.normalWorld = Eigen::Vector3d::UnitZ();
  d.speedMps = speed;
  d.impactorMassKg = 0.1;
  d.impactorRadiusM = 0.02;
  return d;
}

double diagonal(const TetMesh& mesh) {
  return (mesh.nodes.colwise().maxCoeff() - mesh.nodes.colwise().minCoeff()).norm();
}

TEST(ContactLoad, SpreadPressureKeepsItsResultantAndItsPointOfAction) {
  // A ball near the middle of a plate's top face (z = 0.01): the disc lies on that flat face, so
  // the load's point of action is the contact point, and every loaded node is on that face, on a
  // face the disc reaches.
  for (const ElementOrder order : {ElementOrder::P1, ElementOrder::P2}) {
    SCOPED_TRACE(elementOrderName(order));
    const Pack pack = testing::makeGlassPlatePack(1500, 6, 0.3, order).value();
    const TetMesh& mesh = pack.objects[0].tetMesh;
    const Points nodes = makeFemMesh(mesh, order).value().nodes();
    const double top = nodes.col(2).maxCoeff();
    const Eigen::Vector3d point(0.15, 0.13, top);
    double ringOnly = 0.0;
    for (const double spread : {0.05, 0.0}) {
      WorldSettings s;
      s.fracture.contactSpreadFraction = spread;
      s.fracture.staticCorrection = false;  // only the load is looked at: no factorisation
      World world = World::create(Pack(pack), s).value();
      auto r = world.impact(ballOnPlate(world.addObject({.asset = "plate"}).value(), point, 1.0));
      ASSERT_TRUE(r) << r.error().message;
      const ImpactResult& res = r.value();
      const double rho = res.loadRadiusM;
      EXPECT_GE(rho, spread * diagonal(mesh) - 1e-15);
      EXPECT_GE(rho, res.contact.patchRadiusM);
      double sum = 0.0;
      Eigen::Vector3d action = Eigen::Vector3d::Zero();
      bool midEdge = false;
      for (const auto& [node, w] : res.loadWeights) {
        ASSERT_GE(node, 0);
        ASSERT_LT(node, nodes.rows());
        sum += w;
        action += w * nodes.row(node).transpose();
        EXPECT_NEAR(nodes(node, 2), top, 1e-12);                          // on the top face
        EXPECT_LT((nodes.row(node).transpose() - point).norm(), 3.0 * rho);  // on a face the disc reaches
        if (order == ElementOrder::P1) {
          EXPECT_GE(w, 0.0);
        }
        midEdge = midEdge || node >= mesh.nodes.rows();
      }
      EXPECT_NEAR(sum, 1.0, 1e-12);
      EXPECT_LT((action - point).norm(), 0.02 * rho) << "spread " << spread;  // measured ≤ 0.4 % of ρ
      if (order == ElementOrder::P2) {
        EXPECT_TRUE(midEdge);  // where a pressure puts most of its load
      }
      if (spread == 0.0) ringOnly = rho;
      std::printf("%s plate, spread %.2f: ρ = %.4f m (a = %.4f m) over %zu nodes, point of action off by %.2e m\n",
                  elementOrderName(order), spread, rho, res.contact.patchRadiusM, res.loadWeights.size(),
                  (action - point).norm());
    }
    EXPECT_LT(ringOnly, 0.05 * diagonal(mesh));  // the mesh's ring alone is finer than the object's length
  }
}

TEST(ContactLoad, SpreadOutsideZeroToOneIsATypedError) {
  const Pack pack = testing::makeGlassPlatePack(300, 4, 0.1).value();
  for (const double bad : {-0.1, 1.0, std::nan("")}) {
    WorldSettings s;
    s.fracture.contactSpreadFraction = bad;
    auto w = World::create(Pack(pack), s);
    ASSERT_FALSE(w);
    EXPECT_EQ(w.error().code, ErrorCode::InvalidArgument);
  }
}

TEST(ContactLoad, CorrectedPeakAgreesOnThreeMeshSizes) {
  // The same ball on three meshes of a P2 plate, 0.12 × 0.12 × 0.01 m, with the load spread over
  // 0.15 of its diagonal (2.5 cm), above every mesh's ring: the same pressure on each mesh, and the
  // corrected peak (under the ball, in flexure) converges. With the load on the ring only, ρ
  // follows the mesh and so does the peak. Measured: see the printout.
  std::vector<double> peaks;
  for (const int64_t tets : {1000, 2000, 4000}) {
    const Pack pack = testing::makeGlassPlatePack(tets, 12, 0.12, ElementOrder::P2).value();
    WorldSettings s;
    s.fracture.contactSpreadFraction = 0.15;
    World world = World::create(Pack(pack), s).value();
    const double top = pack.objects[0].tetMesh.nodes.col(2).maxCoeff();
    auto r = world.impact(ballOnPlate(world.addObject({.asset = "plate"}).value(), Eigen::Vector3d(0.07, 0.05, top), 3.0));
    ASSERT_TRUE(r) << r.error().message;
    const double expectedRho = 0.15 * diagonal(pack.objects[0].tetMesh);
    EXPECT_NEAR(r.value().loadRadiusM, expectedRho, 1e-12 * expectedRho) << tets << " tets: the ring is wider";
    peaks.push_back(r.value().peakPrincipalStressPa);
    std::printf("P2 plate, %lld tets: corrected peak %.2f MPa, ρ = %.4f m, peak element %d\n",
                static_cast<long long>(pack.objects[0].tetMesh.tets.rows()), peaks.back() / 1e6, r.value().loadRadiusM,
                r.value().peakElement);
  }
  const auto [lo, hi] = std::minmax_element(peaks.begin(), peaks.end());
  EXPECT_LT(*hi / *lo, 1.15);
}

}  // namespace
}  // namespace brittle
