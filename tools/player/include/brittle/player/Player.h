// Player.h — plays a scene: a Bullet rigid-body simulation whose hard contacts become runtime
// impacts, and whose broken bodies are replaced by their fragments.
//
//   auto scene = loadScene("assets/scenes/plate-drop.json");
//   auto played = playScene(std::move(pack), scene.value(), PlayerSettings{});   // Result<PlayResult>
//
// Bullet is the double-precision build (bullet-float64); no Bullet type appears in this header.
//
// Each frame runs `substeps` fixed Bullet steps (single thread, one internal step per call, so the
// same pack, scene, settings and seed give bit-identical poses). After each step, every contact of
// a breakable body whose normal approach speed, from the velocities before the step, exceeds
// impactThresholdMps becomes a World impact at the contact point with the body's outward normal,
// the other body's mass (+∞ if static), radius (sphere radius, +∞ for a box, plane or hull) and
// material (a flat face on a flat impactor, which has no Hertz contact, takes the body's size as
// its radius: ImpactDesc::flatPairRadiusM). One impact per body per step (its fastest contact); at most
// maxImpactsPerStep per step (fastest first, ties by body); the rest wait for the next step and
// each wait is counted in deferredImpacts. A body that was hit ignores contacts for cooldownS
// (its fragments inherit what is left of it). A broken body leaves Bullet, and each fragment enters as a new body with a convex hull
// of its surface, its exact mass properties (principal axes) and the parent's velocity at its
// centre of mass (v + ω × r); matched fragments keep their new ObjectId and can break again, debris
// never break. A static body cannot take an impactor's momentum: when one breaks, the body that hit
// it gets its velocity from before the step back (it goes through; it meets the fragments next
// step). A dynamic body that breaks keeps the collision Bullet solved (its fragments inherit it).
// Bodies born in the same step whose bounding boxes overlap (convex hulls of concave fragments do)
// do not collide with each other until their boxes have separated once: Bullet would otherwise
// push them apart with energy out of nothing.
//
// Fracture off the frame (fractureLatencyFrames = L ≥ 1, the default): an impact found in frame F
// is submitted to the World (World::submitImpact) and computed on its workers while the play goes
// on. The struck body stays a rigid body in Bullet (it bounces as one) and takes no other impact;
// at the start of frame F + L its result is collected (waiting only if the work is not done: the
// wait is part of that frame's fractureS and of the event's waitS) and, if it broke, it is replaced
// by its fragments at its pose and velocity then. If it was static, the body that hit it is put
// back where it touched, with the velocities it had before the contact, so that it goes through
// and meets the fragments as it would have, L frames later. Because the frame of application is
// fixed, a play is bit-identical whatever the machine's speed. L = 0: each impact is computed in the
// step that found it, on the player's thread, as before.
//
// Frames: the world's z axis is up; the floor is the plane z = height. Bodies are placed by their
// asset's local origin (the pack's mesh frame); Bullet bodies live in principal axes at the centre
// of mass, and the player keeps the offset.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "brittle/database/Pack.h"
#include "brittle/core/Result.h"
#include "brittle/player/Scene.h"
#include "brittle/runtime/World.h"

