// Simulation.h — the play: a Bullet world of pack objects, fragments and impactors whose contacts
// become runtime impacts. Its parts live in one file each: Simulation.cpp (bodies and the frame
// loop), ContactScheduling.cpp (contacts → impacts submitted, collected and applied at a fixed
// latency), FragmentSpawning.cpp (a broken body's fragments as new bodies) and Recording.cpp
// (tracks, energy, lowest points). Private to the player.
#pragma once

#include <btBulletDynamicsCommon.h>

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "BulletBody.h"
#include "DebrisHulls.h"
#include "brittle/core/Timing.h"
#include "brittle/player/Player.h"

namespace brittle::play {

// A breakable body's contact in a step, in the body's local frame: a candidate impact. Sorted
// fastest first (ties: the lower body index), so the per-step cap keeps the hardest hits.
struct Candidate {
  int32_t body = -1, other = -1;
  double speedMps = 0.0;
  Eigen::Vector3d pointLocal, normalLocal;
  int32_t waited = 0;  ///< steps waited (impact cap or frame budget)
  bool operator<(const Candidate& o) const { return speedMps != o.speedMps ? speedMps > o.speedMps : body < o.body; }
};

// A submitted impact's outcome, collected from the World as soon as its work is done (in
// submission order, never past one still running, so the World hands out object ids in the same
// order on a fast or a slow machine), with its fragments' hulls. It takes effect at its frame;
// what remains for that frame is adding the bodies to Bullet.
struct Landing {
  Status status = Ok{};
  ImpactResult result;
  std::vector<Hull> hulls;
  bool hullsBuilt = false;
};

// An impact submitted to the World's workers, applied at the start of applyFrame.
struct InFlight {
  ImpactTicket ticket;
  Candidate candidate;
  int64_t applyFrame = 0;
  size_t event = 0;          ///< its index in PlayResult::events
  // The other body at the contact (after the step), and its velocities before it.
  btTransform otherTransform = btTransform::getIdentity();
  Eigen::Vector3d otherPreVelocity = Eigen::Vector3d::Zero(), otherPreAngular = Eigen::Vector3d::Zero();
  std::shared_ptr<Landing> landing;  ///< its outcome, once collected
};

class Simulation {
 public:
  Simulation(World world, const Scene& scene, const PlayerSettings& settings, std::shared_ptr<HullStore> hulls);
  ~Simulation();

  Status addFloor();
  Status addObject(const SceneObject& o);
  void addImpactor(const RigidImpactor& imp);
  Status waitUntilPrepared() { return mWorld.waitUntilPrepared(); }
  void setMaterials(std::vector<Material> materials) { mMaterials = std::move(materials); }

  // The play, one frame at a time: begin(), stepFrame() until frameCount(), finish().
  void begin();
  FrameStats stepFrame();
  PlayResult finish();
  Result<PlayResult> run();
  int64_t frameCount() const { return mOut.frames; }
  int64_t frame() const { return mFrame; }
  double timeS() const { return static_cast<double>(mFrame) * mScene.timeStepS; }
  const PlayResult& progress() const { return mOut; }

  // The live bodies as the viewer draws them.
  std::vector<BodyView> liveBodies() const;
  // An impactor thrown in during the play: it exists from the next sample on.
  void throwImpactor(const RigidImpactor& imp);

 private:
  // Bodies (Simulation.cpp).
  Material materialOf(const std::string& name) const;
  Body& addHullBody(BodyState state, const TriangleMesh& surface, const MassProperties& mass, bool isStatic,
                    const Eigen::Matrix3d& rotation, const Eigen::Vector3d& translation);
  Body& addHullBody(BodyState state, const TriangleMesh& surface, const MassProperties& mass, const Hull& hull,
                    bool isStatic, const Eigen::Matrix3d& rotation, const Eigen::Vector3d& translation);
  void finishBody(Body& b, double massKg, const Eigen::Vector3d& moments, const Eigen::Matrix3d& bodyRotation,
                  const Eigen::Vector3d& comWorld);

  // Contact scheduling (ContactScheduling.cpp).
  bool processContacts(int64_t frame, double timeS, double spentS, PlayResult& out);
  void updateSiblingPairs();
  bool breakable(int index, double timeS) const;
  Eigen::Vector3d pointVelocity(int index, const Eigen::Vector3d& point) const;
  Candidate candidate(int body, int other, double speed, const Eigen::Vector3d& pointWorld, const Eigen::Vector3d& normalWorld) const;
  bool impact(const Candidate& c, int64_t frame, double timeS, bool fast, PlayResult& out);
  void collectReady();
  void land(InFlight& f);
  bool applyDue(int64_t frame, PlayResult& out);

  // Fragment spawning (FragmentSpawning.cpp).
  bool applyResult(const Status& st, const ImpactResult& r, const std::vector<Hull>* hulls, const Candidate& c,
                   int64_t frame, PlayResult& out, ImpactEvent& e, const InFlight* flight = nullptr);
  void spawnFragments(const ImpactResult& r, const std::vector<Hull>& hulls, const Candidate& c, int64_t frame,
                      const InFlight* flight);

  // Recording (Recording.cpp).
  void energy(double& total, double& kinetic) const;
  double lowestPoint(const Body& b) const;
  void recordPose(Body& b);
  void recordPoses(int64_t sample);

  World mWorld;
  const Scene& mScene;
  PlayerSettings mSettings;
  std::vector<Material> mMaterials;
  Material mFloorMaterial = materialPreset("concrete").value();
  btDefaultCollisionConfiguration mConfig;
  btSequentialImpulseConstraintSolver mSolver;
  SiblingFilter mFilter;  // outlives mBullet, which points to it
  std::unique_ptr<btBroadphaseInterface> mBroadphase;
  std::unique_ptr<btCollisionDispatcher> mDispatcher;
  std::unique_ptr<btDiscreteDynamicsWorld> mBullet;
  std::unique_ptr<btCollisionShape> mFloorShape;
  std::unique_ptr<btRigidBody> mFloor;
  std::vector<Body> mBodies;
  std::vector<Candidate> mDeferred;
  std::vector<InFlight> mInFlight;  // submitted impacts, in submission order
  std::shared_ptr<HullStore> mHulls;
  SteadyClock::time_point mPaceStart;  // realTime: the wall time of frame 0
  PlayResult mOut;
  int64_t mFrame = 0;
  int64_t mDeferredCount = 0;
  int64_t mBudgetDeferredCount = 0;
  int64_t mSimplifiedCount = 0;
  std::vector<int32_t> mBornThisStep;
  ImpactResult mResult;
};

}  // namespace brittle::play
