// Where methods fail: extreme materials, speeds and geometry, degenerate elements, solver
// non-convergence, an empty database, everything breaking at once. Each case must give a valid
// result (finite numbers, closed fragments that add up to the body) or a typed error: never NaN,
// a hang or a crash. (Ambiguous canonical frames are covered by FragmentMatcherTest.)
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "brittle/precompute/BakePipeline.h"
#include "brittle/precompute/BaseShapes.h"
#include "brittle/precompute/FragmentDatabaseBake.h"
#include "brittle/precompute/MaterialLibrary.h"
#include "brittle/precompute/ModalAnalysis.h"
#include "brittle/runtime/FemAssembly.h"
#include "brittle/descriptors/VolumeMoments.h"
#include "brittle/runtime/World.h"
#include "brittle/testing/BakeFixtures.h"
#include "brittle/testing/DatabaseFixtures.h"
#include "brittle/testing/Fixtures.h"

namespace brittle {
namespace {

Material variant(const std::string& name, double youngsModulusPa) {
  Material m = testing::presetGlass();
  m.name = name;
  m.youngsModulusPa = youngsModulusPa;
  return m;
}

class StabilityTest : public ::testing::Test {
 protected:
  // A 0.1 m glass cube, the same cube 10⁵ times stiffer and 10⁶ times softer than glass, and a
  // needle 0.2 × 0.006 × 0.006 m; a small fragment database for matching.
  static void SetUpTestSuite() {
    sPack = new Pack;
    auto add = [](const std::string& name, const TriangleMesh& surface, const Material& material, int64_t tets) {
      ObjectBakeSettings b;
      b.name = name;
      b.material = material;
      b.tetMesh.targetTets = tets;
      b.modal.modeCount = 12;
      auto asset = bakeSurface(surface, b);
      ASSERT_TRUE(asset) << name << ": " << asset.error().message;
      sPack->materials.push_back(material);
      sPack->objects.push_back(std::move(asset).value());
    };
    add("cube", testing::makeBoxSurface(0.1, 0.1, 0.1), testing::presetGlass(), 1500);
    add("stiff", testing::makeBoxSurface(0.1, 0.1, 0.1), variant("stiff", 7e15), 1500);
    add("soft", testing::makeBoxSurface(0.1, 0.1, 0.1), variant("soft", 7e4), 1500);
    add("needle", testing::makeBoxSurface(0.2, 0.006, 0.006), variant("needle-glass", 70e9), 1500);
    auto database = bakeFragmentDatabase(testing::shippedShapesDatabase({"box", "plate", "rod"}, 8, 300, 6));
    ASSERT_TRUE(database) << database.error().message;
    sPack->database = std::move(database).value();
  }
  static void TearDownTestSuite() { delete sPack; }
  static inline Pack* sPack = nullptr;

  static double volumeOf(const std::string& name) {
    for (const ObjectAsset& a : sPack->objects) {
      if (a.name == name) return a.massProperties.volumeM3;
    }
    return 0.0;
  }

  // One impact on a fresh instance of `asset`; the result must be valid or a typed error.
  static Result<ImpactResult> hit(const std::string& asset, ImpactDesc d, WorldSettings settings = {},
                                  bool withDatabase = true) {
    Pack pack = *sPack;
    if (!withDatabase) pack.database = {};
    auto world = World::create(std::move(pack), settings);
    EXPECT_TRUE(world) << world.error().message;
    if (!world) return world.error();
    auto id = world.value().addObject({.asset = asset});
    EXPECT_TRUE(id) << id.error().message;
    if (!id) return id.error();
    d.object = id.value();
    auto r = world.value().impact(d);
    if (r) expectValid(r.value(), volumeOf(asset));
    return r;
  }

  static void expectValid(const ImpactResult& r, double volume) {
    EXPECT_TRUE(std::isfinite(r.peakPrincipalStressPa));
    EXPECT_TRUE(std::isfinite(r.contact.durationS) && r.contact.durationS > 0.0);
    EXPECT_TRUE(std::isfinite(r.contact.pulseAmplitudeN) && r.contact.pulseAmplitudeN >= 0.0);
    EXPECT_TRUE(std::isfinite(r.fracture.energyBudgetJ));
    if (!r.broken) return;
    double sum = 0.0;
    for (const FragmentResult& f : r.fragments) {
      EXPECT_TRUE(f.surface.vertices.allFinite());
      EXPECT_GT(f.massProperties.volumeM3, 0.0);
      sum += f.massProperties.volumeM3;
    }
    EXPECT_NEAR(sum, volume, 1e-9 * volume);
  }

