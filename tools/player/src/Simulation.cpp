// Simulation.cpp — the play's bodies (floor, pack objects, impactors, hull bodies) and its frame
// loop: Bullet substeps, contacts handed to the runtime, impacts applied when due.
#include "Simulation.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <thread>

#include "brittle/precompute/MaterialLibrary.h"
#include "brittle/runtime/Fingerprint.h"

namespace brittle::play {

// The automatic fracture latency, s of play: two frames at 60 Hz.
constexpr double kAutoLatencyS = 2.0 / 60.0;

Simulation::Simulation(World world, const Scene& scene, const PlayerSettings& settings, std::shared_ptr<HullStore> hulls)
    : mWorld(std::move(world)), mScene(scene), mSettings(settings), mHulls(std::move(hulls)) {
  if (mSettings.fractureLatencyFrames < 0) {  // automatic: about two 60 Hz frames of play
    mSettings.fractureLatencyFrames = std::max(1, static_cast<int>(std::lround(kAutoLatencyS / mScene.timeStepS)));
  }
  mBroadphase = std::make_unique<btDbvtBroadphase>();
  mDispatcher = std::make_unique<btCollisionDispatcher>(&mConfig);
  mBullet = std::make_unique<btDiscreteDynamicsWorld>(mDispatcher.get(), mBroadphase.get(), &mSolver, &mConfig);
  mBullet->setGravity(bt(scene.gravityMps2));
  // Penetration recovery adds no kinetic energy: split impulse at every depth (Bullet's default
  // threshold, −4 cm, recovers shallower penetrations through the velocities). Fragments can be
  // born slightly into their neighbours (a matched fragment's pieces come from its database
  // entry's shape, not its hull), and pushing them out must not launch them.
  mBullet->getSolverInfo().m_splitImpulse = 1;
  mBullet->getSolverInfo().m_splitImpulsePenetrationThreshold = 0;
  mBullet->getPairCache()->setOverlapFilterCallback(&mFilter);
  mSolver.setRandSeed(0);
}

Simulation::~Simulation() {
  for (Body& b : mBodies)
    if (b.alive) mBullet->removeRigidBody(b.rigid.get());
  if (mFloor) mBullet->removeRigidBody(mFloor.get());
}

Status Simulation::addFloor() {
  if (!mScene.floor) return Ok{};
  mFloorMaterial = materialPreset(mScene.floor->material).value();
  mFloorShape = std::make_unique<btStaticPlaneShape>(btVector3(0, 0, 1), mScene.floor->heightM);
  btRigidBody::btRigidBodyConstructionInfo info(0.0, nullptr, mFloorShape.get());
  mFloor = std::make_unique<btRigidBody>(info);
  mFloor->setRestitution(mFloorMaterial.restitution);
  mFloor->setFriction(mSettings.frictionCoefficient);
  mFloor->setUserIndex(-1);
  mBullet->addRigidBody(mFloor.get());
  return Ok{};
}

// A hull body from a surface in its local frame, placed with the local frame at (rotation, translation).
Body& Simulation::addHullBody(BodyState state, const TriangleMesh& surface, const MassProperties& mass, bool isStatic,
                              const Eigen::Matrix3d& rotation, const Eigen::Vector3d& translation) {
  return addHullBody(std::move(state), surface, mass, convexHull(surface, mass, 0), isStatic, rotation, translation);
}

Body& Simulation::addHullBody(BodyState state, const TriangleMesh& surface, const MassProperties& mass, const Hull& hull,
                              bool isStatic, const Eigen::Matrix3d& rotation, const Eigen::Vector3d& translation) {
  Body& b = mBodies.emplace_back();
  b.state = std::move(state);
  b.state.index = static_cast<int32_t>(mBodies.size() - 1);
  b.state.isStatic = isStatic;
  b.state.massKg = mass.massKg;
  b.state.surface = surface;
  b.comLocal = mass.centerOfMassM;
  b.axes = hull.axes;
  b.sizeM = hull.sizeM;
  auto shape = std::make_unique<btConvexHullShape>();
  for (int i = 0; i < hull.points.size(); ++i) shape->addPoint(hull.points[i], false);
  b.state.hullVertices = hull.points.size();
  shape->recalcLocalAabb();
  shape->setMargin(mSettings.collisionMarginM);
  b.shape = std::move(shape);
  finishBody(b, isStatic ? 0.0 : mass.massKg, hull.moments, rotation * b.axes, rotation * b.comLocal + translation);
  return b;
}

void Simulation::finishBody(Body& b, double massKg, const Eigen::Vector3d& moments, const Eigen::Matrix3d& bodyRotation,
                            const Eigen::Vector3d& comWorld) {
  btRigidBody::btRigidBodyConstructionInfo info(massKg, nullptr, b.shape.get(), massKg > 0.0 ? bt(moments) : btVector3(0, 0, 0));
  info.m_startWorldTransform = btTransform(bt(bodyRotation), bt(comWorld));
  info.m_restitution = b.material.restitution;
  info.m_friction = mSettings.frictionCoefficient;
  b.rigid = std::make_unique<btRigidBody>(info);
  b.rigid->setUserIndex(b.state.index);
  b.rigid->setActivationState(DISABLE_DEACTIVATION);  // a support that breaks must wake what rests on it
  if (massKg > 0.0) {
    // Swept-sphere CCD for fast small bodies (through thin panes).
    b.rigid->setCcdMotionThreshold(0.5 * b.sizeM);
    b.rigid->setCcdSweptSphereRadius(0.2 * b.sizeM);
  }
  mBullet->addRigidBody(b.rigid.get());
}

Status Simulation::addObject(const SceneObject& o) {
  ObjectDesc desc{.asset = o.asset, .rotation = o.rotation.toRotationMatrix(), .translationM = o.positionWorldM};
  auto id = mWorld.addObject(desc);
  if (!id) return makeError(id.error().code, "scene object '" + o.name + "': " + id.error().message);
  const ObjectAsset* asset = mWorld.objectAsset(id.value()).value();
  BodyState state;
  state.name = o.name;
  state.kind = BodyKind::Object;
  Body& b = addHullBody(std::move(state), assetSurface(*asset), asset->massProperties, o.isStatic, desc.rotation,
                        desc.translationM);
  b.object = id.value();
  b.material = materialOf(asset->materialName);
  b.rigid->setRestitution(b.material.restitution);
  b.runtimeRotation = desc.rotation;
  b.runtimeTranslation = desc.translationM;
  if (!o.isStatic) {
    b.rigid->setLinearVelocity(bt(o.velocityMps));
    b.rigid->setAngularVelocity(bt(o.angularVelocityRadPerS));
  }
  return Ok{};
}

void Simulation::addImpactor(const RigidImpactor& imp) {
  Body& b = mBodies.emplace_back();
  b.state.index = static_cast<int32_t>(mBodies.size() - 1);
  b.state.name = imp.name;
  b.state.kind = BodyKind::Impactor;
  b.state.massKg = imp.massKg;
  b.state.impactor = imp;
  b.material = materialPreset(imp.material).value();
  Eigen::Vector3d moments;
  if (imp.shape == ImpactorShape::Sphere) {
    b.shape = std::make_unique<btSphereShape>(imp.radiusM);
    moments.setConstant(0.4 * imp.massKg * imp.radiusM * imp.radiusM);
    b.sizeM = imp.radiusM;
    b.radiusForOthersM = imp.radiusM;
  } else {
    b.shape = std::make_unique<btBoxShape>(bt(imp.halfExtentsM));
    b.shape->setMargin(mSettings.collisionMarginM);
    const Eigen::Vector3d e2 = (2.0 * imp.halfExtentsM).cwiseAbs2();
    moments = imp.massKg / 12.0 * Eigen::Vector3d(e2.y() + e2.z(), e2.x() + e2.z(), e2.x() + e2.y());
    b.sizeM = imp.halfExtentsM.norm();
  }
  finishBody(b, imp.massKg, moments, imp.rotation.toRotationMatrix(), imp.positionWorldM);
  b.rigid->setLinearVelocity(bt(imp.velocityMps));
  b.rigid->setAngularVelocity(bt(imp.angularVelocityRadPerS));
}

Material Simulation::materialOf(const std::string& name) const {
  for (const Material& m : mMaterials)
    if (m.name == name) return m;
  return materialPreset("glass").value();  // unreachable for a validated pack
}

// The play, one frame at a time: begin(), stepFrame() until frameCount(), finish().
void Simulation::begin() {
  mOut = PlayResult{};
  mOut.scene = mScene.name;
  mOut.seed = mScene.seed;
  mOut.timeStepS = mScene.timeStepS;
  mOut.frames = std::max<int64_t>(1, std::llround(mScene.durationS / mScene.timeStepS));
  mFrame = 0;
  if (mSettings.recordTracks) recordPoses(0);
}

FrameStats Simulation::stepFrame() {
  PlayResult& out = mOut;
  const int64_t frame = mFrame;
  const double h = mScene.timeStepS / mScene.substeps;
  double timeS = 0.0;
  FrameStats fs;
  fs.frame = frame;
  if (mSettings.realTime) {
    if (frame == 0) mPaceStart = SteadyClock::now();
    std::this_thread::sleep_until(mPaceStart + std::chrono::duration_cast<SteadyClock::duration>(
                                                   std::chrono::duration<double>(static_cast<double>(frame) * mScene.timeStepS)));
  }
  if (!mInFlight.empty()) {
    const auto t0 = SteadyClock::now();
    collectReady();
    fs.fractured = applyDue(frame, out);
    fs.fractureS += secondsSince(t0);
  }
  for (int s = 0; s < mScene.substeps; ++s) {
    const auto t0 = SteadyClock::now();
    for (Body& b : mBodies) {
      if (!b.alive) continue;
      b.preVelocity = eig(b.rigid->getLinearVelocity());
      b.preAngular = eig(b.rigid->getAngularVelocity());
    }
    mBullet->stepSimulation(h, 0);
    timeS = (static_cast<double>(frame) + (s + 1.0) / mScene.substeps) * mScene.timeStepS;
    const auto t1 = SteadyClock::now();
    fs.fractured = processContacts(frame, timeS, fs.fractureS, out) || fs.fractured;
    const auto t2 = SteadyClock::now();
    fs.bulletS += secondsBetween(t0, t1);
    fs.fractureS += secondsBetween(t1, t2);
  }
  fs.timeS = timeS;
  fs.bodies = 0;
  for (const Body& b : mBodies) fs.bodies += b.alive ? 1 : 0;
  energy(fs.energyJ, fs.kineticJ);
  out.frameStats.push_back(fs);
  ++mFrame;
  if (mSettings.recordTracks) recordPoses(frame + 1);
  out.deferredImpacts = mDeferredCount;
  out.budgetDeferredImpacts = mBudgetDeferredCount;
  out.simplifiedImpacts = mSimplifiedCount;
  return fs;
}

PlayResult Simulation::finish() {
  PlayResult out = std::move(mOut);
  mOut = PlayResult{};
  out.frames = mFrame;  // frames actually played
  Fingerprint hash;
  for (Body& b : mBodies) {
    if (!b.alive) continue;
    ++out.bodiesAtEnd;
    const btTransform& t = b.rigid->getCenterOfMassTransform();
    for (int i = 0; i < 3; ++i) hash.add(static_cast<double>(t.getOrigin()[i]));
    const btQuaternion q = t.getRotation();
    for (int i = 0; i < 4; ++i) hash.add(static_cast<double>(q[i]));
  }
  out.poseHash = hash.value();
  for (const FrequencySource s : {FrequencySource::Own, FrequencySource::Entry, FrequencySource::Ritz, FrequencySource::Checked,
                                  FrequencySource::CheckedP2})
    out.frequencySourcesAtEnd[std::string(frequencySourceName(s))] = 0;
  for (const Body& b : mBodies) {
    if (!b.alive || !b.object.valid()) continue;
    if (auto p = mWorld.frequencyError(b.object, timeS())) ++out.frequencySourcesAtEnd[std::string(frequencySourceName(p.value().source))];
  }
  for (Body& b : mBodies) {
    if (b.alive && !mSettings.recordTracks) recordPose(b);
    if (b.alive) b.state.lowestPointM = lowestPoint(b);
    out.bodies.push_back(b.state);
  }
  return out;
}

Result<PlayResult> Simulation::run() {
  begin();
  while (mFrame < mOut.frames) stepFrame();
  return finish();
}

// The live bodies as the viewer draws them.
std::vector<BodyView> Simulation::liveBodies() const {
  std::vector<BodyView> views;
  for (const Body& b : mBodies) {
    if (!b.alive) continue;
    BodyView v;
    v.index = b.state.index;
    v.kind = b.state.kind;
    v.name = b.state.name;
    v.surface = b.state.kind == BodyKind::Impactor ? nullptr : &b.state.surface;
    v.impactor = b.state.kind == BodyKind::Impactor ? &b.state.impactor : nullptr;
    b.localPose(v.rotation, v.translationM);
    views.push_back(std::move(v));
  }
  return views;
}

// An impactor thrown in during the play: it exists from the next sample on.
void Simulation::throwImpactor(const RigidImpactor& imp) {
  addImpactor(imp);
  mBodies.back().state.firstFrame = mFrame;
  if (mSettings.recordTracks) recordPose(mBodies.back());
}

}  // namespace brittle::play
