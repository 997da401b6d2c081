// The runtime end to end on baked objects: thresholds, conservation, determinism, pruning,
// recursive fracture through the database, and typed errors.
#include "brittle/runtime/Fingerprint.h"
#include "brittle/runtime/World.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <functional>
#include <map>
#include <mutex>
#include <stdexcept>
#include <thread>

#include "brittle/precompute/BakePipeline.h"
#include "brittle/precompute/BaseShapes.h"
#include "brittle/precompute/FragmentDatabaseBake.h"
#include "brittle/precompute/MeshValidation.h"
#include "brittle/runtime/FragmentModes.h"
#include "brittle/runtime/PolynomialModes.h"
#include "brittle/runtime/TetTopology.h"
#include "brittle/testing/BakeFixtures.h"
#include "brittle/testing/DatabaseFixtures.h"
#include "brittle/testing/Fixtures.h"
#include "brittle/core/EigenBlocking.h"

namespace brittle {
namespace {

// FNV-1a over the fragments' arrays: equal results give equal hashes.
uint64_t hashFragments(const ImpactResult& r) {
  uint64_t h = 1469598103934665603ull;
  auto eat = [&](const void* data, size_t bytes) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (size_t i = 0; i < bytes; ++i) h = (h ^ p[i]) * 1099511628211ull;
  };
  for (const FragmentResult& f : r.fragments) {
    eat(f.surface.vertices.data(), sizeof(double) * static_cast<size_t>(f.surface.vertices.size()));
    eat(f.surface.faces.data(), sizeof(int32_t) * static_cast<size_t>(f.surface.faces.size()));
  }
  return h;
}

class WorldTest : public ::testing::Test {
 protected:
  // A glass plate 0.3 × 0.3 × 0.01 m (the case, coarser) and a small fragment database,
  // baked once for the suite.
  static void SetUpTestSuite() {
    auto plate = testing::makeGlassPlatePack(3000, 20);
    ASSERT_TRUE(plate) << plate.error().message;
    sPack = new Pack(std::move(plate).value());
    auto database = bakeFragmentDatabase(testing::shippedShapesDatabase({"box", "plate", "wedge", "blob"}, 16, 400, 12));
    ASSERT_TRUE(database) << database.error().message;
    sPack->database = std::move(database).value();
  }
  static void TearDownTestSuite() { delete sPack; }
  static Pack* sPack;

  static World makeWorld(WorldSettings settings = {}, bool withDatabase = true) {
    Pack pack = *sPack;
    if (!withDatabase) pack.database = {};
    auto w = World::create(std::move(pack), settings);
    EXPECT_TRUE(w) << w.error().message;
    return std::move(w).value();
  }

  // The suite's pack with synthetic frequency-error models (MatchErrors.h), calibrated at the
  // runtime's default degree 5: the error rises with the indicator; the three models differ in
  // their bins (2, 4 and 3), so a prediction read from the wrong one differs.
  static Pack withFrequencyModels() {
    Pack pack = *sPack;
    std::vector<std::pair<double, double>> samples;
    for (int k = 1; k <= 8; ++k) samples.emplace_back(0.05 * k, 0.1 * k);
    FrequencyErrorModels& models = pack.database.frequencyErrors;
    models.ritz = fitMatchErrors(samples, MatchErrorSettings{.bins = 2}).value();
    models.checked = fitMatchErrors(samples, MatchErrorSettings{.bins = 4}).value();
    models.checkedP2 = fitMatchErrors(samples, MatchErrorSettings{.bins = 3}).value();
    models.degree = 5;
    return pack;
  }

  // A steel ball on the plate's top face, 1 cm and 2 cm off its centre (the plate is [0, 0.3]² × [0, 0.01]).
  static ImpactDesc ball(ObjectId id, double speed, double massKg = 0.1, double radiusM = 0.02) {
    ImpactDesc d;
    d.object = id;
    d.pointWorld = Eigen::Vector3d(0.16, 0.13, 0.01);
    d.normalWorld = Eigen::Vector3d::UnitZ();
    d.speedMps = speed;
    d.impactorMassKg = massKg;
    d.impactorRadiusM = radiusM;
    return d;
  }

  // The largest matched fragment of `broken` (null: none).
  static const FragmentResult* largestMatched(const ImpactResult& broken) {
    const FragmentResult* target = nullptr;
    for (const FragmentResult& f : broken.fragments) {
      if (f.path == FragmentPath::Matched && (!target || f.massProperties.volumeM3 > target->massProperties.volumeM3)) target = &f;
    }
    return target;
  }

  // A hit far below its threshold (the fragment stays whole) on the largest matched fragment of
  // `broken`, at its highest node, from above.
  static ImpactDesc softHitOnTheLargestMatched(World& world, const ImpactResult& broken) {
    const FragmentResult* target = largestMatched(broken);
    EXPECT_NE(target, nullptr);
    if (!target) return {};
    const Points& nodes = world.objectAsset(target->object).value()->tetMesh.nodes;
    Eigen::Index top;
    nodes.col(2).maxCoeff(&top);
    ImpactDesc soft = ball(target->object, 0.05);
    soft.pointWorld = nodes.row(top).transpose();
    soft.pointToleranceM = 1.0;
    return soft;
  }

  // A world and the same break in it.
  struct Broken {
    World& world;
    const ImpactResult& result;
  };
  // A soft hit on the largest matched piece of `world`'s break: at `earlyS` (before its version's
  // due time) the same as in `before`, at `lateS` (at or after it) the same as in `after`, and the
  // two differ.
  static void expectHitsFollowTheDueTime(Broken world, Broken before, Broken after, double earlyS, double lateS) {
    ImpactDesc soft = softHitOnTheLargestMatched(world.world, world.result);
    ImpactDesc softBefore = softHitOnTheLargestMatched(before.world, before.result);
    ImpactDesc softAfter = softHitOnTheLargestMatched(after.world, after.result);
    ASSERT_TRUE(soft.object.valid() && softBefore.object.valid() && softAfter.object.valid());
    soft.timeS = softBefore.timeS = earlyS;
    auto early = world.world.impact(soft);
    auto earlyReference = before.world.impact(softBefore);
    soft.timeS = softAfter.timeS = lateS;
    auto late = world.world.impact(soft);
    auto lateReference = after.world.impact(softAfter);
    ASSERT_TRUE(early && earlyReference && late && lateReference);
    EXPECT_EQ(early.value().peakPrincipalStressPa, earlyReference.value().peakPrincipalStressPa);
    EXPECT_EQ(late.value().peakPrincipalStressPa, lateReference.value().peakPrincipalStressPa);
    EXPECT_NE(early.value().peakPrincipalStressPa, late.value().peakPrincipalStressPa);
  }