  static ImpactDesc ballOnTop(double speed, double massKg = 0.1) {
    ImpactDesc d;
    d.pointWorld = Eigen::Vector3d(0.06, 0.035, 0.1);  // the cube spans [0, 0.1]³
    d.normalWorld = Eigen::Vector3d::UnitZ();
    d.speedMps = speed;
    d.impactorMassKg = massKg;
    d.impactorRadiusM = 0.02;
    return d;
  }
};

TEST_F(StabilityTest, ExtremeSpeedsGiveValidResults) {
  // From a speck of dust's speed to a rifle bullet's and beyond: no NaN, no crash.
  for (double speed : {1e-9, 1e-4, 0.1, 30.0, 1e3, 1e5}) {
    SCOPED_TRACE(speed);
    auto r = hit("cube", ballOnTop(speed));
    ASSERT_TRUE(r) << r.error().message;
    if (speed <= 1e-4) {
      EXPECT_FALSE(r.value().broken);
    }
    if (speed >= 1e3) {
      EXPECT_TRUE(r.value().broken);
    }
  }
}

TEST_F(StabilityTest, ExtremelyStiffAndSoftMaterialsGiveValidResults) {
  for (const char* asset : {"stiff", "soft"}) {
    for (double speed : {0.5, 50.0}) {
      SCOPED_TRACE(::testing::Message() << asset << " at " << speed);
      auto r = hit(asset, ballOnTop(speed));
      ASSERT_TRUE(r) << r.error().message;
      EXPECT_GT(r.value().peakPrincipalStressPa, 0.0);
    }
  }
}

TEST_F(StabilityTest, GrazingEdgeAndCornerImpactsGiveValidResults) {
  const double s = 0.1;
  struct Case {
    const char* what;
    Eigen::Vector3d point, normal;
  };
  const Case cases[] = {
      {"edge", {s, 0.5 * s, s}, Eigen::Vector3d(1, 0, 1).normalized()},
      {"corner", {s, s, s}, Eigen::Vector3d(1, 1, 1).normalized()},
      {"corner, flat ground", {0.0, 0.0, 0.0}, Eigen::Vector3d(-1, -1, -1).normalized()},
  };
  for (const Case& c : cases) {
    for (double speed : {2.0, 40.0}) {
      SCOPED_TRACE(::testing::Message() << c.what << " at " << speed);
      ImpactDesc d = ballOnTop(speed);
      d.pointWorld = c.point;
      d.normalWorld = c.normal;
      if (std::string(c.what) == "corner, flat ground") d.impactorMassKg = d.impactorRadiusM = INFINITY;
      auto r = hit("cube", d);
      ASSERT_TRUE(r) << r.error().message;
    }
  }
  // Grazing: a ball at 40 m/s skimming the top face at 0.1° reports the face normal and the
  // normal approach speed 40 sin 0.1° = 7 cm/s.
  auto grazing = hit("cube", ballOnTop(40.0 * std::sin(0.1 * std::numbers::pi / 180.0)));
  ASSERT_TRUE(grazing) << grazing.error().message;
  EXPECT_FALSE(grazing.value().broken);
  // A host that reports a normal 89.9° off the face's gets a valid result or a typed error.
  ImpactDesc skewed = ballOnTop(40.0);
  skewed.pointWorld = Eigen::Vector3d(0.5 * s, 0.5 * s, s);
  skewed.normalWorld = Eigen::Vector3d(std::sin(89.9 * std::numbers::pi / 180), 0.0, std::cos(89.9 * std::numbers::pi / 180));
  auto r = hit("cube", skewed);
  if (!r) {
    EXPECT_EQ(r.error().code, ErrorCode::InvalidArgument) << r.error().message;
  }
}

TEST_F(StabilityTest, NeedleBreaksIntoValidPiecesAndTinyFragmentsStayClosed) {
  ImpactDesc d;
  d.pointWorld = Eigen::Vector3d(0.13, 0.003, 0.006);  // the needle spans [0, 0.2] × [0, 0.006]²
  d.normalWorld = Eigen::Vector3d::UnitZ();
  d.impactorMassKg = 0.05;
  d.impactorRadiusM = 0.005;
  const double needle = volumeOf("needle");
  for (double speed : {5.0, 200.0}) {
    SCOPED_TRACE(speed);
    d.speedMps = speed;
    auto r = hit("needle", d);  // also checks finite values and that the volumes add up
    ASSERT_TRUE(r) << r.error().message;
    ASSERT_TRUE(r.value().broken);
    EXPECT_GT(r.value().fragments.size(), 1u);
    for (const FragmentResult& f : r.value().fragments) {
      SCOPED_TRACE(::testing::Message() << "fragment of " << f.massProperties.volumeM3 / needle << " of the needle");
      // Closed as the descriptors require (no directed edge without its reverse: OpenMesh
      // otherwise), and closed, manifold and consistently oriented edge by edge.
      const auto moments = computeVolumeMoments(f.surface, 0, f.massProperties.centerOfMassM);
      ASSERT_TRUE(moments) << moments.error().message;
      EXPECT_NEAR(moments.value()(0, 0, 0), f.massProperties.volumeM3, 1e-9 * f.massProperties.volumeM3);
      EXPECT_TRUE(testing::isClosedAndOriented(f.surface));
    }
  }
}

TEST_F(StabilityTest, EverythingBreakingAtOnceStaysValidAndBounded) {
  // A 1 kg ball at 1 km/s: the cut is limited by CrackSettings::maxCracks, never unbounded.
  auto r = hit("cube", ballOnTop(1e3, 1.0));
  ASSERT_TRUE(r) << r.error().message;
  ASSERT_TRUE(r.value().broken);
  EXPECT_GE(r.value().fragments.size(), 4u);
  EXPECT_LE(r.value().fracture.crackCount, CrackSettings{}.maxCracks);
}

TEST_F(StabilityTest, EmptyDatabaseLeavesFragmentsUnmatchedNotBroken) {
  auto r = hit("cube", ballOnTop(40.0), {}, false);
  ASSERT_TRUE(r) << r.error().message;
  ASSERT_TRUE(r.value().broken);
  for (const FragmentResult& f : r.value().fragments) EXPECT_EQ(f.matchedEntry, -1);
}

TEST_F(StabilityTest, ArpackNonConvergenceFallsBackToLargerSubspacesOrATypedError) {
  const ObjectAsset& cube = sPack->objects[0];
  const Material glass = materialPreset("glass").value();
  const FemSystem system = assembleFem(cube.tetMesh, glass, {}).value();
  ModalSettings starved;
  starved.modeCount = 12;
  starved.shiftRad2PerS2 = defaultShift(cube.tetMesh.nodes, glass);
  starved.maxIterations = 1;
  starved.lanczosVectors = 19;  // the fewest ARPACK allows for 18 eigenvalues (12 + 6 rigid)
  starved.retries = 0;
  const auto failed = computeModes(system, cube.tetMesh.nodes, starved);
  ASSERT_FALSE(failed.ok());
  EXPECT_EQ(failed.error().code, ErrorCode::EigenNotConverged);
  EXPECT_NE(failed.error().message.find("converged"), std::string::npos) << failed.error().message;
  // The same start with retries (2× subspace and 2× iterations each) converges to the baked modes.
  starved.retries = 8;
  const auto recovered = computeModes(system, cube.tetMesh.nodes, starved);
  ASSERT_TRUE(recovered.ok()) << recovered.error().message;
  for (int j = 0; j < 12; ++j) {
    EXPECT_NEAR(recovered.value().basis.frequenciesHz(j) / cube.modal.frequenciesHz(j), 1.0, 1e-8) << j;
  }
}

TEST_F(StabilityTest, SliverAndNearDegenerateTetsAreHandled) {
  // Two tets sharing a face; the apex of the second sinks towards that face: from a fair tet to
  // a sliver (volume 1e-6 of the first), then flat and inverted.
  for (double height : {1.0, 1e-3, 1e-6, 0.0, -1e-3}) {
    SCOPED_TRACE(height);
    TetMesh m;
    m.nodes.resize(5, 3);
    m.nodes << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0.3, 0.3, 1, 0.3, 0.3, -height;
    m.tets.resize(2, 4);
    m.tets << 0, 1, 2, 3, 0, 2, 1, 4;
    const auto system = assembleFem(m, materialPreset("glass").value(), {});
    if (height <= 0.0) {
      ASSERT_FALSE(system.ok());  // flat or inverted
      EXPECT_EQ(system.error().code, ErrorCode::DegenerateElement);
      continue;
    }
    ASSERT_TRUE(system.ok()) << system.error().message;
    EXPECT_TRUE(Eigen::MatrixXd(system.value().stiffness).allFinite());
    ModalSettings ms;
    ms.modeCount = 2;
    ms.shiftRad2PerS2 = defaultShift(m.nodes, materialPreset("glass").value());
    // A sliver's stiffness spans ten orders of magnitude: the modes come out finite, or the
    // rigid-mode check says the basis cannot be trusted.
    const auto dense = computeModesDense(system.value(), m.nodes, ms);
    if (dense.ok()) {
      EXPECT_TRUE(dense.value().basis.frequenciesHz.allFinite());
      EXPECT_TRUE(dense.value().basis.modes.allFinite());
    } else {
      EXPECT_TRUE(dense.error().code == ErrorCode::RigidModeMismatch || dense.error().code == ErrorCode::EigenNotConverged)
          << dense.error().message;
    }
  }
}

}  // namespace
}  // namespace brittle
