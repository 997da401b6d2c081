// The default glass plate (assets/meshes/plate.off: 0.3 × 0.3 × 0.01 m, preset glass, free) with
// quadratic tetrahedra: P2 reaches the converged first frequency with a quarter of the elements
// that leave P1 38 % too stiff (issue 17; docs/results/accuracy.md has the P1 figures).
//
// Reference: the first elastic mode (twisting) converges to 389.4 Hz.
// - CalculiX 2.20 C3D10 on Mesh_3 meshes of the plate: 389.42 Hz at 41k elements, 389.90 Hz at
//   7k (issue 17).
// - brittle's own P2 (exact mass, so a Rayleigh–Ritz upper bound on every mesh), from
//     brittle_validation_tests --gtest_also_run_disabled_tests --gtest_filter=PlateFrequency.DISABLED_*
//   7 446 tets 389.632 Hz, 11 626 tets 389.590, 26 462 tets 389.590, 37 322 tets 389.424,
//   75 455 tets (369k dofs, 157 s) 389.328 Hz: the converged value lies at or below 389.33 Hz,
//   0.02 % under the 389.4 used here, far inside the 2 % target.
// - ccx on this test's 7 446-tet mesh (CalculixFrequencyTest.cpp, DISABLED_DefaultPlate):
//   389.6317 Hz with its own C3D10 mass, 389.6316 Hz with the exact one, as brittle's P2.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "brittle/core/Timing.h"
#include "brittle/descriptors/MassProperties.h"
#include "brittle/precompute/BakeManifest.h"
#include "brittle/precompute/MaterialLibrary.h"
#include "brittle/precompute/MeshIO.h"
#include "brittle/precompute/ModalAnalysis.h"
#include "brittle/precompute/TetMesher.h"
#include "brittle/runtime/FemAssembly.h"
#include "brittle/runtime/QuadraticTetMesh.h"
#include "brittle/testing/Fixtures.h"

