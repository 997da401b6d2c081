// The player on the default scenes with a small pack baked once (the default manifest's objects
// with fewer tets, and an 8-entry database): each scene breaks something, plays bit-identically
// twice, keeps every body above the floor, and gains no mechanical energy outside fracture events.
#include "brittle/player/Player.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>

#include "brittle/player/Scene.h"
#include "brittle/precompute/BakePipeline.h"
#include "brittle/precompute/BaseShapes.h"
#include "brittle/precompute/FragmentDatabaseBake.h"
#include "brittle/testing/Fixtures.h"

namespace brittle {
namespace {

class PlayerTest : public ::testing::TestWithParam<const char*> {
 protected:
  static void SetUpTestSuite() {
    auto manifest = loadBakeManifest(testing::sourceDir() / "assets" / "default-pack.json");
    ASSERT_TRUE(manifest) << manifest.error().message;
    std::vector<ObjectBakeSettings> objects = std::move(manifest).value();
    // Fewer tets than the default pack, except the vase, whose thin wall needs its 8000.
    for (ObjectBakeSettings& o : objects) {
      if (o.name == "glass-plate") o.tetMesh.targetTets = 3000;
      if (o.name == "brick" || o.name == "stone-ball") o.tetMesh.targetTets = 400;
      o.modal.modeCount = 12;
    }
    auto pack = bakePack(objects);
    ASSERT_TRUE(pack) << pack.error().message;
    sPack = new Pack(std::move(pack).value());
    DatabaseBakeSettings db;
    db.shapes = selectBaseShapes(loadBaseShapes(testing::sourceDir() / "assets" / "shapes" / "base-shapes.json").value(),
                                 {"box", "plate", "wedge", "blob"})
                    .value();
    db.entryCount = 8;
    db.tetMesh.targetTets = 300;
    db.modeCount = 6;
    auto database = bakeFragmentDatabase(db);
    ASSERT_TRUE(database) << database.error().message;
    sPack->database = std::move(database).value();
  }
  static void TearDownTestSuite() { delete sPack; }
  static inline Pack* sPack = nullptr;

  static Scene scene(const std::string& name) {
    auto s = loadScene(testing::sourceDir() / "assets" / "scenes" / (name + ".json"));
    EXPECT_TRUE(s) << s.error().message;
    return s.value();
  }

  static PlayResult play(const Scene& s, PlayerSettings settings = {}) {
    auto r = playScene(*sPack, s, settings);
    EXPECT_TRUE(r) << r.error().message;
    return std::move(r).value();
  }
};

TEST_P(PlayerTest, BreaksDeterministicallyAboveTheFloorWithoutGainingEnergy) {
  ASSERT_NE(sPack, nullptr);
  const Scene s = scene(GetParam());
  const PlayResult a = play(s), b = play(s);
  std::printf("%s: %lld impacts, %lld breaks, %lld deferred, %lld refused, %d bodies at end, hash %016llx\n", GetParam(),
              static_cast<long long>(a.impacts), static_cast<long long>(a.breaks), static_cast<long long>(a.deferredImpacts),
              static_cast<long long>(a.failedImpacts), a.bodiesAtEnd, static_cast<unsigned long long>(a.poseHash));
  EXPECT_GE(a.breaks, 1);
  EXPECT_EQ(a.poseHash, b.poseHash);
  EXPECT_EQ(a.bodiesAtEnd, b.bodiesAtEnd);
  EXPECT_EQ(a.impacts, b.impacts);
  EXPECT_GT(a.bodiesAtEnd, static_cast<int32_t>(s.objects.size() + s.impactors.size()));

  // No tunnelling: every body, alive or broken, ends above the floor (less Bullet's penetration
  // slop and the collision margin).
  const double floor = s.floor->heightM;
  for (const BodyState& body : a.bodies) EXPECT_GE(body.lowestPointM, floor - 0.01) << body.name;

  // Energy: E = Σ ½mv² + ½ωᵀIω − m g·x over the dynamic bodies after each frame (FrameStats).
  // Between two fracture events (a fracture replaces a body by fragments with new velocities, and
  // may hand an impactor its velocity back), E may never rise above its lowest value since the
  // last fracture by more than 1 % of the largest kinetic energy of the run (Bullet's contact
  // solver is not exactly dissipative; measured: ≤ 0.01 %).
  double peakKinetic = 0.0;
  for (const FrameStats& f : a.frameStats) peakKinetic = std::max(peakKinetic, f.kineticJ);
  const double tolerance = 0.01 * peakKinetic + 1e-6;
  double reference = a.frameStats.front().energyJ, worst = 0.0;
  for (size_t i = 1; i < a.frameStats.size(); ++i) {
    const FrameStats& f = a.frameStats[i];
    if (f.fractured) {
      reference = f.energyJ;
      continue;
    }
    worst = std::max(worst, f.energyJ - reference);
    EXPECT_LE(f.energyJ, reference + tolerance) << "frame " << f.frame;
    reference = std::min(reference, f.energyJ);
  }
  std::printf("  largest energy gain outside fractures %.3g J (tolerance %.3g J)\n", worst, tolerance);
}

INSTANTIATE_TEST_SUITE_P(DefaultScenes, PlayerTest,
                         ::testing::Values("plate-drop", "ball-through-pane", "brick-stack", "vase-drop"),
                         [](const auto& p) {
                           std::string n = p.param;
                           std::replace(n.begin(), n.end(), '-', '_');
                           return n;
                         });

TEST(PlayerErrorsTest, UnknownAssetAndBadSettingsAreTyped) {
  Pack empty;
  Scene s;
  s.objects.push_back({.name = "x", .asset = "no-such-object"});
  auto r = playScene(empty, s);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().code, ErrorCode::InvalidArgument);
  EXPECT_NE(r.error().message.find("no-such-object"), std::string::npos);
  PlayerSettings bad;
  bad.maxImpactsPerStep = 0;
  EXPECT_EQ(validatePlayerSettings(bad).error().code, ErrorCode::InvalidArgument);
  bad = {};
  bad.impactThresholdMps = -1.0;
  EXPECT_FALSE(validatePlayerSettings(bad));
}

}  // namespace
}  // namespace brittle
