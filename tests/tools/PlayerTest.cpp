// The player on the default scenes with a small pack baked once (the default manifest's objects
// with fewer tets, and an 8-entry database): each scene breaks something, plays bit-identically
// twice, keeps every body above the floor, and gains no mechanical energy outside fracture events.
#include "brittle/player/Player.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <tuple>
#include <set>
#include <cstdio>
#include <memory>
#include <tiny_gltf.h>

#include "brittle/player/GltfReplay.h"
#include "brittle/player/Scene.h"
#include "brittle/precompute/BakeManifest.h"
#include "brittle/precompute/BakePipeline.h"
#include "brittle/precompute/BaseShapes.h"
#include "brittle/precompute/FragmentDatabaseBake.h"
#include "brittle/testing/DatabaseFixtures.h"
#include "brittle/testing/Fixtures.h"

namespace brittle {
namespace {

// The small pack, baked once for the process (both suites use it).
const Pack* smallPack() {
  static const std::unique_ptr<Pack> pack = [] {
    std::unique_ptr<Pack> p;
    auto manifest = loadBakeManifest(testing::sourceDir() / "assets" / "default-pack.json");
    EXPECT_TRUE(manifest) << manifest.error().message;
    if (!manifest) return p;
    std::vector<ObjectBakeSettings> objects = std::move(manifest).value();
    // Fewer tets than the default pack, except the vase, whose thin wall needs 8000 in P1. Every
    // object is P1 here: Mesh_3 makes the plate's 7.4k tets at any smaller target, and the
    // player's behaviour is what these suites test, not the element (P2 bodies in the player:
    // WorldP2Test, the main job's scenes).
    for (ObjectBakeSettings& o : objects) {
      o.elementOrder = ElementOrder::P1;
      if (o.name == "glass-plate") o.tetMesh.targetTets = 3000;
      if (o.name == "brick" || o.name == "stone-ball") o.tetMesh.targetTets = 800;
      if (o.name == "porcelain-vase") o.tetMesh.targetTets = 8000;
      o.modal.modeCount = 12;
    }
    auto baked = bakePack(objects);
    EXPECT_TRUE(baked) << baked.error().message;
    if (!baked) return p;
    auto database = bakeFragmentDatabase(testing::shippedShapesDatabase({"box", "plate", "wedge", "blob"}, 8, 300, 6));
    EXPECT_TRUE(database) << database.error().message;
    if (!database) return p;
    p = std::make_unique<Pack>(std::move(baked).value());
    p->database = std::move(database).value();
    return p;
  }();
  return pack.get();
}

Scene defaultScene(const std::string& name) {
  auto s = loadScene(testing::sourceDir() / "assets" / "scenes" / (name + ".json"));
  EXPECT_TRUE(s) << s.error().message;
  return s.value();
}

PlayResult play(const Scene& s, PlayerSettings settings = {}) {
  auto r = playScene(*smallPack(), s, settings);
  EXPECT_TRUE(r) << r.error().message;
  return std::move(r).value();
}

// A default scene played with the default settings, once per process (the player tests run in
// one): plays are deterministic (PlayerTest plays each scene twice and compares the bits), so the
// tests below that compare other settings against the default share its play.
const PlayResult& defaultPlay(const std::string& name) {
  static std::map<std::string, PlayResult> plays;
  auto it = plays.find(name);
  if (it == plays.end()) it = plays.emplace(name, play(defaultScene(name))).first;
  return it->second;
}

// Each default scene, with its fracture applied at once (latency 0, on the player's thread) and
// two frames after the contact (computed on the World's workers meanwhile).
class PlayerTest : public ::testing::TestWithParam<std::tuple<const char*, int>> {
 protected:
  static void SetUpTestSuite() { smallPack(); }
};

TEST_P(PlayerTest, BreaksDeterministicallyAboveTheFloorWithoutGainingEnergy) {
  ASSERT_NE(smallPack(), nullptr);
  const Scene s = defaultScene(std::get<0>(GetParam()));
  PlayerSettings settings;
  settings.fractureLatencyFrames = std::get<1>(GetParam());
  const PlayResult a = play(s, settings), b = play(s, settings);
  std::printf("%s, latency %d: %lld impacts, %lld breaks, %lld deferred, %lld refused, %d bodies at end, hash %016llx\n",
              std::get<0>(GetParam()), settings.fractureLatencyFrames,
              static_cast<long long>(a.impacts), static_cast<long long>(a.breaks), static_cast<long long>(a.deferredImpacts),
              static_cast<long long>(a.failedImpacts), a.bodiesAtEnd, static_cast<unsigned long long>(a.poseHash));
  EXPECT_GE(a.breaks, 1);
  EXPECT_EQ(a.poseHash, b.poseHash);
  // Every result takes effect exactly `latency` frames after its contact (or not before the end).
  for (const ImpactEvent& e : a.events) {
    if (e.appliedFrame >= 0) EXPECT_EQ(e.appliedFrame, e.frame + settings.fractureLatencyFrames);
    else EXPECT_GT(e.frame + settings.fractureLatencyFrames, a.frames - 1);
  }
  EXPECT_EQ(a.bodiesAtEnd, b.bodiesAtEnd);
  EXPECT_EQ(a.impacts, b.impacts);
  EXPECT_GT(a.bodiesAtEnd, static_cast<int32_t>(s.objects.size() + s.impactors.size()));
  // Every live breakable body counted once by the source of its frequencies; the same in both runs.
  int32_t sources = 0, breakable = 0;
  for (const auto& [name, count] : a.frequencySourcesAtEnd) sources += count;
  for (const BodyState& body : a.bodies)
    if ((body.kind == BodyKind::Object || body.kind == BodyKind::Fragment) && body.lastFrame < 0) ++breakable;
  EXPECT_EQ(a.frequencySourcesAtEnd.size(), 5u);
  EXPECT_EQ(a.frequencySourcesAtEnd, b.frequencySourcesAtEnd);
  EXPECT_GT(sources, 0);
  EXPECT_LE(sources, breakable);

  // No tunnelling: every body, alive or broken, ends above the floor (less Bullet's penetration
  // slop and the collision margin).
  const double floor = s.floor->heightM;
  for (const BodyState& body : a.bodies) EXPECT_GE(body.lowestPointM, floor - 0.01) << body.name;
  // Fragments' collision hulls keep at most hullMaxVertices vertices (and at least a tetrahedron's).
  for (const BodyState& body : a.bodies) {
    if (body.kind == BodyKind::Impactor) continue;
    EXPECT_GE(body.hullVertices, 4) << body.name;
    if (body.kind != BodyKind::Object) {
      EXPECT_LE(body.hullVertices, settings.hullMaxVertices) << body.name;
    }
  }

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
                         ::testing::Combine(::testing::Values("plate-drop", "ball-through-pane", "brick-stack", "vase-drop"),
                                            ::testing::Values(0, 2)),
                         [](const auto& p) {
                           std::string n = std::get<0>(p.param);
                           std::replace(n.begin(), n.end(), '-', '_');
                           return n + "_latency" + std::to_string(std::get<1>(p.param));
                         });

// A static pane broken late still lets the ball through: at the frame its fragments appear, the
// ball is put back where it touched with its velocity from before, so it ends on the far side at
// any latency, near where it ends when the pane breaks at once (it meets the same fragments).
TEST(PlayerLatencyTest, TheBallGoesThroughThePaneWhateverTheLatency) {
  ASSERT_NE(smallPack(), nullptr);
  const Scene s = defaultScene("ball-through-pane");
  auto ballEnd = [&](int latency) {
    PlayerSettings settings;
    settings.fractureLatencyFrames = latency;
    const PlayResult r = play(s, settings);
    EXPECT_GE(r.breaks, 1) << latency;
    for (const BodyState& b : r.bodies)
      if (b.kind == BodyKind::Impactor) return b.translationsM.back();
    return Eigen::Vector3d(Eigen::Vector3d::Constant(std::nan("")));
  };
  const Eigen::Vector3d now = ballEnd(0);
  ASSERT_GT(now.y(), 0.2);  // through the pane (y = 0) and on
  for (int latency : {1, 4}) {
    const Eigen::Vector3d late = ballEnd(latency);
    EXPECT_GT(late.y(), 0.2) << latency;
    EXPECT_NEAR(late.y(), now.y(), 0.1) << latency;
  }
  PlayerSettings bad;
  bad.fractureLatencyFrames = -2;
  EXPECT_EQ(validatePlayerSettings(bad).error().code, ErrorCode::InvalidArgument);
  // Automatic: 33 ms of play, 8 of the scene's 240 Hz frames.
  const PlayResult& automatic = defaultPlay("ball-through-pane");
  ASSERT_FALSE(automatic.events.empty());
  EXPECT_EQ(automatic.events.front().appliedFrame - automatic.events.front().frame, 8);
}

// A result is collected as soon as its work is done (its hulls then built on a worker) or at its
// frame, whichever comes first; which one depends on the machine's speed and must not change the
// play. Paced in wall time with two workers, results are mostly ready early; unpaced with one, the
// play reaches each frame first and waits.
TEST(PlayerLatencyTest, ThePlayIsTheSameWhetherResultsLandEarlyOrAtTheirFrame) {
  ASSERT_NE(smallPack(), nullptr);
  const Scene s = defaultScene("ball-through-pane");
  PlayerSettings waiting;
  waiting.world.workerThreads = 1;
  PlayerSettings paced;
  paced.realTime = true;
  paced.world.workerThreads = 2;
  const PlayResult a = play(s, waiting), b = play(s, paced);
  EXPECT_GE(a.breaks, 1);
  EXPECT_EQ(a.poseHash, b.poseHash);
  EXPECT_EQ(a.impacts, b.impacts);
  EXPECT_EQ(a.breaks, b.breaks);
  EXPECT_EQ(a.bodiesAtEnd, b.bodiesAtEnd);
  ASSERT_EQ(a.events.size(), b.events.size());
  for (size_t i = 0; i < a.events.size(); ++i) EXPECT_EQ(a.events[i].appliedFrame, b.events[i].appliedFrame) << i;
}

// Capped collision hulls: the exact hulls of the pane's fragments have more vertices than the cap
// (so the cap does something), the capped ones keep at most the cap, and the ball still goes
// through the pane.
TEST(PlayerHullTest, FragmentHullsKeepAtMostTheCap) {
  ASSERT_NE(smallPack(), nullptr);
  const Scene s = defaultScene("ball-through-pane");
  auto largestHull = [&](int cap) {
    PlayerSettings settings;
    settings.hullMaxVertices = cap;
    const PlayResult r = play(s, settings);
    EXPECT_GE(r.breaks, 1) << cap;
    int32_t largest = 0;
    for (const BodyState& b : r.bodies)
      if (b.kind == BodyKind::Fragment || b.kind == BodyKind::Debris) largest = std::max(largest, b.hullVertices);
    return largest;
  };
  const int32_t exact = largestHull(0);
  std::printf("largest fragment hull: %d vertices exact, capped at 16 and 24\n", exact);
  EXPECT_GT(exact, 24);
  EXPECT_LE(largestHull(24), 24);
  EXPECT_LE(largestHull(16), 16);
}

// The replay: every body is a node, and every node is animated over the whole run (translation,
// rotation, scale); a fragment is scaled to zero before it exists, and its parent after it broke.
TEST(PlayerReplayTest, EveryFragmentNodeIsAnimatedOverItsLifetime) {
  ASSERT_NE(smallPack(), nullptr);
  PlayerSettings settings;
  settings.recordTracks = true;
  const PlayResult r = play(defaultScene("ball-through-pane"), settings);
  ASSERT_GE(r.breaks, 1);
  EXPECT_EQ(r.poseHash, defaultPlay("ball-through-pane").poseHash);  // recording changes nothing
  const auto path = testing::makeTempDir("replay") / "replay.glb";
  const Status written = writeGltfReplay(r, path);
  ASSERT_TRUE(written) << written.error().message;

  tinygltf::Model model;
  tinygltf::TinyGLTF loader;
  std::string err, warn;
  ASSERT_TRUE(loader.LoadBinaryFromFile(&model, &err, &warn, path.string())) << err;
  ASSERT_EQ(model.animations.size(), 1u);
  const tinygltf::Animation& anim = model.animations[0];
  const auto floats = [&](int accessor) {
    const tinygltf::Accessor& a = model.accessors[static_cast<size_t>(accessor)];
    const tinygltf::BufferView& v = model.bufferViews[static_cast<size_t>(a.bufferView)];
    const auto* p = reinterpret_cast<const float*>(model.buffers[0].data.data() + v.byteOffset + a.byteOffset);
    return std::vector<float>(p, p + v.byteLength / sizeof(float));
  };
  int fragments = 0;
  for (const BodyState& b : r.bodies) {
    int node = -1;
    for (size_t n = 0; n < model.nodes.size(); ++n)
      if (model.nodes[n].name == b.name) node = static_cast<int>(n);
    ASSERT_GE(node, 0) << b.name;
    std::set<std::string> paths;
    for (const tinygltf::AnimationChannel& c : anim.channels) {
      if (c.target_node != node) continue;
      paths.insert(c.target_path);
      const tinygltf::AnimationSampler& sampler = anim.samplers[static_cast<size_t>(c.sampler)];
      EXPECT_EQ(model.accessors[static_cast<size_t>(sampler.input)].count, static_cast<size_t>(r.frames + 1));
      if (c.target_path != "scale") continue;
      const std::vector<float> scale = floats(sampler.output);
      ASSERT_EQ(scale.size(), 3u * static_cast<size_t>(r.frames + 1));
      const int64_t last = b.lastFrame < 0 ? r.frames : b.lastFrame;
      for (int64_t k = 0; k <= r.frames; ++k) {
        const bool alive = k >= b.firstFrame && k <= last;
        EXPECT_EQ(scale[static_cast<size_t>(3 * k)], alive ? 1.0f : 0.0f) << b.name << " sample " << k;
      }
    }
    EXPECT_EQ(paths, (std::set<std::string>{"translation", "rotation", "scale"})) << b.name;
    if (b.kind == BodyKind::Fragment || b.kind == BodyKind::Debris) {
      ++fragments;
      EXPECT_GT(b.firstFrame, 0) << b.name;
      EXPECT_GE(model.nodes[static_cast<size_t>(node)].mesh, 0) << b.name;
    }
  }
  EXPECT_GE(fragments, 2);
}

// The cap on impacts per step: in the brick stack the ball and the top brick hit each other in
// the same step; with one impact per step the slower waits (counted), and is computed next step.
TEST(PlayerCapTest, ImpactsAboveTheCapWaitAndAreCounted) {
  ASSERT_NE(smallPack(), nullptr);
  const Scene s = defaultScene("brick-stack");
  PlayerSettings capped;
  capped.maxImpactsPerStep = 1;
  const PlayResult& free = defaultPlay("brick-stack");
  const PlayResult one = play(s, capped);
  EXPECT_EQ(free.deferredImpacts, 0);
  EXPECT_GE(one.deferredImpacts, 1);
  std::map<int64_t, int> perFrameStep;
  for (const ImpactEvent& e : one.events) ++perFrameStep[static_cast<int64_t>(std::llround(e.timeS / (s.timeStepS / s.substeps)))];
  for (const auto& [step, count] : perFrameStep) EXPECT_LE(count, 1) << "step " << step;
  EXPECT_GE(one.breaks, 1);
}

// The frame budget: with a budget no impact can meet, every impact after a frame's first waits
// (counted) until it has waited maxBudgetWaits steps, then runs simplified; none is dropped, so
// every body that was hit still gets its impact.
TEST(PlayerBudgetTest, ImpactsBeyondTheBudgetWaitThenRunSimplified) {
  ASSERT_NE(smallPack(), nullptr);
  const Scene s = defaultScene("brick-stack");
  PlayerSettings tight;
  tight.fractureBudgetS = 1e-12;
  tight.maxBudgetWaits = 2;
  const PlayResult& free = defaultPlay("brick-stack");
  const PlayResult budget = play(s, tight);
  EXPECT_EQ(free.budgetDeferredImpacts, 0);
  EXPECT_EQ(free.simplifiedImpacts, 0);
  EXPECT_GE(budget.budgetDeferredImpacts, 2);
  EXPECT_GE(budget.simplifiedImpacts, 1);
  int simplified = 0;
  for (const ImpactEvent& e : budget.events) {
    if (!e.simplified) continue;
    ++simplified;
    EXPECT_GE(e.waitedSteps, tight.maxBudgetWaits);
  }
  EXPECT_EQ(simplified, budget.simplifiedImpacts);
  EXPECT_GE(budget.impacts, 1);
  EXPECT_GE(budget.breaks, 1);
  PlayerSettings bad;
  bad.fractureBudgetS = -1.0;
  EXPECT_EQ(validatePlayerSettings(bad).error().code, ErrorCode::InvalidArgument);
  bad = {};
  bad.maxBudgetWaits = -1;
  EXPECT_EQ(validatePlayerSettings(bad).error().code, ErrorCode::InvalidArgument);
}

// The session the viewer drives: frame by frame it gives playScene's poses, and a thrown sphere
// becomes a body (bad throws are typed errors).
TEST(PlaySessionTest, SteppingGivesPlaySceneAndThrowsAddBodies) {
  ASSERT_NE(smallPack(), nullptr);
  const Scene s = defaultScene("plate-drop");
  const PlayResult whole = play(s);
  auto session = PlaySession::create(*smallPack(), s);
  ASSERT_TRUE(session) << session.error().message;
  PlaySession& p = *session.value();
  EXPECT_EQ(p.frameCount(), whole.frames);
  while (p.frame() < p.frameCount()) p.stepFrame();
  EXPECT_EQ(p.progress().impacts, whole.impacts);
  const PlayResult stepped = p.finish();
  EXPECT_EQ(stepped.poseHash, whole.poseHash);
  EXPECT_EQ(stepped.breaks, whole.breaks);

  auto again = PlaySession::create(*smallPack(), s);
  ASSERT_TRUE(again);
  PlaySession& q = *again.value();
  const size_t before = q.bodies().size();
  RigidImpactor ball;
  ball.radiusM = 0.02;
  ball.massKg = 0.2;
  ball.positionWorldM = Eigen::Vector3d(0.0, 0.0, 1.5);
  ball.velocityMps = Eigen::Vector3d(0.0, 0.0, -10.0);
  ASSERT_TRUE(q.throwSphere(ball));
  EXPECT_EQ(q.bodies().size(), before + 1);
  EXPECT_EQ(q.bodies().back().kind, BodyKind::Impactor);
  q.stepFrame();
  RigidImpactor bad = ball;
  bad.radiusM = 0.0;
  EXPECT_EQ(q.throwSphere(bad).error().code, ErrorCode::InvalidArgument);
  bad = ball;
  bad.velocityMps.x() = std::nan("");
  EXPECT_EQ(q.throwSphere(bad).error().code, ErrorCode::InvalidArgument);
  bad = ball;
  bad.shape = ImpactorShape::Box;
  EXPECT_EQ(q.throwSphere(bad).error().code, ErrorCode::InvalidArgument);
  bad = ball;
  bad.material = "cheese";
  EXPECT_EQ(q.throwSphere(bad).error().code, ErrorCode::UnknownMaterial);
  EXPECT_EQ(q.bodies().size(), before + 1);
}

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
  bad = {};
  bad.hullMaxVertices = 3;  // not even a tetrahedron
  EXPECT_EQ(validatePlayerSettings(bad).error().code, ErrorCode::InvalidArgument);
}

}  // namespace
}  // namespace brittle