  // Lowest speed (to 1 %) that breaks the plate, by bisection on [lo, hi].
  static double breakingSpeed(World& world, const std::function<ImpactDesc(ObjectId, double)>& make) {
    double lo = 0.01, hi = 400.0;
    auto breaks = [&](double v) {
      auto id = world.addObject({.asset = "plate"});
      auto r = world.impact(make(id.value(), v));
      EXPECT_TRUE(r) << r.error().message;
      if (world.isAlive(id.value())) {
        EXPECT_TRUE(world.removeObject(id.value()));
      }
      return r && r.value().broken;
    };
    EXPECT_FALSE(breaks(lo));
    EXPECT_TRUE(breaks(hi));
    while (hi / lo > 1.01) {
      const double mid = std::sqrt(lo * hi);
      (breaks(mid) ? hi : lo) = mid;
    }
    return hi;
  }
};
Pack* WorldTest::sPack = nullptr;

TEST_F(WorldTest, BreaksAboveAThresholdWithClosedFragmentsThatConserveVolumeAndMass) {
  World world = makeWorld();
  auto id = world.addObject({.asset = "plate"});
  ASSERT_TRUE(id) << id.error().message;
  auto soft = world.impact(ball(id.value(), 0.05));
  ASSERT_TRUE(soft) << soft.error().message;
  EXPECT_FALSE(soft.value().broken);
  EXPECT_LT(soft.value().peakPrincipalStressPa, sPack->materials[0].tensileStrengthPa);
  EXPECT_TRUE(world.isAlive(id.value()));

  auto hard = world.impact(ball(id.value(), 60.0));
  ASSERT_TRUE(hard) << hard.error().message;
  const ImpactResult& r = hard.value();
  ASSERT_TRUE(r.broken);
  EXPECT_GE(r.fragments.size(), 2u);
  EXPECT_FALSE(world.isAlive(id.value()));  // the broken body's id is stale
  const ObjectAsset& plate = sPack->objects[0];
  const double volume = computeTetMassProperties(plate.tetMesh, 1.0).volumeM3;
  double sum = 0.0, mass = 0.0;
  for (const FragmentResult& f : r.fragments) {
    const Status valid = validateSurfaceMesh(f.surface);
    EXPECT_TRUE(valid) << valid.error().message;
    sum += f.massProperties.volumeM3;
    mass += f.massProperties.massKg;
    EXPECT_EQ(f.debris, f.massProperties.volumeM3 < 0.01 * volume);
    if (!f.debris) {
      EXPECT_TRUE(f.matchedEntry >= 0 || f.exactModes);
      EXPECT_TRUE(world.isAlive(f.object));
    }
  }
  EXPECT_NEAR(sum, volume, 1e-9 * volume);
  EXPECT_NEAR(mass, plate.massProperties.massKg, 1e-9 * plate.massProperties.massKg);
  EXPECT_GT(r.fracture.crackAreaM2, 0.0);
  EXPECT_LE(r.fracture.energySpentJ, r.fracture.energyBudgetJ);
  EXPECT_GT(r.contact.durationS, 0.0);
}

// The P2 plate tests' hit: a 100 g ball at 60 m/s on the small plate's top face.
ImpactDesc quadraticPlateHit(ObjectId plate) {
  ImpactDesc d;
  d.object = plate;
  d.pointWorld = Eigen::Vector3d(0.07, 0.08, 0.01);
  d.normalWorld = Eigen::Vector3d::UnitZ();
  d.speedMps = 60.0;
  d.impactorMassKg = 0.1;
  d.impactorRadiusM = 0.02;
  return d;
}

// The small P2 plate the WorldP2Test tests break, baked once for the process (they run in one).
const Result<Pack>& quadraticPlatePack() {
  static const Result<Pack> pack = testing::makeGlassPlatePack(300, 12, 0.15, ElementOrder::P2);
  return pack;
}

TEST(WorldP2Test, FragmentsMatchedToQuadraticEntriesAreQuadraticAndBreakAgain) {
  // A database of the brick's own pieces in P2 tets (bake-db --element p2 on a mesh base shape,
  // broken off by the runtime): a matched fragment is its entry placed, P2 (FEM nodes and four
  // stress points per tet), and it breaks again.
  ASSERT_TRUE(quadraticPlatePack()) << quadraticPlatePack().error().message;
  Pack pack = quadraticPlatePack().value();
  DatabaseBakeSettings db = testing::brickPiecesDatabase(4);
  db.modeCount = 8;
  auto database = bakeFragmentDatabase(db);
  ASSERT_TRUE(database) << database.error().message;
  pack.database = std::move(database).value();
  WorldSettings settings;
  settings.fracture.exactModesMaxTets = 0;  // every fragment that is not debris is matched
  auto world = World::create(std::move(pack), settings);
  ASSERT_TRUE(world) << world.error().message;
  ImpactDesc d = quadraticPlateHit(world.value().addObject({.asset = "plate"}).value());
  auto hit = world.value().impact(d);
  ASSERT_TRUE(hit) << hit.error().message;
  ASSERT_TRUE(hit.value().broken);
  int matched = 0, brokeAgain = 0;
  for (const FragmentResult& f : hit.value().fragments) {
    if (f.matchedEntry < 0) continue;
    ++matched;
    auto asset = world.value().objectAsset(f.object);
    ASSERT_TRUE(asset) << asset.error().message;
    const ObjectAsset& a = *asset.value();
    EXPECT_EQ(a.elementOrder, ElementOrder::P2);
    EXPECT_EQ(a.modal.modes.rows(), 3 * femNodeCount(a.tetMesh, ElementOrder::P2));
    EXPECT_EQ(a.stressModes.rows(), 24 * a.tetMesh.tets.rows());
    // The body's mass properties are the fragment's own, exactly (not the entry's rescaled ones,
    // whose inertia follows the entry's shape): its next contact sees the piece's mass and inertia.
    EXPECT_EQ(a.massProperties.volumeM3, f.massProperties.volumeM3);
    EXPECT_EQ(a.massProperties.massKg, f.massProperties.massKg);
    EXPECT_EQ(a.massProperties.centerOfMassM, f.massProperties.centerOfMassM);
    EXPECT_EQ(a.massProperties.inertiaKgM2, f.massProperties.inertiaKgM2);
    ImpactDesc again = d;
    again.object = f.object;
    again.pointWorld = a.tetMesh.nodes.row(a.surfaceFaces(0, 0)).transpose();
    again.normalWorld = Eigen::Vector3d::UnitZ();
    again.speedMps = 80.0;
    auto second = world.value().impact(again);
    ASSERT_TRUE(second) << second.error().message;
    brokeAgain += second.value().broken ? 1 : 0;
  }
  EXPECT_GE(matched, 2);
  EXPECT_GE(brokeAgain, 1);
}

TEST(WorldP2Test, AQuadraticPlateBreaksIntoClosedFragmentsThatKeepTheirElement) {
  // The default pack's plate is P2: its impact scans the elements' corners, its static correction
  // solves with the P2 K, and the exact path gives each fragment its own P2 model.
  const Result<Pack>& pack = quadraticPlatePack();
  ASSERT_TRUE(pack) << pack.error().message;
  const ObjectAsset plate = pack.value().objects[0];
  ASSERT_EQ(plate.elementOrder, ElementOrder::P2);
  WorldSettings settings;
  settings.fracture.exactModesMaxTets = 1000000;  // every fragment that is not debris
  settings.fracture.exactModesMaxDof = 0;
  settings.fracture.exactModesBudgetDof = 0;
  settings.fracture.exactModeCount = 4;           // a few modes: the element is the point here
  const Pack source = pack.value();
  auto world = World::create(Pack(source), settings);
  ASSERT_TRUE(world) << world.error().message;
  ImpactDesc d = quadraticPlateHit(world.value().addObject({.asset = "plate"}).value());
  auto hit = world.value().impact(d);
  ASSERT_TRUE(hit) << hit.error().message;
  const ImpactResult& r = hit.value();
  ASSERT_TRUE(r.broken);
  EXPECT_TRUE(r.staticCorrectionUsed);
  ASSERT_GE(r.peakElement, 0);
  EXPECT_LT(r.peakElement, plate.tetMesh.tets.rows());
  const double volume = computeTetMassProperties(plate.tetMesh, 1.0).volumeM3;
  double sum = 0.0;
  int exact = 0;
  for (const FragmentResult& f : r.fragments) {
    const Status valid = validateSurfaceMesh(f.surface);
    EXPECT_TRUE(valid) << valid.error().message;
    sum += f.massProperties.volumeM3;
    if (!f.exactModes) continue;
    ++exact;
    const ObjectAsset& a = *world.value().objectAsset(f.object).value();
    EXPECT_EQ(a.elementOrder, ElementOrder::P2);
    EXPECT_EQ(a.modal.modes.rows(), 3 * femNodeCount(a.tetMesh, ElementOrder::P2));
    EXPECT_EQ(a.stressModes.rows(), 24 * a.tetMesh.tets.rows());
    EXPECT_GT(a.modal.frequenciesHz[0], 0.0);
    EXPECT_LT(a.modal.residuals.maxCoeff(), 1e-6);
  }
  EXPECT_GE(exact, 2);
  EXPECT_NEAR(sum, volume, 1e-9 * volume);

  // The exact path's budget in degrees of freedom: over it, a fragment goes to the match (here,
  // with no database, it stays a surface) and says why.
  WorldSettings tight = settings;
  tight.fracture.exactModesMaxDof = 30;
  auto small = World::create(Pack(source), tight);
  ASSERT_TRUE(small) << small.error().message;
  d.object = small.value().addObject({.asset = "plate"}).value();
  auto again = small.value().impact(d);
  ASSERT_TRUE(again && again.value().broken);
  for (const FragmentResult& f : again.value().fragments) {
    if (f.debris) continue;
    EXPECT_FALSE(f.exactModes);
    EXPECT_NE(f.reason.find("over exactModesMaxDof = 30"), std::string::npos) << f.reason;
  }
  tight.fracture.exactModesMaxDof = -1;
  EXPECT_EQ(World::create(Pack(source), tight).error().code, ErrorCode::InvalidArgument);
}

TEST_F(WorldTest, SameSeedSameFragmentsOtherSeedOtherCracks) {
  auto run = [&](uint64_t seed) {
    WorldSettings s;
    s.seed = seed;
    World world = makeWorld(s, false);
    auto id = world.addObject({.asset = "plate"});
    return world.impact(ball(id.value(), 60.0)).value();
  };
  const ImpactResult a = run(1), b = run(1), c = run(2);
  ASSERT_TRUE(a.broken && c.broken);
  EXPECT_EQ(hashFragments(a), hashFragments(b));
  EXPECT_EQ(a.fracture.cutElements, b.fracture.cutElements);
  EXPECT_NE(a.fracture.cutElements, c.fracture.cutElements);  // the noise is seeded
  // Same contact and stresses: the seed only steers the crack paths.
  EXPECT_EQ(a.peakPrincipalStressPa, c.peakPrincipalStressPa);
}

TEST_F(WorldTest, OtherSeedsGiveOtherCracksWithTheSameStatistics) {
  // Two disjoint sets of eight seeds: every impact breaks the pane, and the mean fragment count
  // and largest-fragment fraction of the two sets agree within the spread of single runs.
  auto stats = [&](uint64_t firstSeed) {
    double fragments = 0.0, largest = 0.0;
    for (uint64_t seed = firstSeed; seed < firstSeed + 8; ++seed) {
      WorldSettings s;
      s.seed = seed;
      World world = makeWorld(s, false);
      auto r = world.impact(ball(world.addObject({.asset = "plate"}).value(), 20.0)).value();
      EXPECT_TRUE(r.broken) << seed;
      double total = 0.0, big = 0.0;
      for (const FragmentResult& f : r.fragments) {
        total += f.massProperties.volumeM3;
        big = std::max(big, f.massProperties.volumeM3);
      }
      fragments += static_cast<double>(r.fragments.size()) / 8.0;
      largest += big / total / 8.0;
    }
    return std::pair{fragments, largest};
  };
  const auto [countA, largestA] = stats(100);
  const auto [countB, largestB] = stats(200);
  std::printf("mean fragments %.2f vs %.2f, largest fraction %.3f vs %.3f\n", countA, countB, largestA, largestB);
  EXPECT_NEAR(countA / countB, 1.0, 0.35);
  EXPECT_NEAR(largestA, largestB, 0.15);
}

TEST_F(WorldTest, PruningChangesNothingButTheWork) {
  WorldSettings pruned, full;
  full.fracture.pruneStresses = false;
  for (double speed : {0.5, 60.0}) {
    World a = makeWorld(pruned, false), b = makeWorld(full, false);
    auto ra = a.impact(ball(a.addObject({.asset = "plate"}).value(), speed)).value();
    auto rb = b.impact(ball(b.addObject({.asset = "plate"}).value(), speed)).value();
    EXPECT_EQ(ra.peakPrincipalStressPa, rb.peakPrincipalStressPa);
    EXPECT_EQ(ra.peakElement, rb.peakElement);
    EXPECT_EQ(ra.peakTimeS, rb.peakTimeS);
    EXPECT_EQ(ra.fracture.cutElements, rb.fracture.cutElements);
    EXPECT_EQ(hashFragments(ra), hashFragments(rb));
    EXPECT_LT(ra.stressEvaluations, rb.stressEvaluations);
  }
}

TEST_F(WorldTest, ThresholdMovesWithStrengthImpactorMassAndRadius) {
  World base = makeWorld({}, false);
  const double v0 = breakingSpeed(base, [](ObjectId id, double v) { return ball(id, v); });
  const double heavier = breakingSpeed(base, [](ObjectId id, double v) { return ball(id, v, 0.4); });
  const double smaller = breakingSpeed(base, [](ObjectId id, double v) { return ball(id, v, 0.1, 0.002); });
  const double larger = breakingSpeed(base, [](ObjectId id, double v) { return ball(id, v, 0.1, 0.08); });
  Pack strong = *sPack;
  strong.database = {};
  strong.materials[0].tensileStrengthPa *= 2.0;
  World strongWorld = World::create(std::move(strong)).value();
  const double stronger = breakingSpeed(strongWorld, [](ObjectId id, double v) { return ball(id, v); });
  std::printf("breaking speed: base %.3g m/s, 4x mass %.3g, radius 2 mm %.3g, radius 80 mm %.3g, 2x strength %.3g\n", v0,
              heavier, smaller, larger, stronger);
  EXPECT_LT(heavier, v0);
  EXPECT_GT(stronger, v0);
  // The plate fails in flexure (the back-face tension under the ball). A larger ball makes a stiffer
  // Hertz contact: a shorter, higher pulse for the same impulse, which loads the modes more, so it
  // breaks the plate at a lower speed (measured: 2 mm 4.82 m/s, 20 mm 4.39, 80 mm 3.88; the patches
  // are all smaller than the load's spread, ContactGeometry.h, so only the pulses differ). Local
  // Hertzian cone cracks, which favour small balls, are finer than the spread and not modelled.
  EXPECT_LT(larger, smaller * 0.97);
  EXPECT_LE(larger, v0);
  EXPECT_LE(v0, smaller);
}

TEST_F(WorldTest, MatchedFragmentsBreakAgain) {
  World world = makeWorld();
  auto first = world.impact(ball(world.addObject({.asset = "plate"}).value(), 60.0));
  ASSERT_TRUE(first && first.value().broken);
  // The largest matched fragment, hit hard at a point on its surface.
  const FragmentResult* target = nullptr;
  for (const FragmentResult& f : first.value().fragments) {
    if (f.object.valid() && (!target || f.massProperties.volumeM3 > target->massProperties.volumeM3)) target = &f;
  }
  ASSERT_NE(target, nullptr);
  auto asset = world.objectAsset(target->object);
  ASSERT_TRUE(asset);
  EXPECT_GT(asset.value()->modal.frequenciesHz.size(), 0);
  // Hit the fragment's highest node, from above.
  const Points& nodes = asset.value()->tetMesh.nodes;
  Eigen::Index top;
  nodes.col(2).maxCoeff(&top);
  ImpactDesc again = ball(target->object, 200.0);
  again.pointWorld = nodes.row(top).transpose();
  again.pointToleranceM = 1.0;
  auto second = world.impact(again);
  ASSERT_TRUE(second) << second.error().message;
  EXPECT_TRUE(second.value().broken);
  EXPECT_GE(second.value().fragments.size(), 2u);
}

// A matched fragment's body is its database entry's shape standing in for the fragment, and the
// host collides with the fragment, whose surface can lie off the entry's: such a body takes a
// point up to its own size from its surface, whatever the host's tolerance; a body with its own
// mesh (here the plate) keeps the host's, or 5 % of its size. Farther than either: InvalidArgument.
TEST_F(WorldTest, AMatchedBodyTakesAPointOffItsEntrysSurfaceWithinItsSize) {
  World world = makeWorld();
  auto first = world.impact(ball(world.addObject({.asset = "plate"}).value(), 60.0));
  ASSERT_TRUE(first && first.value().broken);
  const FragmentResult* target = largestMatched(first.value());
  ASSERT_NE(target, nullptr);
  auto asset = world.objectAsset(target->object);
  ASSERT_TRUE(asset) << asset.error().message;
  ASSERT_NE(world.frequencyError(target->object, 0.0).value().source, FrequencySource::Own);
  const Points& nodes = asset.value()->tetMesh.nodes;
  const double size = (nodes.colwise().maxCoeff() - nodes.colwise().minCoeff()).norm();
  // Above the highest node by `fraction` of the size: every surface point is at most that high,
  // so the point is exactly that far from the surface.
  Eigen::Index top;
  nodes.col(2).maxCoeff(&top);
  auto above = [&](ObjectId id, const Eigen::Vector3d& p, double fraction, double length, double hostToleranceM = 0.0) {
    ImpactDesc d = ball(id, 0.05);  // far below any threshold: the object stays whole
    d.pointWorld = p + fraction * length * Eigen::Vector3d::UnitZ();
    d.pointToleranceM = hostToleranceM;
    return world.impact(d);
  };
  for (double fraction : {0.2, 0.9}) {
    for (double host : {0.0, 0.01 * size}) {
      auto hit = above(target->object, nodes.row(top).transpose(), fraction, size, host);
      ASSERT_TRUE(hit) << fraction << ", host tolerance " << host << ": " << hit.error().message;
      EXPECT_FALSE(hit.value().broken);
    }
  }
  auto far = above(target->object, nodes.row(top).transpose(), 1.1, size);
  ASSERT_FALSE(far);
  EXPECT_EQ(far.error().code, ErrorCode::InvalidArgument) << far.error().message;
  auto hostFar = above(target->object, nodes.row(top).transpose(), 1.1, size, 1.2 * size);
  EXPECT_TRUE(hostFar) << "a host's larger tolerance still holds";
  // The plate (0.3 × 0.3 × 0.01 m, top face z = 0.01): 4 % of its size above it is taken, 20 % is not.
  const ObjectId plate = world.addObject({.asset = "plate"}).value();
  const double plateSize = std::sqrt(0.3 * 0.3 + 0.3 * 0.3 + 0.01 * 0.01);
  auto near = above(plate, Eigen::Vector3d(0.16, 0.13, 0.01), 0.04, plateSize);
  ASSERT_TRUE(near) << near.error().message;
  auto off = above(plate, Eigen::Vector3d(0.16, 0.13, 0.01), 0.2, plateSize);
  ASSERT_FALSE(off);
  EXPECT_EQ(off.error().code, ErrorCode::InvalidArgument) << off.error().message;
  EXPECT_TRUE(above(plate, Eigen::Vector3d(0.16, 0.13, 0.01), 0.2, plateSize, 0.25 * plateSize));  // the host's
  auto strict = above(plate, Eigen::Vector3d(0.16, 0.13, 0.01), 0.04, plateSize, 0.01 * plateSize);
  ASSERT_FALSE(strict);
  EXPECT_EQ(strict.error().code, ErrorCode::InvalidArgument) << strict.error().message;
}

// A matched fragment's body rings at the fragment's own frequencies (PolynomialModes.h, degree 5
// by default): its frequencies are the fragment's polynomial Ritz values, its mode shapes and
// stress modes the entry's (those of the same break with degree 0, bit for bit), and it breaks
// again.
TEST_F(WorldTest, MatchedBodiesRingAtTheirFragmentsOwnFrequencies) {
  WorldSettings settings;
  settings.fracture.meshRatioMaxDof = 2000;  // some pieces the exact path leaves here are within it, some not
  World world = makeWorld(settings);
  auto broken = world.impact(ball(world.addObject({.asset = "plate"}).value(), 60.0));
  ASSERT_TRUE(broken && broken.value().broken);
  WorldSettings entries;
  entries.fracture.polynomialModeDegree = 0;
  World other = makeWorld(entries);
  auto same = other.impact(ball(other.addObject({.asset = "plate"}).value(), 60.0));
  ASSERT_TRUE(same && same.value().broken);
  ASSERT_EQ(hashFragments(same.value()), hashFragments(broken.value()));  // the break itself is the same
  const Material glass = sPack->materials.front();
  const ObjectAsset& plate = sPack->objects.front();
  ASSERT_EQ(plate.name, "plate");
  const TetTopology topology = buildTetTopology(plate.tetMesh).value();
  const FractureState& fracture = broken.value().fracture;
  int matched = 0, checked = 0;
  for (size_t i = 0; i < broken.value().fragments.size(); ++i) {
    const FragmentResult& f = broken.value().fragments[i];
    if (f.path != FragmentPath::Matched) continue;
    ++matched;
    auto asset = world.objectAsset(f.object);
    auto entry = other.objectAsset(same.value().fragments[i].object);
    ASSERT_TRUE(asset && entry);
    const ModalBasis& basis = asset.value()->modal;
    // As the World asks for them: without shapes, as many as the entry has modes.
    auto own = polynomialModes(f.surface, glass, 5, /*withShapes=*/false, entry.value()->modal.eigenvaluesRad2PerS2.size());
    ASSERT_TRUE(own) << own.error().message;
    // The lowest three corrected by the fragment's own mesh where its linear-tet model is within
    // meshRatioMaxDof: the World's values, bit for bit.
    Eigen::VectorXd expected = own.value().frequenciesHz;
    const int label = static_cast<int>(i);
    const int64_t dof = fragmentCutDof(plate.tetMesh, topology, fracture.nodeLabels, label, ElementOrder::P1, CutCells::Prisms);
    if (dof <= settings.fracture.meshRatioMaxDof) {
      ++checked;
      auto sub = fragmentSubMesh(plate.tetMesh, topology, fracture.nodeLabels, fracture.edgeCuts, label, CutCells::Prisms);
      ASSERT_TRUE(sub);
      auto ratios = meshFrequencyRatios(sub.value(), glass, 5, kMeshRatioModes);
      ASSERT_TRUE(ratios) << ratios.error().message;
      EXPECT_LT(ratios.value().ratios.minCoeff(), 1.0);
      applyMeshRatios(expected, ratios.value());
    }
    const Eigen::Index r = basis.frequenciesHz.size();
    ASSERT_GT(r, 0);
    EXPECT_EQ(basis.frequenciesHz, expected.head(r)) << "fragment " << i << ", " << dof << " DOF in linear tets";
    EXPECT_NE(basis.frequenciesHz, entry.value()->modal.frequenciesHz);
    EXPECT_EQ(basis.modes, entry.value()->modal.modes);
    EXPECT_EQ(asset.value()->stressModes, entry.value()->stressModes);
    const Eigen::VectorXd ratio = basis.eigenvaluesRad2PerS2.array() / entry.value()->modal.eigenvaluesRad2PerS2.array();
    EXPECT_EQ(basis.residuals, (1.0 - ratio.array()).abs().matrix());
  }
  std::printf("%d matched fragments, %d checked on their own mesh\n", matched, checked);
  EXPECT_GE(checked, 1);
  EXPECT_LT(checked, matched);  // the larger ones are over the limit
  EXPECT_GE(matched, 2);
  const ImpactDesc soft = softHitOnTheLargestMatched(world, broken.value());
  ImpactDesc hard = soft;
  hard.speedMps = 200.0;
  auto again = world.impact(hard);
  ASSERT_TRUE(again) << again.error().message;
  EXPECT_TRUE(again.value().broken);
}

// A later check (FractureSettings::meshRatioLateMaxDof): the pieces over meshRatioMaxDof keep their
// Ritz values for impacts before the break's time plus meshRatioLateDelayS and have them checked
// from then on, bit for bit what a world checking them at birth gives; a break without a time has
// no later version. Which version an impact sees depends on the host's times alone.
TEST_F(WorldTest, ALaterCheckAppliesFromItsDueTime) {
  auto makeSettings = [](int first, int later) {
    WorldSettings s;
    s.fracture.meshRatioMaxDof = first;
    s.fracture.meshRatioLateMaxDof = later;
    s.fracture.meshRatioLateDelayS = 0.5;
    s.fracture.meshRatioDelayS = 0.0;  // the first limit's check at birth (the next test delays it)
    return s;
  };
  World world = makeWorld(makeSettings(2000, 100000));
  World unchecked = makeWorld(makeSettings(2000, 0));
  World checked = makeWorld(makeSettings(100000, 0));
  ImpactDesc hit = ball(world.addObject({.asset = "plate"}).value(), 60.0);
  hit.timeS = 2.0;
  auto broken = world.impact(hit);
  ASSERT_TRUE(broken && broken.value().broken);
  ImpactDesc same = ball(unchecked.addObject({.asset = "plate"}).value(), 60.0);
  same.timeS = 2.0;
  auto brokenUnchecked = unchecked.impact(same);
  same.object = checked.addObject({.asset = "plate"}).value();
  auto brokenChecked = checked.impact(same);
  ASSERT_TRUE(brokenUnchecked && brokenChecked);
  ASSERT_EQ(hashFragments(brokenUnchecked.value()), hashFragments(broken.value()));
  ASSERT_EQ(hashFragments(brokenChecked.value()), hashFragments(broken.value()));
  int later = 0, matched = 0;
  for (size_t i = 0; i < broken.value().fragments.size(); ++i) {
    const FragmentResult& f = broken.value().fragments[i];
    if (f.path != FragmentPath::Matched) {
      EXPECT_TRUE(std::isnan(f.lateCheckDueS));
      continue;
    }
    ++matched;
    EXPECT_EQ(f.lateCheckDueS, 2.5);
    EXPECT_TRUE(std::isnan(brokenUnchecked.value().fragments[i].lateCheckDueS));
    const ObjectAsset* before = world.objectAsset(f.object, 2.49).value();
    const ObjectAsset* after = world.objectAsset(f.object, 2.5).value();
    EXPECT_EQ(before, world.objectAsset(f.object).value());
    EXPECT_EQ(before, world.objectAsset(f.object, std::numeric_limits<double>::quiet_NaN()).value());
    EXPECT_EQ(before->modal.frequenciesHz, unchecked.objectAsset(brokenUnchecked.value().fragments[i].object).value()->modal.frequenciesHz);
    EXPECT_EQ(after->modal.frequenciesHz, checked.objectAsset(brokenChecked.value().fragments[i].object).value()->modal.frequenciesHz);
    if (before != after) {
      ++later;
      EXPECT_NE(before->modal.frequenciesHz, after->modal.frequenciesHz);
      EXPECT_LT(after->modal.frequenciesHz[0], before->modal.frequenciesHz[0]);  // a check only lowers them
    }
  }
  std::printf("%d matched fragments, %d checked later\n", matched, later);
  EXPECT_GE(later, 1);
  EXPECT_LT(later, matched);  // the small ones were checked at birth
  expectHitsFollowTheDueTime({world, broken.value()}, {unchecked, brokenUnchecked.value()}, {checked, brokenChecked.value()}, 2.2, 3.0);
  // Without a time the break has no later version.
  World untimed = makeWorld(makeSettings(2000, 100000));
  auto plain = untimed.impact(ball(untimed.addObject({.asset = "plate"}).value(), 60.0));
  ASSERT_TRUE(plain && plain.value().broken);
  for (const FragmentResult& f : plain.value().fragments) {
    EXPECT_TRUE(std::isnan(f.lateCheckDueS));
    if (f.object.valid()) {
      EXPECT_EQ(untimed.objectAsset(f.object, 100.0).value(), untimed.objectAsset(f.object).value());
    }
  }
  // Typed errors: an infinite time, a negative or infinite delay, a negative limit.
  ImpactDesc infinite = ball(untimed.addObject({.asset = "plate"}).value(), 1.0);
  infinite.timeS = std::numeric_limits<double>::infinity();
  EXPECT_EQ(untimed.impact(infinite).error().code, ErrorCode::InvalidArgument);
  for (double delay : {-0.1, std::numeric_limits<double>::infinity()}) {
    WorldSettings wrong;
    wrong.fracture.meshRatioLateDelayS = delay;
    EXPECT_EQ(World::create(Pack(*sPack), wrong).error().code, ErrorCode::InvalidArgument) << delay;
  }
  WorldSettings negative;
  negative.fracture.meshRatioLateMaxDof = -1;
  EXPECT_EQ(World::create(Pack(*sPack), negative).error().code, ErrorCode::InvalidArgument);
}

// A timed break's exact-path pieces (FractureSettings::exactModesDelayS) are their database match,
// at their Ritz values, for impacts before the break's time plus the delay, and their own modal
// analysis from then on: bit for bit the body a world giving it at birth makes, so that a piece
// struck within frames of its birth never waits for an analysis. Without a time or a database
// the analysis is the first body.
TEST_F(WorldTest, ATimedBreaksExactPathPiecesTakeTheirOwnModesFromExactModesDelayS) {
  WorldSettings delayedSettings;  // the default delay
  ASSERT_EQ(delayedSettings.fracture.exactModesDelayS, 0.25);
  WorldSettings atBirth;
  atBirth.fracture.exactModesDelayS = 0.0;
  World world = makeWorld(delayedSettings);
  World exactFirst = makeWorld(atBirth);
  ImpactDesc hit = ball(world.addObject({.asset = "plate"}).value(), 60.0);
  hit.timeS = 2.0;
  auto broken = world.impact(hit);
  hit.object = exactFirst.addObject({.asset = "plate"}).value();
  auto reference = exactFirst.impact(hit);
  ASSERT_TRUE(broken && broken.value().broken && reference);
  ASSERT_EQ(hashFragments(broken.value()), hashFragments(reference.value()));
  const FragmentResult* largest = nullptr;
  int exact = 0;
  for (size_t i = 0; i < broken.value().fragments.size(); ++i) {
    const FragmentResult& f = broken.value().fragments[i];
    const FragmentResult& g = reference.value().fragments[i];
    EXPECT_EQ(f.path, g.path);
    if (f.path != FragmentPath::ExactModes) {
      EXPECT_TRUE(std::isnan(f.exactDueS));
      continue;
    }
    ++exact;
    EXPECT_EQ(f.exactDueS, 2.25);
    EXPECT_TRUE(std::isnan(g.exactDueS));
    const ObjectAsset* before = world.objectAsset(f.object, 2.24).value();
    const ObjectAsset* after = world.objectAsset(f.object, 2.25).value();
    EXPECT_EQ(before, world.objectAsset(f.object).value());  // an impact without a time: the first body
    EXPECT_NE(before, after);
    EXPECT_NE(before->modal.frequenciesHz, after->modal.frequenciesHz);
    EXPECT_EQ(after->modal.frequenciesHz, exactFirst.objectAsset(g.object).value()->modal.frequenciesHz);
    EXPECT_EQ(after->tetMesh.tets, exactFirst.objectAsset(g.object).value()->tetMesh.tets);
    EXPECT_EQ(world.frequencyError(f.object, 2.24).value().source, FrequencySource::Ritz);
    EXPECT_EQ(world.frequencyError(f.object, 2.25).value().source, FrequencySource::Own);
    EXPECT_EQ(exactFirst.frequencyError(g.object, 2.0).value().source, FrequencySource::Own);
    if (!largest || f.massProperties.volumeM3 > largest->massProperties.volumeM3) largest = &f;
  }
  std::printf("%d exact-path pieces of %zu fragments\n", exact, broken.value().fragments.size());
  ASSERT_GE(exact, 1);
  // A soft hit on the largest of them: before the due time on the match, from it the reference's.
  const size_t index = static_cast<size_t>(largest - broken.value().fragments.data());
  const Points& nodes = world.objectAsset(largest->object, 2.25).value()->tetMesh.nodes;
  Eigen::Index top;
  nodes.col(2).maxCoeff(&top);
  ImpactDesc soft = ball(largest->object, 0.05);
  soft.pointWorld = nodes.row(top).transpose();
  soft.pointToleranceM = 1.0;
  ImpactDesc softReference = soft;
  softReference.object = reference.value().fragments[index].object;
  soft.timeS = softReference.timeS = 2.3;
  auto late = world.impact(soft);
  auto lateReference = exactFirst.impact(softReference);
  ASSERT_TRUE(late && lateReference) << (late ? lateReference.error().message : late.error().message);
  EXPECT_EQ(late.value().peakPrincipalStressPa, lateReference.value().peakPrincipalStressPa);
  soft.timeS = 2.1;
  auto early = world.impact(soft);
  ASSERT_TRUE(early) << early.error().message;
  EXPECT_NE(early.value().peakPrincipalStressPa, late.value().peakPrincipalStressPa);
  // Without a time, or without a database, the analysis is the first body.
  for (bool database : {true, false}) {
    World other = makeWorld(delayedSettings, database);
    ImpactDesc plain = ball(other.addObject({.asset = "plate"}).value(), 60.0);
    if (!database) plain.timeS = 2.0;
    auto r = other.impact(plain);
    ASSERT_TRUE(r && r.value().broken);
    int seen = 0;
    for (const FragmentResult& f : r.value().fragments) {
      EXPECT_TRUE(std::isnan(f.exactDueS));
      if (f.path != FragmentPath::ExactModes) continue;
      ++seen;
      EXPECT_EQ(other.frequencyError(f.object, 100.0).value().source, FrequencySource::Own);
      EXPECT_EQ(other.objectAsset(f.object, 100.0).value(), other.objectAsset(f.object).value());
    }
    EXPECT_GE(seen, 1) << database;
  }
  // Typed errors: a negative, infinite or NaN delay.
  for (double delay : {-0.1, std::numeric_limits<double>::infinity(), std::numeric_limits<double>::quiet_NaN()}) {
    WorldSettings wrong;
    wrong.fracture.exactModesDelayS = delay;
    EXPECT_EQ(World::create(Pack(*sPack), wrong).error().code, ErrorCode::InvalidArgument) << delay;
  }
}

// A timed break's pieces get their check (within meshRatioMaxDof) from meshRatioDelayS after the
// break: their first body has the Ritz values alone, so that an impact within frames of the
// break never waits for a check, and the checked body is made right after the first bodies.
// Impacts before the due time are the unchecked world's, from it the world checked at birth; a
// break without a time is checked at birth.
TEST_F(WorldTest, ATimedBreaksPiecesAreCheckedFromMeshRatioDelayS) {
  auto makeSettings = [](int maxDof, double delay) {
    WorldSettings s;
    s.fracture.meshRatioMaxDof = maxDof;
    s.fracture.meshRatioDelayS = delay;
    s.fracture.meshRatioLateMaxDof = 0;  // no later check: the first limit's alone
    return s;
  };
  World world = makeWorld(makeSettings(100000, 0.25));
  World unchecked = makeWorld(makeSettings(0, 0.25));
  World checked = makeWorld(makeSettings(100000, 0.0));
  std::vector<ImpactResult> breaks;
  for (World* w : {&world, &unchecked, &checked}) {
    ImpactDesc hit = ball(w->addObject({.asset = "plate"}).value(), 60.0);
    hit.timeS = 2.0;
    auto r = w->impact(hit);
    ASSERT_TRUE(r && r.value().broken);
    breaks.push_back(std::move(r).value());
  }
  ASSERT_EQ(hashFragments(breaks[1]), hashFragments(breaks[0]));
  ASSERT_EQ(hashFragments(breaks[2]), hashFragments(breaks[0]));
  int matched = 0;
  for (size_t i = 0; i < breaks[0].fragments.size(); ++i) {
    const FragmentResult& f = breaks[0].fragments[i];
    EXPECT_TRUE(std::isnan(f.lateCheckDueS));
    if (f.path != FragmentPath::Matched) {
      EXPECT_TRUE(std::isnan(f.checkDueS));
      continue;
    }
    ++matched;
    EXPECT_EQ(f.checkDueS, 2.25);
    EXPECT_TRUE(std::isnan(breaks[1].fragments[i].checkDueS));  // nothing to check
    EXPECT_TRUE(std::isnan(breaks[2].fragments[i].checkDueS));  // checked at birth
    const ObjectAsset* before = world.objectAsset(f.object, 2.24).value();
    const ObjectAsset* after = world.objectAsset(f.object, 2.25).value();
    EXPECT_EQ(before, world.objectAsset(f.object).value());
    EXPECT_EQ(before->modal.frequenciesHz, unchecked.objectAsset(breaks[1].fragments[i].object).value()->modal.frequenciesHz);
    EXPECT_EQ(after->modal.frequenciesHz, checked.objectAsset(breaks[2].fragments[i].object).value()->modal.frequenciesHz);
    EXPECT_NE(before->modal.frequenciesHz, after->modal.frequenciesHz);
    // The checked version is the first one at other frequencies (checkedVersion): the same mesh,
    // shapes, stress modes and mass, where the world checking at birth made them itself.
    EXPECT_EQ(after->modal.modes, before->modal.modes);
    EXPECT_EQ(after->stressModes, before->stressModes);
    EXPECT_EQ(after->tetMesh.nodes, before->tetMesh.nodes);
    EXPECT_EQ(after->massProperties.inertiaKgM2, before->massProperties.inertiaKgM2);
    EXPECT_EQ(after->modal.residuals, checked.objectAsset(breaks[2].fragments[i].object).value()->modal.residuals);
    EXPECT_EQ(world.frequencyError(f.object, 2.24).value().source, FrequencySource::Ritz);
    EXPECT_EQ(world.frequencyError(f.object, 2.25).value().source, FrequencySource::Checked);
    EXPECT_EQ(world.frequencyError(f.object, 2.25).value().indicator,
              checked.frequencyError(breaks[2].fragments[i].object).value().indicator);
  }
  EXPECT_GE(matched, 2);
  expectHitsFollowTheDueTime({world, breaks[0]}, {unchecked, breaks[1]}, {checked, breaks[2]}, 2.1, 2.25);
  // Without a time the first body is checked, as with no delay.
  World untimed = makeWorld(makeSettings(100000, 0.25));
  auto plain = untimed.impact(ball(untimed.addObject({.asset = "plate"}).value(), 60.0));
  ASSERT_TRUE(plain && plain.value().broken);
  ASSERT_EQ(hashFragments(plain.value()), hashFragments(breaks[0]));
  for (size_t i = 0; i < plain.value().fragments.size(); ++i) {
    const FragmentResult& f = plain.value().fragments[i];
    EXPECT_TRUE(std::isnan(f.checkDueS));
    if (f.path != FragmentPath::Matched) continue;
    EXPECT_EQ(untimed.objectAsset(f.object).value()->modal.frequenciesHz,
              checked.objectAsset(breaks[2].fragments[i].object).value()->modal.frequenciesHz);
  }
  // Typed errors: a negative or infinite delay, or one past the later check's.
  for (double delay : {-0.1, std::numeric_limits<double>::infinity(), 0.6}) {
    WorldSettings wrong;
    wrong.fracture.meshRatioDelayS = delay;
    wrong.fracture.meshRatioLateDelayS = 0.5;
    EXPECT_EQ(World::create(Pack(*sPack), wrong).error().code, ErrorCode::InvalidArgument) << delay;
  }
  // Without a later check its delay sets no bound (settings from before the delay stay valid).
  WorldSettings noLater;
  noLater.fracture.meshRatioLateMaxDof = 0;
  noLater.fracture.meshRatioLateDelayS = 0.0;
  noLater.fracture.frequencyErrorTarget = 0.0;
  EXPECT_TRUE(World::create(Pack(*sPack), noLater));
}

// Each body says where its frequencies come from and how far off the pack's calibration predicts
// them (World::frequencyError): a pack object its own; a matched piece its Ritz values, read at
// their convergence from degree 3 to 5, or, once checked (at birth, or from its later check's due
// time), the checked values at the mesh's gain; with polynomialModeDegree 0 the entry's, at the
// match's distance. A pack without the calibration predicts nothing but still says the source.
TEST_F(WorldTest, BodiesSayWhereTheirFrequenciesComeFromAndTheirPredictedError) {
  const Pack calibrated = withFrequencyModels();
  const FrequencyErrorModels& models = calibrated.database.frequencyErrors;
  WorldSettings settings;
  settings.fracture.meshRatioMaxDof = 2000;
  settings.fracture.meshRatioDelayS = 0.0;  // the small pieces checked at birth
  settings.fracture.meshRatioLateMaxDof = 100000;
  World world = World::create(Pack(calibrated), settings).value();
  World uncalibrated = makeWorld(settings);
  const ObjectId plateId = world.addObject({.asset = "plate"}).value();
  auto own = world.frequencyError(plateId);
  ASSERT_TRUE(own);
  EXPECT_EQ(own.value().source, FrequencySource::Own);
  EXPECT_TRUE(std::isnan(own.value().indicator) && std::isnan(own.value().median) && std::isnan(own.value().p90));
  ImpactDesc hit = ball(plateId, 60.0);
  hit.timeS = 2.0;
  auto broken = world.impact(hit);
  ASSERT_TRUE(broken && broken.value().broken);
  EXPECT_EQ(world.frequencyError(plateId).error().code, ErrorCode::InvalidArgument);  // stale
  hit.object = uncalibrated.addObject({.asset = "plate"}).value();
  auto same = uncalibrated.impact(hit);
  ASSERT_TRUE(same && same.value().broken);
  const Material glass = sPack->materials.front();
  int ritz = 0, checkedAtBirth = 0, checkedLater = 0;
  for (size_t i = 0; i < broken.value().fragments.size(); ++i) {
    const FragmentResult& f = broken.value().fragments[i];
    if (f.path != FragmentPath::Matched) continue;
    auto early = world.frequencyError(f.object, 2.2);
    auto late = world.frequencyError(f.object, 2.5);
    ASSERT_TRUE(early && late);
    const FrequencyErrorPrediction& e = early.value();
    const FrequencyErrorPrediction& l = late.value();
    EXPECT_EQ(world.frequencyError(f.object).value().source, e.source);  // no time: the first body
    const auto entryModes = world.objectAsset(f.object).value()->modal.eigenvaluesRad2PerS2.size();
    if (e.source == FrequencySource::Ritz) {
      ++ritz;
      // The indicator as the API computes it: degree 3 against degree 5, from the fragment's surface.
      auto five = polynomialModes(f.surface, glass, 5, /*withShapes=*/false, entryModes);
      auto three = polynomialModes(f.surface, glass, 3, /*withShapes=*/false, kMeshRatioModes);
      ASSERT_TRUE(five && three);
      const double expected = matchFrequencyError(three.value().frequenciesHz, five.value().frequenciesHz);
      EXPECT_NEAR(e.indicator, expected, 1e-9 * expected + 1e-12) << "fragment " << i;
      EXPECT_GE(e.indicator, 0.0);
      const MatchErrorPrediction p = predictMatchError(models.ritz, e.indicator);
      EXPECT_EQ(e.median, p.median);
      EXPECT_EQ(e.p90, p.p90);
      EXPECT_EQ(e.beyondRange, p.beyondRange);
      if (l.source == FrequencySource::Checked) ++checkedLater;
    } else {
      ASSERT_EQ(e.source, FrequencySource::Checked) << "fragment " << i;
      ++checkedAtBirth;
      EXPECT_EQ(l.source, FrequencySource::Checked);
    }
    if (l.source == FrequencySource::Checked) {
      EXPECT_GT(l.indicator, 0.0);
      EXPECT_LT(l.indicator, 1.0);
      const MatchErrorPrediction p = predictMatchError(models.checked, l.indicator);
      EXPECT_EQ(l.median, p.median);
      EXPECT_EQ(l.p90, p.p90);
    }
    // The same break without the calibration: the same sources and indicators, no prediction.
    auto bare = uncalibrated.frequencyError(same.value().fragments[i].object, 2.5);
    ASSERT_TRUE(bare);
    EXPECT_EQ(bare.value().source, l.source);
    EXPECT_EQ(bare.value().indicator, l.indicator);
    EXPECT_TRUE(std::isnan(bare.value().median) && std::isnan(bare.value().p90));
  }
  std::printf("%d Ritz bodies (%d checked later), %d checked at birth\n", ritz, checkedLater, checkedAtBirth);
  EXPECT_GE(ritz, 1);
  EXPECT_GE(checkedLater, 1);
  EXPECT_GE(checkedAtBirth, 1);
  // The entry's own frequencies: the match's distance and predicted error.
  WorldSettings entries;
  entries.fracture.polynomialModeDegree = 0;
  World entryWorld = World::create(Pack(calibrated), entries).value();
  auto plain = entryWorld.impact(ball(entryWorld.addObject({.asset = "plate"}).value(), 60.0));
  ASSERT_TRUE(plain && plain.value().broken);
  int entryBodies = 0;
  for (const FragmentResult& f : plain.value().fragments) {
    if (f.path != FragmentPath::Matched) continue;
    ++entryBodies;
    const FrequencyErrorPrediction p = entryWorld.frequencyError(f.object).value();
    EXPECT_EQ(p.source, FrequencySource::Entry);
    EXPECT_EQ(p.indicator, f.matchDistance);
    EXPECT_TRUE(std::isnan(f.predictedMatchError) ? std::isnan(p.median) : p.median == f.predictedMatchError);
  }
  EXPECT_GE(entryBodies, 1);
  EXPECT_EQ(frequencySourceName(FrequencySource::Checked), "checked");
  // Models calibrated at another degree are not used: the indicators move with it.
  WorldSettings degree4;
  degree4.fracture.polynomialModeDegree = 4;
  World other = World::create(Pack(calibrated), degree4).value();
  auto four = other.impact(ball(other.addObject({.asset = "plate"}).value(), 60.0));
  ASSERT_TRUE(four && four.value().broken);
  for (const FragmentResult& f : four.value().fragments) {
    if (f.path != FragmentPath::Matched) continue;
    const FrequencyErrorPrediction p = other.frequencyError(f.object).value();
    EXPECT_NE(p.source, FrequencySource::Entry);
    EXPECT_TRUE(std::isfinite(p.indicator));
    EXPECT_TRUE(std::isnan(p.median) && std::isnan(p.p90));
  }
}

// The escalation (FractureSettings::frequencyErrorTarget): a piece whose later body the pack
// predicts over the target is checked again in quadratic tets, and its impacts from the break's
// time plus meshRatioEscalationDelayS on use that body: bit for bit the body a world checking every
// piece in P2 at birth makes. Within the target, the later body stays.
TEST_F(WorldTest, AnEscalationChecksInQuadraticTetsWhatIsPredictedOverTheTarget) {
  const Pack calibrated = withFrequencyModels();
  const FrequencyErrorModels& models = calibrated.database.frequencyErrors;
  auto makeSettings = [](double target) {
    WorldSettings s;
    s.fracture.meshRatioMaxDof = 2000;
    s.fracture.meshRatioLateMaxDof = 100000;
    s.fracture.frequencyErrorTarget = target;
    return s;
  };
  WorldSettings quadratic;
  quadratic.fracture.meshRatioMaxDof = 100000;
  quadratic.fracture.meshRatioElement = ElementOrder::P2;
  quadratic.fracture.meshRatioDelayS = 0.0;  // checked at birth
  World escalating = World::create(Pack(calibrated), makeSettings(1e-9)).value();  // every prediction is over it
  World within = World::create(Pack(calibrated), makeSettings(1e9)).value();      // none is
  World atBirth = World::create(Pack(calibrated), quadratic).value();
  ImpactDesc hit = ball(escalating.addObject({.asset = "plate"}).value(), 60.0);
  hit.timeS = 2.0;
  auto broken = escalating.impact(hit);
  hit.object = within.addObject({.asset = "plate"}).value();
  auto brokenWithin = within.impact(hit);
  hit.object = atBirth.addObject({.asset = "plate"}).value();
  auto brokenAtBirth = atBirth.impact(hit);
  ASSERT_TRUE(broken && brokenWithin && brokenAtBirth && broken.value().broken);
  ASSERT_EQ(hashFragments(broken.value()), hashFragments(brokenAtBirth.value()));
  int escalated = 0;
  for (size_t i = 0; i < broken.value().fragments.size(); ++i) {
    const FragmentResult& f = broken.value().fragments[i];
    if (f.path != FragmentPath::Matched) continue;
    EXPECT_EQ(f.escalationDueS, 4.0);  // the break's time plus meshRatioEscalationDelayS (2 s)
    EXPECT_TRUE(std::isnan(brokenAtBirth.value().fragments[i].escalationDueS));
    const ObjectAsset* later = escalating.objectAsset(f.object, 3.99).value();
    const ObjectAsset* last = escalating.objectAsset(f.object, 4.0).value();
    const FrequencyErrorPrediction p = escalating.frequencyError(f.object, 4.0).value();
    const ObjectAsset* reference = atBirth.objectAsset(brokenAtBirth.value().fragments[i].object).value();
    if (p.source == FrequencySource::CheckedP2) {
      ++escalated;
      EXPECT_NE(later, last);
      EXPECT_EQ(last->modal.frequenciesHz, reference->modal.frequenciesHz) << "fragment " << i;
      EXPECT_EQ(p.p90, predictMatchError(models.checkedP2, p.indicator).p90);
      EXPECT_EQ(atBirth.frequencyError(brokenAtBirth.value().fragments[i].object).value().source, FrequencySource::CheckedP2);
    }
    // Within the target the last version is the later body itself.
    const FragmentResult& w = brokenWithin.value().fragments[i];
    EXPECT_EQ(within.objectAsset(w.object, 10.0).value(), within.objectAsset(w.object, 3.0).value());
    EXPECT_NE(within.frequencyError(w.object, 10.0).value().source, FrequencySource::CheckedP2);
  }
  std::printf("%d pieces escalated\n", escalated);
  EXPECT_GE(escalated, 2);
  // Typed errors: a negative or infinite target, an escalation before the later check.
  for (double target : {-0.1, std::numeric_limits<double>::infinity()}) {
    WorldSettings wrong;
    wrong.fracture.frequencyErrorTarget = target;
    EXPECT_EQ(World::create(Pack(*sPack), wrong).error().code, ErrorCode::InvalidArgument) << target;
  }
  WorldSettings early;
  early.fracture.meshRatioEscalationDelayS = 0.25;  // before meshRatioLateDelayS (0.5)
  EXPECT_EQ(World::create(Pack(*sPack), early).error().code, ErrorCode::InvalidArgument);
}

// The same in quadratic tets (FractureSettings::meshRatioElement): every checked piece's lowest
// three are its Ritz values times the P2 check's ratios, bit for bit as the API computes them.
TEST_F(WorldTest, AQuadraticCheckGivesTheApisValues) {
  WorldSettings settings;
  settings.fracture.meshRatioMaxDof = 1200;
  settings.fracture.meshRatioElement = ElementOrder::P2;
  World world = makeWorld(settings);
  auto broken = world.impact(ball(world.addObject({.asset = "plate"}).value(), 60.0));
  ASSERT_TRUE(broken && broken.value().broken);
  const Material glass = sPack->materials.front();
  const ObjectAsset& plate = sPack->objects.front();
  const TetTopology topology = buildTetTopology(plate.tetMesh).value();
  const FractureState& fracture = broken.value().fracture;
  int checked = 0;
  for (size_t i = 0; i < broken.value().fragments.size(); ++i) {
    const FragmentResult& f = broken.value().fragments[i];
    if (f.path != FragmentPath::Matched) continue;
    const int label = static_cast<int>(i);
    if (fragmentCutDof(plate.tetMesh, topology, fracture.nodeLabels, label, ElementOrder::P1, CutCells::Prisms) > 1200) continue;
    ++checked;
    auto asset = world.objectAsset(f.object);
    ASSERT_TRUE(asset);
    const Eigen::Index r = asset.value()->modal.frequenciesHz.size();
    Eigen::VectorXd expected = polynomialModes(f.surface, glass, 5, /*withShapes=*/false, r).value().frequenciesHz;
    auto sub = fragmentSubMesh(plate.tetMesh, topology, fracture.nodeLabels, fracture.edgeCuts, label, CutCells::Prisms);
    auto quadratic = meshFrequencyRatios(sub.value(), glass, 5, kMeshRatioModes, ElementOrder::P2);
    auto linear = meshFrequencyRatios(sub.value(), glass, 5, kMeshRatioModes);
    ASSERT_TRUE(quadratic && linear);
    applyMeshRatios(expected, quadratic.value());
    EXPECT_EQ(asset.value()->modal.frequenciesHz, expected.head(r)) << "fragment " << i;
    EXPECT_NE(quadratic.value().ratios, linear.value().ratios);
  }
  EXPECT_GE(checked, 1);
}

// The scene's match-error target weighs each small fragment's match against the exact path: a
// match predicted within the target is taken, one predicted over it gives way to the exact path
// (and says so). The suite's database was calibrated when it was baked (MatchErrors.h).
TEST_F(WorldTest, AMatchErrorTargetTakesTheMatchWhereItIsPredictedGoodEnough) {
  ASSERT_FALSE(sPack->database.matchErrors[static_cast<size_t>(DescriptorKind::Moment)].empty());
  auto run = [&](double target) {
    WorldSettings settings;
    settings.fracture.exactModesMaxTets = 1000000;  // every fragment that is not debris may take the exact path
    settings.fracture.exactModesMaxDof = 0;
    settings.fracture.exactModesBudgetDof = 0;
    settings.fracture.exactModeCount = 4;
    settings.fracture.matchErrorTarget = target;
    World world = makeWorld(settings);
    auto hit = world.impact(ball(world.addObject({.asset = "plate"}).value(), 60.0));
    EXPECT_TRUE(hit && hit.value().broken);
    return std::move(hit).value();
  };
  const ImpactResult lenient = run(1e6), strict = run(1e-9), off = run(0.0);
  ASSERT_EQ(lenient.fragments.size(), off.fragments.size());  // the same fracture: only the new objects differ
  int fragments = 0;
  for (size_t i = 0; i < off.fragments.size(); ++i) {
    if (off.fragments[i].debris) continue;
    ++fragments;
    EXPECT_EQ(off.fragments[i].path, FragmentPath::ExactModes);
    EXPECT_TRUE(off.fragments[i].reason.empty()) << off.fragments[i].reason;
    const FragmentResult& taken = lenient.fragments[i];
    EXPECT_EQ(taken.path, FragmentPath::Matched);
    EXPECT_GE(taken.matchedEntry, 0);
    EXPECT_GE(taken.predictedMatchErrorP90, taken.predictedMatchError);
    EXPECT_GE(taken.predictedMatchError, 0.0);
    const FragmentResult& refused = strict.fragments[i];
    EXPECT_EQ(refused.path, FragmentPath::ExactModes);
    EXPECT_EQ(refused.matchedEntry, -1);
    EXPECT_EQ(refused.predictedMatchErrorP90, taken.predictedMatchErrorP90);
    EXPECT_NE(refused.reason.find("over the target"), std::string::npos) << refused.reason;
  }
  EXPECT_GE(fragments, 2);
  WorldSettings bad;
  bad.fracture.matchErrorTarget = -0.1;
  EXPECT_EQ(World::create(Pack(*sPack), bad).error().code, ErrorCode::InvalidArgument);
  for (int degree : {-1, kMaxPolynomialModeDegree + 1}) {
    WorldSettings wrong;
    wrong.fracture.polynomialModeDegree = degree;
    EXPECT_EQ(World::create(Pack(*sPack), wrong).error().code, ErrorCode::InvalidArgument) << degree;
  }
  WorldSettings negative;
  negative.fracture.meshRatioMaxDof = -1;
  EXPECT_EQ(World::create(Pack(*sPack), negative).error().code, ErrorCode::InvalidArgument);
}

// The exact path's budget per impact: the largest candidates first, each while the total stays
// within it; the others are matched and say why. The same choice on every run.
TEST_F(WorldTest, TheExactPathsBudgetGoesToTheLargestPiecesFirst) {
  auto run = [&](int budget) {
    WorldSettings settings;
    settings.fracture.exactModesMaxTets = 1000000;  // every fragment that is not debris is a candidate
    settings.fracture.exactModesMaxDof = 0;
    settings.fracture.exactModesBudgetDof = budget;
    settings.fracture.exactModeCount = 4;
    World world = makeWorld(settings);
    auto hit = world.impact(ball(world.addObject({.asset = "plate"}).value(), 60.0));
    EXPECT_TRUE(hit && hit.value().broken);
    std::vector<int64_t> dof;  // per fragment: its own model's size, 0 where it is not exact
    for (const FragmentResult& f : hit.value().fragments) {
      dof.push_back(f.exactModes ? world.objectAsset(f.object).value()->modal.modes.rows() : 0);
    }
    return std::make_pair(std::move(hit).value(), dof);
  };
  const auto [all, allDof] = run(0);
  std::vector<size_t> exact;
  for (size_t i = 0; i < all.fragments.size(); ++i)
    if (all.fragments[i].exactModes) exact.push_back(i);
  ASSERT_GE(exact.size(), 2u);
  const size_t largest = *std::max_element(exact.begin(), exact.end(), [&](size_t a, size_t b) { return allDof[a] < allDof[b]; });
  // A budget of the largest piece alone: it, and nothing else, takes the exact path.
  const auto [one, oneDof] = run(static_cast<int>(allDof[largest]));
  ASSERT_EQ(one.fragments.size(), all.fragments.size());  // the same fracture: only the new objects differ
  for (size_t i : exact) {
    const FragmentResult& f = one.fragments[i];
    if (i == largest) {
      EXPECT_TRUE(f.exactModes);
      EXPECT_EQ(oneDof[i], allDof[i]);
      EXPECT_TRUE(f.reason.empty()) << f.reason;
      continue;
    }
    EXPECT_FALSE(f.exactModes);
    EXPECT_EQ(f.path, FragmentPath::Matched);
    EXPECT_NE(f.reason.find("exactModesBudgetDof = " + std::to_string(allDof[largest]) + " (" +
                            std::to_string(allDof[largest]) + " given to larger pieces)"),
              std::string::npos)
        << f.reason;
  }
  // A budget under every piece: all matched; and the same choice on a second run.
  const auto [none, noneDof] = run(1);
  for (size_t i : exact) {
    EXPECT_EQ(none.fragments[i].path, FragmentPath::Matched);
    EXPECT_NE(none.fragments[i].reason.find("past exactModesBudgetDof = 1 (0 given"), std::string::npos) << none.fragments[i].reason;
  }
  EXPECT_EQ(run(static_cast<int>(allDof[largest])).second, oneDof);
  WorldSettings bad;
  bad.fracture.exactModesBudgetDof = -1;
  EXPECT_EQ(World::create(Pack(*sPack), bad).error().code, ErrorCode::InvalidArgument);
}

TEST_F(WorldTest, ExactPathFragmentsHaveTheirOwnModesAndBreakAgainWithoutADatabase) {
  WorldSettings settings;
  settings.fracture.exactModesMaxTets = 1000000;  // every fragment that is not debris
  settings.fracture.exactModesBudgetDof = 0;
  World world = makeWorld(settings, false);
  auto first = world.impact(ball(world.addObject({.asset = "plate"}).value(), 60.0));
  ASSERT_TRUE(first && first.value().broken);
  const FragmentResult* target = nullptr;
  int exact = 0;
  for (const FragmentResult& f : first.value().fragments) {
    EXPECT_EQ(f.exactModes, !f.debris && f.object.valid());
    EXPECT_EQ(f.matchedEntry, -1);
    if (!f.exactModes) continue;
    ++exact;
    // Its own mesh is the fragment's solid: the volume its surface encloses.
    const ObjectAsset& a = *world.objectAsset(f.object).value();
    EXPECT_NEAR(a.massProperties.volumeM3, f.massProperties.volumeM3, 1e-9 * f.massProperties.volumeM3);
    EXPECT_GT(a.modal.frequenciesHz[0], 0.0);
    EXPECT_LT(a.modal.residuals.maxCoeff(), 1e-6);
    if (!target || f.massProperties.volumeM3 > target->massProperties.volumeM3) target = &f;
  }
  ASSERT_GE(exact, 2);
  const Eigen::VectorXd targetHz = world.objectAsset(target->object).value()->modal.frequenciesHz;
  // The largest breaks again when hit hard at its highest node.
  const Points& nodes = world.objectAsset(target->object).value()->tetMesh.nodes;
  Eigen::Index top;
  nodes.col(2).maxCoeff(&top);
  ImpactDesc again = ball(target->object, 200.0);
  again.pointWorld = nodes.row(top).transpose();
  auto second = world.impact(again);
  ASSERT_TRUE(second) << second.error().message;
  EXPECT_TRUE(second.value().broken);

  // Deterministic: the same world gives the same fragments and the same modes.
  World other = makeWorld(settings, false);
  auto repeat = other.impact(ball(other.addObject({.asset = "plate"}).value(), 60.0));
  ASSERT_TRUE(repeat);
  EXPECT_EQ(hashFragments(repeat.value()), hashFragments(first.value()));
  const auto same = static_cast<size_t>(target - first.value().fragments.data());
  EXPECT_EQ(other.objectAsset(repeat.value().fragments[same].object).value()->modal.frequenciesHz, targetHz);
}

TEST_F(WorldTest, FastImpactsSkipTheFactorisationButUseACorrectionThatIsScheduled) {
  // A matched fragment's K is factorised on the workers once its body is made (as a pack
  // object's when it is placed), so a fast impact uses it from the first hit. Without background
  // preparation a fragment's first hit factorises it: a fast first hit skips it and uses the
  // truncated modes alone; once it exists, fast hits use it.
  for (const bool background : {false, true}) {
    SCOPED_TRACE(background ? "prepared in the background" : "prepared on the first hit");
    WorldSettings settings;
    settings.prepareInBackground = background;
    settings.fracture.reportUncorrectedPeak = true;
    // The entry's own frequencies: at its fragment's own, lower ones this soft hit peaks in the
    // ring-down after the contact, where the correction adds nothing, and a corrected peak could
    // not be told from an uncorrected one.
    settings.fracture.polynomialModeDegree = 0;
    World world = makeWorld(settings);
    auto broken = world.impact(ball(world.addObject({.asset = "plate"}).value(), 60.0));
    ASSERT_TRUE(broken && broken.value().broken);
    const ImpactDesc soft = softHitOnTheLargestMatched(world, broken.value());
    ASSERT_TRUE(soft.object.valid());
    ImpactDesc fast = soft;
    fast.fast = true;
    auto first = world.impact(fast);
    ASSERT_TRUE(first) << first.error().message;
    ASSERT_FALSE(first.value().broken);
    EXPECT_EQ(first.value().staticCorrectionUsed, background);
    auto full = world.impact(soft);  // factorises K unless the workers have
    ASSERT_TRUE(full);
    EXPECT_TRUE(full.value().staticCorrectionUsed);
    EXPECT_NE(full.value().peakPrincipalStressPa, full.value().peakWithoutCorrectionPa);
    // Without the correction, the fast first hit is the full hit's truncated modes alone.
    EXPECT_EQ(first.value().peakPrincipalStressPa,
              background ? full.value().peakPrincipalStressPa : full.value().peakWithoutCorrectionPa);
    auto later = world.impact(fast);  // the correction exists now: a fast impact uses it
    ASSERT_TRUE(later);
    EXPECT_TRUE(later.value().staticCorrectionUsed);
    EXPECT_EQ(later.value().peakPrincipalStressPa, full.value().peakPrincipalStressPa);
  }
}

// A matched fragment's static correction is its entry's placed (WorldSettings::shareEntryCorrections)
// or its own factorisation: the same soft hit on the same fragment reads the same corrected peak
// within float rounding either way, and every matched fragment's correction is there once its body is.
TEST_F(WorldTest, AMatchedFragmentsSharedEntryCorrectionEqualsItsOwnFactorisation) {
  std::vector<double> peaks, compliances;
  for (const bool share : {true, false}) {
    SCOPED_TRACE(share ? "the entry's correction placed" : "the fragment's own factorisation");
    WorldSettings settings;
    settings.shareEntryCorrections = share;
    World world = makeWorld(settings);
    auto broken = world.impact(ball(world.addObject({.asset = "plate"}).value(), 60.0));
    ASSERT_TRUE(broken && broken.value().broken);
    const auto& fragments = broken.value().fragments;
    EXPECT_GE(std::count_if(fragments.begin(), fragments.end(), [](const FragmentResult& f) { return f.path == FragmentPath::Matched; }), 2);
    ImpactDesc soft = softHitOnTheLargestMatched(world, broken.value());
    ASSERT_TRUE(soft.object.valid());
    soft.fast = true;  // uses the correction only if it was scheduled: it must be, both ways
    auto hit = world.impact(soft);
    ASSERT_TRUE(hit) << hit.error().message;
    ASSERT_FALSE(hit.value().broken);
    EXPECT_TRUE(hit.value().staticCorrectionUsed);
    peaks.push_back(hit.value().peakPrincipalStressPa);
  }
  // Two factorisations whose L the corrections keep rounded to float (CorrectionStorage::Float):
  // rounding apart: 5.3e-9 measured, the same on every machine (1e-9 before float storage).
  EXPECT_NEAR(peaks[0] / peaks[1], 1.0, 2e-8);
}

// Entries' corrections factorised at placement (prepareEntryCorrections) are the ones a matched
// fragment would otherwise factorise on first use, and an entry dropped from a full cache
// (entryCacheCapacity) is built again to the same bits: the break, and a hit on its largest
// matched piece, are the same bits every way.
TEST_F(WorldTest, EntryCorrectionsFactorisedAtPlacementChangeNoBits) {
  std::vector<uint64_t> prints;
  for (const auto& [prepare, kept] : {std::pair{0, 256}, std::pair{1000, 0}, std::pair{0, 1}}) {
    SCOPED_TRACE(prepare ? "every entry factorised at placement" : kept == 1 ? "one entry kept" : "each entry on first use");
    WorldSettings settings;
    settings.prepareEntryCorrections = prepare;
    settings.entryCacheCapacity = kept;
    World world = makeWorld(settings);
    const ObjectId plate = world.addObject({.asset = "plate"}).value();
    ASSERT_TRUE(world.waitUntilPrepared());
    // Placement did the work, or none of it (one material: one correction per entry).
    const auto entries = static_cast<int32_t>(sPack->database.entries.size());
    ASSERT_GT(entries, 0);
    EXPECT_EQ(world.entryCorrectionsBuilt(), prepare ? entries : 0);
    auto broken = world.impact(ball(plate, 60.0));
    ASSERT_TRUE(broken && broken.value().broken);
    ImpactDesc soft = softHitOnTheLargestMatched(world, broken.value());
    ASSERT_TRUE(soft.object.valid());
    soft.fast = true;  // the correction is used only where it was scheduled: it is, both ways
    auto hit = world.impact(soft);
    ASSERT_TRUE(hit) << hit.error().message;
    EXPECT_TRUE(hit.value().staticCorrectionUsed);
    prints.push_back(fingerprint(broken.value()));
    prints.push_back(fingerprint(hit.value()));
    if (!prepare) {
      EXPECT_GT(world.entryCorrectionsBuilt(), 0);  // the hit on a matched piece built its entry's
    }
  }
  EXPECT_EQ(prints[0], prints[2]);
  EXPECT_EQ(prints[1], prints[3]);
  EXPECT_EQ(prints[0], prints[4]);
  EXPECT_EQ(prints[1], prints[5]);
  WorldSettings bad;
  bad.prepareEntryCorrections = -1;
  EXPECT_EQ(World::create(Pack(*sPack), bad).error().code, ErrorCode::InvalidArgument);
  bad.prepareEntryCorrections = 0;
  bad.entryCacheCapacity = -1;
  EXPECT_EQ(World::create(Pack(*sPack), bad).error().code, ErrorCode::InvalidArgument);
  bad.entryCacheCapacity = 8;
  bad.prepareEntryCorrections = 9;  // prepared only to be dropped
  EXPECT_EQ(World::create(Pack(*sPack), bad).error().code, ErrorCode::InvalidArgument);
}

// A World over a pack read on demand (EntryReading::OnDemand, as `brittle impact`, `play`, `view`
// and `bench impact` read theirs) reads each entry when it is matched: the same fractures, the
// same matched bodies, to the bit, as over the pack read whole.
TEST_F(WorldTest, AWorldReadingEntriesOnDemandBreaksToTheSameBits) {
  const auto path = testing::makeTempDir("world-on-demand") / "pack.h5";
  ASSERT_TRUE(writePack(*sPack, path));
  std::vector<uint64_t> prints;
  for (EntryReading reading : {EntryReading::Whole, EntryReading::OnDemand}) {
    SCOPED_TRACE(reading == EntryReading::Whole ? "whole" : "on demand");
    auto pack = readPack(path, reading);
    ASSERT_TRUE(pack) << pack.error().message;
    EXPECT_EQ(pack.value().database.entrySource != nullptr, reading == EntryReading::OnDemand);
    WorldSettings settings;
    settings.prepareEntryCorrections = 4;  // read in the background at placement, the rest when matched
    auto world = World::create(std::move(pack).value(), settings);
    ASSERT_TRUE(world) << world.error().message;
    const ObjectId plate = world.value().addObject({.asset = "plate"}).value();
    ASSERT_TRUE(world.value().waitUntilPrepared());
    auto broken = world.value().impact(ball(plate, 60.0));
    ASSERT_TRUE(broken && broken.value().broken);
    ImpactDesc soft = softHitOnTheLargestMatched(world.value(), broken.value());  // its body made from its entry
    ASSERT_TRUE(soft.object.valid());
    auto hit = world.value().impact(soft);
    ASSERT_TRUE(hit) << hit.error().message;
    prints.push_back(fingerprint(broken.value()));
    prints.push_back(fingerprint(hit.value()));
  }
  EXPECT_EQ(prints[0], prints[2]);
  EXPECT_EQ(prints[1], prints[3]);
}

// A World over a pack read on demand with one entry damaged (one chunk of its stress modes): the
// plate still breaks the same way, the pieces matched to that entry have the read's typed error
// for a body, the pieces matched to other entries have theirs, and the plate breaks again.
TEST_F(WorldTest, ADamagedEntryFailsOnlyTheBodiesMatchedToIt) {
  const auto dir = testing::makeTempDir("world-damaged");
  ASSERT_TRUE(writePack(*sPack, dir / "pack.h5"));
  auto breakPlate = [&](const std::filesystem::path& path) {
    auto pack = readPack(path, EntryReading::OnDemand);
    EXPECT_TRUE(pack) << pack.error().message;
    auto world = World::create(std::move(pack).value(), {});
    EXPECT_TRUE(world) << world.error().message;
    World w = std::move(world).value();
    auto broken = w.impact(ball(w.addObject({.asset = "plate"}).value(), 60.0));
    EXPECT_TRUE(broken && broken.value().broken);
    return std::pair{std::move(w), std::move(broken).value()};
  };
  // The entry to damage: one the plate's pieces are matched to, long enough to hold a whole chunk
  // of its own, so that no other entry shares the damage.
  const uint64_t chunk = testing::chunkRows(dir / "pack.h5", "/database/entries/stress_modes");
  ASSERT_GT(chunk, 0u);
  int32_t damagedEntry = -1;
  uint64_t damagedRow = 0;
  {
    auto [w, clean] = breakPlate(dir / "pack.h5");
    for (const FragmentResult& f : clean.fragments) {
      if (f.path != FragmentPath::Matched || damagedEntry >= 0) continue;
      if (auto first = testing::stressChunkInsideEntry(sPack->database, static_cast<size_t>(f.matchedEntry), chunk)) {
        damagedEntry = f.matchedEntry;
        damagedRow = *first;
      }
    }
  }
  ASSERT_GE(damagedEntry, 0) << "no matched entry spans a whole chunk";
  std::filesystem::copy_file(dir / "pack.h5", dir / "damaged.h5");
  ASSERT_TRUE(testing::damageChunk(dir / "damaged.h5", "/database/entries/stress_modes", damagedRow));
  ASSERT_FALSE(readPack(dir / "damaged.h5"));  // read whole, the pack is refused

  auto [w, broken] = breakPlate(dir / "damaged.h5");
  int failed = 0, made = 0;
  for (const FragmentResult& f : broken.fragments) {
    if (f.path != FragmentPath::Matched) continue;
    auto asset = w.objectAsset(f.object);
    if (f.matchedEntry != damagedEntry) {
      EXPECT_TRUE(asset) << "entry " << f.matchedEntry << ": " << asset.error().message;
      made += asset.ok();
      continue;
    }
    ++failed;
    ASSERT_FALSE(asset);
    EXPECT_EQ(asset.error().code, ErrorCode::PackCorrupt) << asset.error().message;
    ImpactDesc d = ball(f.object, 1.0);
    d.pointToleranceM = 1.0;  // wherever the piece lies: its body is what fails
    auto hit = w.impact(d);
    ASSERT_FALSE(hit);
    EXPECT_EQ(hit.error().code, ErrorCode::PackCorrupt) << hit.error().message;
  }
  EXPECT_GT(failed, 0);
  EXPECT_GT(made, 0) << "every piece was matched to the damaged entry: the test shows nothing";
  auto again = w.impact(ball(w.addObject({.asset = "plate"}).value(), 60.0));
  ASSERT_TRUE(again) << again.error().message;
  EXPECT_TRUE(again.value().broken);
}

TEST_F(WorldTest, BadInputsGiveTypedErrorsNeverCrashes) {
  World world = makeWorld({}, false);
  auto id = world.addObject({.asset = "plate"});
  ASSERT_TRUE(id);
  auto expectBad = [&](ImpactDesc d, const char* what) {
    auto r = world.impact(d);
    ASSERT_FALSE(r) << what;
    EXPECT_EQ(r.error().code, ErrorCode::InvalidArgument) << what;
  };
  ImpactDesc d = ball(id.value(), 5.0);
  d.pointWorld.x() = std::nan("");
  expectBad(d, "NaN point");
  d = ball(id.value(), 0.0);
  expectBad(d, "zero speed");
  d = ball(id.value(), 5.0);
  d.pointWorld = Eigen::Vector3d(3, 0, 0);
  expectBad(d, "far point");
  d = ball(id.value(), 5.0);
  d.normalWorld = Eigen::Vector3d(0, 0, 0);
  expectBad(d, "zero normal");
  expectBad(ball(ObjectId{}, 5.0), "invalid id");
  expectBad(ball(ObjectId{77, 0}, 5.0), "unknown id");
  ASSERT_TRUE(world.removeObject(id.value()));
  expectBad(ball(id.value(), 5.0), "stale id");
  EXPECT_FALSE(world.removeObject(id.value()));
  EXPECT_FALSE(world.addObject({.asset = "teapot"}));
  ObjectDesc skew{.asset = "plate"};
  skew.rotation(0, 1) = 0.5;
  EXPECT_FALSE(world.addObject(skew));
  WorldSettings bad;
  bad.fracture.pulseSteps = 1;
  EXPECT_EQ(World::create(Pack{}, bad).error().code, ErrorCode::InvalidArgument);
  WorldSettings tiny;
  tiny.maxObjects = 1;
  World small = World::create(Pack(*sPack), tiny).value();
  ASSERT_TRUE(small.addObject({.asset = "plate"}));
  EXPECT_EQ(small.addObject({.asset = "plate"}).error().code, ErrorCode::CapacityExceeded);
}

TEST_F(WorldTest, PosesMoveTheImpactWithTheObject) {
  World world = makeWorld({}, false);
  const Eigen::Matrix3d rot = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  const Eigen::Vector3d shift(4, -2, 1);
  auto moved = world.addObject({.asset = "plate", .rotation = rot, .translationM = shift});
  auto still = world.addObject({.asset = "plate"});
  ImpactDesc a = ball(still.value(), 2.0), b = ball(moved.value(), 2.0);
  b.pointWorld = rot * a.pointWorld + shift;
  b.normalWorld = rot * a.normalWorld;
  auto ra = world.impact(a), rb = world.impact(b);
  ASSERT_TRUE(ra && rb);
  EXPECT_NEAR(ra.value().peakPrincipalStressPa, rb.value().peakPrincipalStressPa, 1e-9 * ra.value().peakPrincipalStressPa);
}

TEST_F(WorldTest, SubmittedImpactsGiveTheSameFractureAsImpactOnAnyWorkerCount) {
  // Three plates hit in turn: synchronously, then submitted all at once and collected in the same
  // order, on one and on two workers. Same seed and calls: same fragments, same new ids.
  const double speeds[] = {60.0, 2.0, 40.0};
  struct Run {
    std::vector<uint64_t> hashes;
    std::vector<std::vector<ObjectId>> ids;
    std::vector<double> peaks;
  };
  auto record = [](Run& run, const ImpactResult& r) {
    run.hashes.push_back(hashFragments(r));
    run.peaks.push_back(r.peakPrincipalStressPa);
    run.ids.emplace_back();
    for (const FragmentResult& f : r.fragments) run.ids.back().push_back(f.object);
  };
  Run sync;
  {
    World world = makeWorld();
    std::vector<ObjectId> plates;
    for (int i = 0; i < 3; ++i) plates.push_back(world.addObject({.asset = "plate"}).value());
    for (int i = 0; i < 3; ++i) {
      auto r = world.impact(ball(plates[static_cast<size_t>(i)], speeds[i]));
      ASSERT_TRUE(r) << r.error().message;
      record(sync, r.value());
    }
  }
  ASSERT_TRUE(sync.ids[0].size() >= 2 && sync.ids[2].size() >= 2);
  for (int workers : {1, 2, 3}) {
    WorldSettings settings;
    settings.workerThreads = workers;
    World world = makeWorld(settings);
    std::vector<ObjectId> plates;
    for (int i = 0; i < 3; ++i) plates.push_back(world.addObject({.asset = "plate"}).value());
    std::vector<ImpactTicket> tickets;
    for (int i = 0; i < 3; ++i) {
      auto t = world.submitImpact(ball(plates[static_cast<size_t>(i)], speeds[i]));
      ASSERT_TRUE(t) << t.error().message;
      tickets.push_back(t.value());
    }
    EXPECT_EQ(world.pendingImpacts(), 3);
    Run async;
    ImpactResult result;
    for (ImpactTicket t : tickets) {
      ASSERT_TRUE(world.collectImpact(t, result));
      EXPECT_TRUE(world.impactReady(t) == false);  // collected: unknown now
      record(async, result);
    }
    EXPECT_EQ(world.pendingImpacts(), 0);
    EXPECT_EQ(async.hashes, sync.hashes) << workers << " workers";
    EXPECT_EQ(async.peaks, sync.peaks) << workers << " workers";
    EXPECT_EQ(async.ids, sync.ids) << workers << " workers";
  }
}

// Every piece of a break struck at once, right after it: most bodies are not made yet, so those
// impacts wait for their bodies on the background threads (ahead of their queue) before they go to
// the workers, where impacts on bodies already made do not queue behind them. They break as the
// same impacts do once every body is made, and a World dropped with them pending ends cleanly.
TEST_F(WorldTest, PiecesStruckBeforeTheirBodiesAreMadeBreakAsOnceTheyAre) {
  struct Run {
    std::vector<uint64_t> hashes;
    std::vector<double> peaks;
    int broken = 0;
  };
  // prepared: wait for every body before the hits; collect: false drops the World with them pending.
  auto run = [&](bool prepared, bool collect) {
    WorldSettings settings;
    settings.workerThreads = 2;  // two background threads on any machine
    World world = makeWorld(settings);
    Run out;
    auto ticket = world.submitImpact(ball(world.addObject({.asset = "plate"}).value(), 60.0));
    EXPECT_TRUE(ticket);
    ImpactResult broken;
    EXPECT_TRUE(world.collectImpact(ticket.value(), broken));
    if (prepared) {
      EXPECT_TRUE(world.waitUntilPrepared());
    }
    std::vector<ImpactTicket> hits;
    for (const FragmentResult& f : broken.fragments) {
      if (f.path != FragmentPath::Matched) continue;
      Eigen::Index top;
      f.surface.vertices.col(2).maxCoeff(&top);
      ImpactDesc hit = ball(f.object, 30.0);
      hit.pointWorld = f.surface.vertices.row(top).transpose();
      hit.pointToleranceM = 1.0;
      auto t = world.submitImpact(hit);
      EXPECT_TRUE(t) << t.error().message;
      if (t) hits.push_back(t.value());
    }
    EXPECT_GE(hits.size(), 3u);
    if (!collect) return out;
    ImpactResult r;
    for (ImpactTicket t : hits) {
      EXPECT_TRUE(world.collectImpact(t, r));
      out.hashes.push_back(hashFragments(r));
      out.peaks.push_back(r.peakPrincipalStressPa);
      out.broken += r.broken ? 1 : 0;
    }
    return out;
  };
  const Run made = run(true, true);
  const Run struckAtOnce = run(false, true);
  EXPECT_GE(made.broken, 1);
  EXPECT_EQ(struckAtOnce.hashes, made.hashes);
  EXPECT_EQ(struckAtOnce.peaks, made.peaks);
  (void)run(false, false);  // returns: the World waited for its pending impacts and their bodies
}

// A World closed while its background work and submitted impacts run (a placement's factorisation,
// the pieces' bodies, impacts waiting for them) stops them at their next cancellation point instead
// of running them to their end (Cancellation.h; the time it takes is measured in docs/realtime.md,
// "A World destroyed without waiting"). What must hold: closing never fails or crashes at any of
// those moments (the sanitizer suite runs this), and nothing of a closed World's stays behind in the
// threads it used (a cancellation flag left set on a oneTBB worker would fail the next World's
// impacts): a World made after them breaks the plate into the reference's bits.
TEST_F(WorldTest, AWorldClosedWhileItsWorkRunsStopsItAndTheNextWorldBreaksAlike) {
  auto fracture = [&] {
    WorldSettings settings;
    settings.workerThreads = 2;
    World world = makeWorld(settings);
    auto r = world.impact(ball(world.addObject({.asset = "plate"}).value(), 60.0));
    EXPECT_TRUE(r && r.value().broken);
    return r ? hashFragments(r.value()) : 0;
  };
  const uint64_t reference = fracture();
  for (int stage = 0; stage < 4; ++stage) {
    WorldSettings settings;
    settings.workerThreads = 2;
    World world = makeWorld(settings);
    auto id = world.addObject({.asset = "plate"});  // its preparation starts on a background thread
    ASSERT_TRUE(id);
    if (stage == 0) continue;  // closed while it is prepared
    auto ticket = world.submitImpact(ball(id.value(), 60.0));
    ASSERT_TRUE(ticket);
    if (stage == 1) continue;  // closed while the impact waits for the preparation or runs
    ImpactResult broken;
    ASSERT_TRUE(world.collectImpact(ticket.value(), broken));
    ASSERT_TRUE(broken.broken);
    if (stage == 2) continue;  // closed while the pieces' bodies are made
    for (const FragmentResult& f : broken.fragments) {  // closed with impacts waiting for those bodies
      if (f.path != FragmentPath::Matched) continue;
      ImpactDesc hit = ball(f.object, 30.0);
      hit.pointWorld = f.surface.vertices.row(0).transpose();
      hit.pointToleranceM = 1.0;
      EXPECT_TRUE(world.submitImpact(hit));
    }
  }
  EXPECT_EQ(fracture(), reference);
}

// Removing a fragment, or breaking it, abandons its versions not made yet (its checks, its
// escalation, its own analysis): their background jobs are skipped or stopped (BodySource::abandon).
// Those jobs share per-entry values with the other pieces' (an entry's placement, its static
// correction), which a stopped job leaves unmade for the next to make: the pieces left get every
// version bit for bit as in a world where nothing was removed.
TEST_F(WorldTest, RemovedAndBrokenPiecesVersionsAreAbandonedAndTheOthersKeepTheirBits) {
  auto breakPlate = [&](World& world) {
    ImpactDesc hit = ball(world.addObject({.asset = "plate"}).value(), 60.0);
    hit.timeS = 1.0;
    auto r = world.impact(hit);
    EXPECT_TRUE(r && r.value().broken);
    return r ? std::move(r).value() : ImpactResult{};
  };
  WorldSettings settings;
  settings.workerThreads = 2;
  World reference = makeWorld(settings);
  World world = makeWorld(settings);
  const ImpactResult kept = breakPlate(reference);
  const ImpactResult broken = breakPlate(world);
  ASSERT_EQ(hashFragments(broken), hashFragments(kept));
  // At once, while the pieces' bodies and versions are made: every other matched piece removed,
  // one broken again.
  std::vector<size_t> left;
  int removed = 0, rebroken = 0;
  for (size_t i = 0; i < broken.fragments.size(); ++i) {
    const FragmentResult& f = broken.fragments[i];
    if (f.path != FragmentPath::Matched) continue;
    if (rebroken == 0 && !std::isnan(f.checkDueS)) {
      ImpactDesc hit = ball(f.object, 120.0);
      hit.pointWorld = f.surface.vertices.row(0).transpose();
      hit.pointToleranceM = 1.0;
      hit.timeS = 1.01;
      auto again = world.impact(hit);
      ASSERT_TRUE(again) << again.error().message;
      rebroken += again.value().broken;
      if (again.value().broken) continue;
    }
    if ((i % 2) == 0) {
      ASSERT_TRUE(world.removeObject(f.object));
      ++removed;
    } else {
      left.push_back(i);
    }
  }
  EXPECT_GT(removed, 0);
  EXPECT_EQ(rebroken, 1);
  ASSERT_FALSE(left.empty());
  ASSERT_TRUE(world.waitUntilPrepared());
  ASSERT_TRUE(reference.waitUntilPrepared());
  for (size_t i : left) {
    for (double t : {1.0, 1.3, 10.0}) {  // the first body, the checks, the last version
      auto mine = world.objectAsset(broken.fragments[i].object, t);
      auto theirs = reference.objectAsset(kept.fragments[i].object, t);
      ASSERT_TRUE(mine && theirs);
      EXPECT_EQ(mine.value()->modal.frequenciesHz, theirs.value()->modal.frequenciesHz) << i << " at " << t << " s";
      EXPECT_EQ(mine.value()->stressModes, theirs.value()->stressModes) << i << " at " << t << " s";
    }
  }
}

TEST_F(WorldTest, APendingObjectStaysAsItWasAndRefusesOtherCalls) {
  World world = makeWorld();
  const ObjectId id = world.addObject({.asset = "plate"}).value();
  auto ticket = world.submitImpact(ball(id, 60.0));
  ASSERT_TRUE(ticket) << ticket.error().message;
  EXPECT_TRUE(world.isAlive(id));
  EXPECT_EQ(world.impact(ball(id, 5.0)).error().code, ErrorCode::InvalidArgument);
  EXPECT_EQ(world.submitImpact(ball(id, 5.0)).error().code, ErrorCode::InvalidArgument);
  EXPECT_EQ(world.removeObject(id).error().code, ErrorCode::InvalidArgument);
  ImpactResult r;
  ASSERT_TRUE(world.collectImpact(ticket.value(), r));
  EXPECT_TRUE(r.broken);
  EXPECT_FALSE(world.isAlive(id));
  EXPECT_EQ(world.collectImpact(ticket.value(), r).error().code, ErrorCode::InvalidArgument);  // collected once
  EXPECT_EQ(world.collectImpact(ImpactTicket{}, r).error().code, ErrorCode::InvalidArgument);
  EXPECT_FALSE(world.impactReady(ImpactTicket{12345}));
  WorldSettings one;
  one.maxPendingImpacts = 1;
  World limited = makeWorld(one);
  const ObjectId a = limited.addObject({.asset = "plate"}).value(), b = limited.addObject({.asset = "plate"}).value();
  ASSERT_TRUE(limited.submitImpact(ball(a, 1.0)));
  EXPECT_EQ(limited.submitImpact(ball(b, 1.0)).error().code, ErrorCode::CapacityExceeded);
}

TEST_F(WorldTest, AFailedImpactLeavesTheWorldAsItWas) {
  // On a worker: a point off the surface is found by the contact stage; the error reaches the
  // caller and the object is no longer pending.
  World world = makeWorld();
  const ObjectId id = world.addObject({.asset = "plate"}).value();
  ImpactDesc off = ball(id, 60.0);
  off.pointWorld = Eigen::Vector3d(3, 0, 0);
  auto ticket = world.submitImpact(off);
  ASSERT_TRUE(ticket);
  ImpactResult r;
  const Status failed = world.collectImpact(ticket.value(), r);
  ASSERT_FALSE(failed);
  EXPECT_EQ(failed.error().code, ErrorCode::InvalidArgument);
  EXPECT_TRUE(world.isAlive(id));
  EXPECT_TRUE(world.impact(ball(id, 1.0)));
  // Fragments that do not fit in maxObjects: the impact fails as a whole, the plate stays.
  WorldSettings tiny;
  tiny.maxObjects = 1;
  World small = makeWorld(tiny);
  const ObjectId plate = small.addObject({.asset = "plate"}).value();
  const Status full = small.impact(ball(plate, 60.0), r);
  ASSERT_FALSE(full);
  EXPECT_EQ(full.error().code, ErrorCode::CapacityExceeded);
  EXPECT_NE(full.error().message.find("maxObjects"), std::string::npos) << full.error().message;
  EXPECT_TRUE(small.isAlive(plate));
  EXPECT_EQ(small.objectCount(), 1);
  EXPECT_TRUE(small.impact(ball(plate, 1.0)));
  // More fragments than maxFragmentsPerImpact: the same, caught before the surfaces are built.
  World reference = makeWorld();  // the same first impact, uncapped
  const size_t made = reference.impact(ball(reference.addObject({.asset = "plate"}).value(), 60.0)).value().fragments.size();
  ASSERT_GT(made, 2u);
  WorldSettings few;
  few.maxFragmentsPerImpact = 2;
  World capped = makeWorld(few);
  const ObjectId capPlate = capped.addObject({.asset = "plate"}).value();
  const Status over = capped.impact(ball(capPlate, 60.0), r);
  ASSERT_FALSE(over);
  EXPECT_EQ(over.error().code, ErrorCode::CapacityExceeded);
  EXPECT_NE(over.error().message.find("maxFragmentsPerImpact"), std::string::npos) << over.error().message;
  EXPECT_TRUE(capped.isAlive(capPlate));
  few.maxFragmentsPerImpact = 1;
  EXPECT_EQ(World::create(Pack{}, few).error().code, ErrorCode::InvalidArgument);
}

// The host's hook on the workers: called once per submitted impact that was computed, before it
// is ready, with the fragments collectImpact then returns; not called for impact(); a hook that
// throws fails the impact, which leaves the object as it was.
TEST_F(WorldTest, TheComputedHookSeesEachSubmittedResultBeforeItIsReady) {
  struct Seen {
    std::mutex mutex;
    std::map<uint64_t, std::vector<double>> volumes;  // per ticket: the fragments' volumes
  };
  auto seen = std::make_shared<Seen>();
  WorldSettings settings;
  settings.onImpactComputed = [seen](ImpactTicket t, const ImpactResult& r) {
    std::vector<double> v;
    for (const FragmentResult& f : r.fragments) v.push_back(f.massProperties.volumeM3);
    std::lock_guard<std::mutex> lock(seen->mutex);
    EXPECT_TRUE(seen->volumes.emplace(t.id, std::move(v)).second) << "called twice for ticket " << t.id;
  };
  World world = makeWorld(settings);
  const ObjectId a = world.addObject({.asset = "plate"}).value(), b = world.addObject({.asset = "plate"}).value();
  auto ta = world.submitImpact(ball(a, 60.0));
  auto tb = world.submitImpact(ball(b, 1.0));  // does not break: called all the same
  ASSERT_TRUE(ta && tb);
  // Once impactReady says so, the hook has run already (before collectImpact is called).
  for (const ImpactTicket t : {ta.value(), tb.value()}) {
    while (!world.impactReady(t)) std::this_thread::yield();
    std::lock_guard<std::mutex> lock(seen->mutex);
    EXPECT_EQ(seen->volumes.count(t.id), 1u) << "ticket " << t.id << " is ready before its hook ran";
  }
  ImpactResult ra, rb;
  ASSERT_TRUE(world.collectImpact(ta.value(), ra));
  ASSERT_TRUE(world.collectImpact(tb.value(), rb));
  ASSERT_TRUE(ra.broken);
  EXPECT_FALSE(rb.broken);
  {
    std::lock_guard<std::mutex> lock(seen->mutex);
    ASSERT_EQ(seen->volumes.size(), 2u);
    const std::vector<double>& va = seen->volumes.at(ta.value().id);
    ASSERT_EQ(va.size(), ra.fragments.size());
    for (size_t i = 0; i < va.size(); ++i) EXPECT_EQ(va[i], ra.fragments[i].massProperties.volumeM3);
    EXPECT_TRUE(seen->volumes.at(tb.value().id).empty());
  }
  const ObjectId c = world.addObject({.asset = "plate"}).value();
  ASSERT_TRUE(world.impact(ball(c, 60.0)));
  EXPECT_EQ(seen->volumes.size(), 2u);

  WorldSettings throwing;
  throwing.onImpactComputed = [](ImpactTicket, const ImpactResult&) { throw std::runtime_error("host hook failed"); };
  World failing = makeWorld(throwing);
  const ObjectId d = failing.addObject({.asset = "plate"}).value();
  auto td = failing.submitImpact(ball(d, 60.0));
  ASSERT_TRUE(td);
  ImpactResult rd;
  const Status st = failing.collectImpact(td.value(), rd);
  ASSERT_FALSE(st);
  EXPECT_NE(st.error().message.find("host hook failed"), std::string::npos) << st.error().message;
  EXPECT_TRUE(failing.isAlive(d));
  EXPECT_EQ(failing.objectCount(), 1);
}

TEST_F(WorldTest, EveryFragmentSaysWhatItBecameAndWhy) {
  auto check = [&](World world, FragmentPath expected, const char* reason) {
    auto r = world.impact(ball(world.addObject({.asset = "plate"}).value(), 60.0));
    ASSERT_TRUE(r && r.value().broken);
    int debris = 0;
    for (const FragmentResult& f : r.value().fragments) {
      if (f.debris) {
        EXPECT_EQ(f.path, FragmentPath::Debris);
        ++debris;
        continue;
      }
      if (expected == FragmentPath::SurfaceOnly) {
        EXPECT_EQ(f.path, FragmentPath::SurfaceOnly);
        EXPECT_FALSE(f.object.valid());
        EXPECT_NE(f.reason.find(reason), std::string::npos) << f.reason;
      } else {
        EXPECT_TRUE(f.path == FragmentPath::ExactModes || f.path == FragmentPath::Matched) << fragmentPathName(f.path);
        EXPECT_TRUE(f.object.valid());
        EXPECT_EQ(f.path == FragmentPath::ExactModes, f.exactModes);
        EXPECT_EQ(f.path == FragmentPath::Matched, f.matchedEntry >= 0);
      }
    }
    EXPECT_LT(debris, static_cast<int>(r.value().fragments.size()));
  };
  check(makeWorld(), FragmentPath::Matched, "");
  WorldSettings noExact;
  noExact.fracture.exactModesMaxTets = 0;
  check(makeWorld(noExact, false), FragmentPath::SurfaceOnly, "no database");
  WorldSettings off;
  off.fracture.matchFragments = false;
  check(makeWorld(off), FragmentPath::SurfaceOnly, "matchFragments is off");
  EXPECT_EQ(fragmentPathName(FragmentPath::ExactModes), "exact_modes");
}

TEST_F(WorldTest, BackgroundPreparationChangesNothingButWhereTheWorkRuns) {
  auto peak = [&](bool background) {
    WorldSettings s;
    s.prepareInBackground = background;
    World world = makeWorld(s, false);
    auto r = world.impact(ball(world.addObject({.asset = "plate"}).value(), 2.0));
    EXPECT_TRUE(r && r.value().staticCorrectionUsed);
    return r ? r.value().peakPrincipalStressPa : 0.0;
  };
  EXPECT_EQ(peak(true), peak(false));
}

// Eigen blocks its products by the cache sizes it reads from the CPU, and products blocked
// otherwise round otherwise: a World pins them (EigenBlocking.h), so that a machine with other
// caches, or a host that set its own, breaks the plate into the same bits. The sizes below are a
// 48 KB / 2 MB / 260 MB Xeon's, a 32 KB / 512 KB / 16 MB EPYC-like machine's and a small one's;
// without the pin the first two gave the main job's plate impact two fingerprints.
TEST_F(WorldTest, TheSameFractureWhateverCacheSizesEigenWasGiven) {
  struct Caches {
    std::ptrdiff_t l1, l2, l3;
  };
  std::vector<uint64_t> prints, bodies;
  for (const Caches c : {Caches{48 << 10, 2 << 20, 260 << 20}, Caches{32 << 10, 512 << 10, 16 << 20}, Caches{16 << 10, 64 << 10, 1 << 20}}) {
    SCOPED_TRACE(std::to_string(c.l1) + " / " + std::to_string(c.l2) + " / " + std::to_string(c.l3) + " bytes");
    Eigen::setCpuCacheSizes(c.l1, c.l2, c.l3);  // as the host's machine, or the host itself, had them
    World world = makeWorld();
    EXPECT_EQ(Eigen::l1CacheSize(), kEigenBlockingL1);
    EXPECT_EQ(Eigen::l2CacheSize(), kEigenBlockingL2);
    EXPECT_EQ(Eigen::l3CacheSize(), kEigenBlockingL3);
    const ObjectId plate = world.addObject({.asset = "plate"}).value();
    auto broken = world.impact(ball(plate, 60.0));
    ASSERT_TRUE(broken && broken.value().broken);
    prints.push_back(fingerprint(broken.value()));
    // The new bodies too: their modal data, made on the workers.
    Fingerprint made;
    for (const FragmentResult& f : broken.value().fragments) {
      if (!f.object.valid()) continue;
      auto asset = world.objectAsset(f.object);
      ASSERT_TRUE(asset) << asset.error().message;
      made.add(asset.value()->modal.modes);
      made.add(asset.value()->modal.frequenciesHz);
    }
    bodies.push_back(made.value());
  }
  EXPECT_EQ(prints[0], prints[1]);
  EXPECT_EQ(prints[0], prints[2]);
  EXPECT_EQ(bodies[0], bodies[1]);
  EXPECT_EQ(bodies[0], bodies[2]);
}

}  // namespace
}  // namespace brittle