namespace brittle {

struct PlayerSettings {
  double impactThresholdMps = 0.5;  ///< a contact approaching faster than this is an impact
  double cooldownS = 0.05;          ///< a body ignores contacts this long after an impact
  int maxImpactsPerStep = 4;        ///< impacts computed per step; the others wait (deferred)
  /// Wall-clock budget per frame for fracture (contact scan, impacts, new bodies), s; 0: none.
  /// Once a frame has spent it, its remaining impacts wait for the next step, fastest first
  /// (counted in budgetDeferredImpacts). An impact that has waited maxBudgetWaits steps runs
  /// anyway, simplified: ImpactDesc::fast, no factorisation of K on a first hit (counted in
  /// simplifiedImpacts). Nothing is dropped. A wall-clock budget makes the play depend on the
  /// machine's speed; without it (the default) a play is deterministic.
  double fractureBudgetS = 0.0;
  int maxBudgetWaits = 4;
  /// Frames from an impact's contact to its fracture taking effect (see above); 0: at once, on the
  /// player's thread; −1 (the default): the frames nearest to 33 ms of play (two 60 Hz frames; 8
  /// of the default scenes' 240 Hz frames), at least one. That is the time a worker has for an
  /// impact before the play waits for it; a person does not see a break 33 ms late.
  int fractureLatencyFrames = -1;
  double frictionCoefficient = 0.5;
  double collisionMarginM = 0.001;  ///< Bullet's margin around hulls and boxes
  /// Most vertices of a fragment's collision hull; 0: the exact hull of its surface. Bullet's
  /// narrow phase walks a hull's vertices for every support point, so a pile of fragments with
  /// exact hulls (about 60 vertices, up to 144, on the pane) costs most of a frame, and the exact
  /// hulls of a shattered pane's dense surfaces cost ~80 ms to build. The capped hull is the
  /// surface's extreme vertex in each of hullMaxVertices fixed directions of the fragment's
  /// principal frame: it lies inside the exact hull, touches it in those directions, and costs a
  /// pass over the vertices per direction. The scene's own objects keep their exact hulls: their
  /// first contacts are the scene's main impacts, and where they touch decides how they break.
  int hullMaxVertices = 24;
  /// Fraction of a body's size the contact point may lie off its surface in the runtime: Bullet's
  /// hull is convex and the surface need not be. A matched fragment's runtime shape is its database
  /// entry, not its exact surface, and can lie farther off: the runtime takes a point up to such a
  /// body's whole size off whatever this says (ImpactDesc::pointToleranceM).
  double pointToleranceFraction = 0.5;
  bool recordTracks = false;        ///< keep every body's pose per frame (for a replay)
  /// Paced as a host would be: each frame starts no earlier than its time in the play (frame ×
  /// time step of wall time after the first), so that workers get the wall time a real-time host
  /// gives them between an impact and its application. Frame times exclude the sleep. Results do
  /// not change; only how long the play takes.
  bool realTime = false;
  /// world.seed is replaced by the scene's seed. The player factorises up to 256 database entries'
  /// corrections when an object is placed (WorldSettings::prepareEntryCorrections), so that a
  /// shattering break does not queue an entry factorisation per matched piece.
  WorldSettings world = [] {
    WorldSettings w;
    w.prepareEntryCorrections = 256;
    return w;
  }();
};

/// Range checks: threshold > 0, cooldown ≥ 0, maxImpactsPerStep ≥ 1, fractureBudgetS ≥ 0,
/// maxBudgetWaits ≥ 0, fractureLatencyFrames in [−1, 600], friction ≥ 0, margin in
/// (0, 0.05], hullMaxVertices 0 or in [8, 4096], tolerance fraction in (0, 1], and validateWorldSettings. Error: InvalidArgument.
Status validatePlayerSettings(const PlayerSettings& settings);

enum class BodyKind { Object, Fragment, Debris, Impactor };
std::string_view bodyKindName(BodyKind kind);

/// One impact handed to the runtime.
struct ImpactEvent {
  double timeS = 0.0;
  int64_t frame = 0;
  int32_t body = -1;             ///< player body index (BodyState::index)
  std::string object;            ///< the body's name: the scene name, "+fN" per fragment generation
  int32_t otherBody = -1;        ///< −1: the floor
  double speedMps = 0.0;         ///< normal approach speed
  double otherMassKg = 0.0;      ///< +∞: static
  bool broken = false;
  int32_t fragments = 0;         ///< 0 unless broken
  int32_t debris = 0;            ///< how many of them are rigid debris
  double peakPrincipalStressPa = 0.0;
  StageTimes times;              ///< the runtime's stages
  std::string error;             ///< non-empty: the runtime refused the impact (counted, not fatal)
  int32_t waitedSteps = 0;       ///< steps it waited (impact cap or frame budget)
  bool simplified = false;       ///< run fast (ImpactDesc::fast) after waiting maxBudgetWaits steps
  bool staticCorrection = false; ///< the runtime used the static correction
  int32_t modesUsed = 0;         ///< the runtime's modes for this impact
  /// The frame at whose start the result was applied (frame + latency); −1 if the play ended first.
  /// With fractureLatencyFrames = 0, the contact's own frame.
  int64_t appliedFrame = -1;
  double waitS = 0.0;            ///< wall time the play waited for the result when it was due
};

struct FrameStats {
  int64_t frame = 0;
  double timeS = 0.0;            ///< at the end of the frame
  int32_t bodies = 0;            ///< bodies in Bullet at the end of the frame (with impactors)
  double bulletS = 0.0;          ///< wall time in Bullet stepping
  double fractureS = 0.0;        ///< wall time in contact scanning, impacts and spawning fragments
  double energyJ = 0.0;          ///< Σ ½mv² + ½ωᵀIω − m g·x over dynamic bodies (x: centre of mass)
  double kineticJ = 0.0;         ///< Σ ½mv² + ½ωᵀIω alone
  bool fractured = false;        ///< a body broke (or an impactor was reset) in this frame
};

/// A body at the end, or over time with PlayerSettings::recordTracks.
struct BodyState {
  int32_t index = -1;            ///< in order of creation
  std::string name;
  BodyKind kind = BodyKind::Object;
  int32_t parent = -1;           ///< the body it broke from
  /// Samples: sample 0 is the start, sample k the end of frame k − 1. A fragment born in frame F
  /// exists from sample F + 1; a body broken in frame F exists until sample F.
  int64_t firstFrame = 0;        ///< its first sample
  int64_t lastFrame = -1;        ///< its last sample; −1: alive at the end
  bool isStatic = false;
  double massKg = 0.0;
  /// The body's surface in its own local frame (the pack mesh frame; for fragments the broken
  /// body's frame). Impactors: empty (shape described by impactor).
  TriangleMesh surface;
  RigidImpactor impactor;        ///< for kind == Impactor
  /// Pose of the local frame: world = rotation · local + translation. With recordTracks, one per
  /// sample from firstFrame to lastFrame (or the last sample); otherwise the last pose only.
  std::vector<Eigen::Quaterniond> rotations;
  std::vector<Eigen::Vector3d> translationsM;
  double lowestPointM = 0.0;     ///< lowest world z of its surface (or shape) at the end
  int32_t hullVertices = 0;      ///< vertices of its collision hull (impactors and the floor: 0)
};

struct PlayResult {
  std::string scene;
  uint64_t seed = 1;             ///< the World's seed (the scene's, or the player's override): the fracture history
  int64_t frames = 0;
  double timeStepS = 0.0;
  std::vector<ImpactEvent> events;
  std::vector<FrameStats> frameStats;
  std::vector<BodyState> bodies;  ///< every body that ever existed, by index
  int64_t impacts = 0;           ///< handed to the runtime
  int64_t breaks = 0;
  int64_t deferredImpacts = 0;   ///< waits of one step because of maxImpactsPerStep
  int64_t budgetDeferredImpacts = 0;  ///< waits of one step because the frame's fracture budget was spent
  int64_t simplifiedImpacts = 0; ///< impacts run fast after waiting maxBudgetWaits steps
  int64_t failedImpacts = 0;     ///< refused by the runtime (events with an error)
  int32_t bodiesAtEnd = 0;
  /// The breakable bodies alive at the end by where the frequencies an impact at the scene's last
  /// time would use come from (frequencySourceName: "own", "entry", "ritz", "checked",
  /// "checked_p2"; World::frequencyError), made if they were not: after the timed frames.
  std::map<std::string, int32_t> frequencySourcesAtEnd;
  uint64_t poseHash = 0;         ///< FNV-1a over the final poses of live bodies, by index
  double loadS = 0.0;            ///< building the World and the bodies
};

/// A live body, as a viewer draws it.
struct BodyView {
  int32_t index = -1;
  BodyKind kind = BodyKind::Object;
  std::string name;
  const TriangleMesh* surface = nullptr;     ///< local frame; null for impactors (valid until the next step)
  const RigidImpactor* impactor = nullptr;   ///< for impactors
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  ///< local → world
  Eigen::Vector3d translationM = Eigen::Vector3d::Zero();
};

/// A scene played one frame at a time (what playScene runs to the end, and what a viewer drives):
///
///   auto session = PlaySession::create(std::move(pack), scene, settings);   // Result<unique_ptr>
///   while (session.value()->frame() < session.value()->frameCount()) session.value()->stepFrame();
///   PlayResult r = session.value()->finish();
///
/// Stepping past frameCount() goes on (a viewer may run longer than the scene's duration).
class PlaySession {
 public:
  /// Errors: as playScene.
  static Result<std::unique_ptr<PlaySession>> create(Pack pack, const Scene& scene, const PlayerSettings& settings = {});
  ~PlaySession();
  PlaySession(const PlaySession&) = delete;
  PlaySession& operator=(const PlaySession&) = delete;