namespace brittle {
namespace {

constexpr double kConvergedHz = 389.4;
constexpr int64_t kP1DefaultTets = 30785;  // the default pack's plate (docs/results/accuracy.md)

struct PlateMesh {
  TetMesh mesh;
  double meshingS = 0.0;
};

PlateMesh meshPlate(const TetMeshSettings& ts) {
  auto surface = readSurfaceMesh(testing::sourceDir() / "assets" / "meshes" / "plate.off");
  EXPECT_TRUE(surface.ok()) << surface.error().message;
  const auto start = SteadyClock::now();
  auto tets = tetrahedralize(surface.value(), ts);
  EXPECT_TRUE(tets.ok()) << tets.error().message;
  return {tets.value().mesh, secondsSince(start)};
}

struct FirstMode {
  double hz = 0.0;
  Eigen::Index dofs = 0;
  double assemblyS = 0.0, modalS = 0.0;
};

template <class Mesh>
FirstMode firstElasticMode(const Mesh& mesh, const Material& material) {
  const auto start = SteadyClock::now();
  const FemSystem sys = assembleFem(mesh, material, {}).value();
  const double assemblyS = secondsSince(start);
  ModalSettings ms;
  ms.modeCount = 2;
  ms.shiftRad2PerS2 = defaultShift(mesh.nodes, material);
  auto modes = computeModes(sys, mesh.nodes, ms);
  EXPECT_TRUE(modes.ok()) << modes.error().message;
  if (!modes.ok()) return {};
  return {modes.value().basis.frequenciesHz(0), sys.stiffness.rows(), assemblyS, secondsSince(start) - assemblyS};
}

TEST(PlateFrequency, P2ReachesTheConvergedFirstModeWithAQuarterOfTheP1Elements) {
  const Material glass = materialPreset("glass").value();
  TetMeshSettings ts;  // the bake's defaults
  ts.targetTets = 6000;
  const PlateMesh plate = meshPlate(ts);
  const int64_t tets = plate.mesh.tets.rows();
  ASSERT_LE(4 * tets, kP1DefaultTets);
  const QuadraticTetMesh quadratic = makeQuadraticTetMesh(plate.mesh).value();
  const FirstMode p2 = firstElasticMode(quadratic, glass);
  const FirstMode p1 = firstElasticMode(plate.mesh, glass);
  std::printf("plate, %lld tets (meshed in %.2f s): P2 %.2f Hz (%+.2f%% against %.1f Hz; %lld dofs, assembly %.2f s, modes %.2f s), "
              "P1 %.2f Hz (%+.1f%%; %lld dofs, assembly %.2f s, modes %.2f s)\n",
              static_cast<long long>(tets), plate.meshingS, p2.hz, 100.0 * (p2.hz / kConvergedHz - 1.0), kConvergedHz,
              static_cast<long long>(p2.dofs), p2.assemblyS, p2.modalS, p1.hz, 100.0 * (p1.hz / kConvergedHz - 1.0),
              static_cast<long long>(p1.dofs), p1.assemblyS, p1.modalS);
  EXPECT_NEAR(p2.hz / kConvergedHz, 1.0, 0.02);
  // P2 converges from above as P1 does (a conforming displacement method), and P1 locks.
  EXPECT_GT(p2.hz, kConvergedHz * (1.0 - 1e-3));
  EXPECT_GT(p1.hz, 1.3 * p2.hz);
}

TEST(PlateFrequency, TheDefaultPacksStretchedPlateIsWithinAFifthOfAPercentWithFewerTets) {
  // The default pack meshes the plate with tets twice as wide as thick (TetMesher.h): its bending
  // needs one quadratic element through the thickness, not elements as wide as it is thick.
  // Measured at 4 007 tets: 389.95 Hz (+0.14 %), against 389.63 Hz (+0.06 %) at 7 446 near-regular
  // ones; the impacts' cost: docs/realtime.md.
  auto manifest = loadBakeManifest(testing::sourceDir() / "assets" / "default-pack.json");
  ASSERT_TRUE(manifest) << manifest.error().message;
  const auto plate = std::find_if(manifest.value().begin(), manifest.value().end(),
                                  [](const ObjectBakeSettings& o) { return o.name == "glass-plate"; });
  ASSERT_NE(plate, manifest.value().end());
  ASSERT_EQ(plate->elementOrder, ElementOrder::P2);
  ASSERT_GT(plate->tetMesh.thinStretch, 1.0);
  const PlateMesh stretched = meshPlate(plate->tetMesh);
  TetMeshSettings near = plate->tetMesh;
  near.thinStretch = 1.0;
  const PlateMesh regular = meshPlate(near);
  const int64_t tets = stretched.mesh.tets.rows();
  EXPECT_LT(static_cast<double>(tets), 0.65 * static_cast<double>(regular.mesh.tets.rows()));
  EXPECT_LE(7 * tets, kP1DefaultTets);  // issue 17 asked for a quarter
  // Taken back: the same solid, its faces where they were (exactly here, an axis-aligned plate;
  // a tilted one: TetMesherTest).
  EXPECT_NEAR(computeTetMassProperties(stretched.mesh, 1.0).volumeM3, 0.3 * 0.3 * 0.01, 1e-9 * 9e-4);
  EXPECT_NEAR(stretched.mesh.nodes.col(2).maxCoeff(), 0.005, 1e-15);
  EXPECT_NEAR(stretched.mesh.nodes.col(2).minCoeff(), -0.005, 1e-15);
  // Fewer, wider tets: their edges reach further in plane (Mesh_3's size, ∝ tets^(-1/3) in the
  // stretched solid, is the in-plane one).
  auto inPlaneReach = [](const TetMesh& m) {
    double sum = 0.0;
    for (Eigen::Index t = 0; t < m.tets.rows(); ++t) {
      for (int a = 0; a < 4; ++a) {
        for (int b = a + 1; b < 4; ++b) sum += (m.nodes.row(m.tets(t, a)) - m.nodes.row(m.tets(t, b))).head<2>().norm();
      }
    }
    return sum / (6.0 * static_cast<double>(m.tets.rows()));
  };
  EXPECT_GT(inPlaneReach(stretched.mesh), 1.3 * inPlaneReach(regular.mesh));
  const Material glass = materialPreset("glass").value();
  const FirstMode p2 = firstElasticMode(makeQuadraticTetMesh(stretched.mesh).value(), glass);
  std::printf("plate stretched %.1f: %lld tets (near-regular: %lld), P2 %.2f Hz (%+.2f%%)\n", plate->tetMesh.thinStretch,
              static_cast<long long>(tets), static_cast<long long>(regular.mesh.tets.rows()), p2.hz,
              100.0 * (p2.hz / kConvergedHz - 1.0));
  EXPECT_NEAR(p2.hz / kConvergedHz, 1.0, 0.002);
  EXPECT_GT(p2.hz, kConvergedHz * (1.0 - 1e-3));
}

// Not run by default (minutes): the refinement that gives the reference value above.
TEST(PlateFrequency, DISABLED_ConvergedFirstFrequency) {
  const Material glass = materialPreset("glass").value();
  for (int64_t target : {6000, 12000, 24000, 48000, 96000}) {
    TetMeshSettings ts;
    ts.targetTets = target;
    const PlateMesh plate = meshPlate(ts);
    const QuadraticTetMesh quadratic = makeQuadraticTetMesh(plate.mesh).value();
    const FirstMode p2 = firstElasticMode(quadratic, glass);
    std::printf("P2, %lld tets, %lld dofs: %.3f Hz (%.1f s)\n", static_cast<long long>(plate.mesh.tets.rows()),
                static_cast<long long>(p2.dofs), p2.hz, p2.assemblyS + p2.modalS);
    std::fflush(stdout);
  }
}

}  // namespace
}  // namespace brittle