  FrameStats stepFrame();
  int64_t frame() const;        ///< frames played
  int64_t frameCount() const;   ///< the scene's duration in frames
  double timeS() const;         ///< frame() × the time step
  const Scene& scene() const;
  /// Counts and events so far (bodies and the pose hash come with finish()).
  const PlayResult& progress() const;
  std::vector<BodyView> bodies() const;
  /// Adds a sphere during the play (it takes part from the next frame). Errors: InvalidArgument
  /// (not a sphere, radius or mass not finite and > 0, non-finite pose or velocities),
  /// UnknownMaterial.
  Status throwSphere(const RigidImpactor& impactor);
  /// The result over the frames played; the session is spent afterwards.
  PlayResult finish();

 private:
  struct Impl;
  explicit PlaySession(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> mImpl;
};

/// Plays scene with the objects of pack. Errors: InvalidArgument (settings; a scene object whose
/// asset is not in the pack; a body Bullet cannot build), those of World::create and addObject.
/// Impacts the runtime refuses are counted (failedImpacts) and the play goes on.
Result<PlayResult> playScene(Pack pack, const Scene& scene, const PlayerSettings& settings = {});

/// Frame time statistics (bullet + fracture per frame), in seconds.
struct FrameTimeSummary {
  double medianS = 0.0, p99S = 0.0, maxS = 0.0;
  double bulletS = 0.0, fractureS = 0.0;  ///< totals
};
FrameTimeSummary summarizeFrameTimes(const std::vector<FrameStats>& frames);

}  // namespace brittle
