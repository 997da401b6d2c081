// Player.cpp — Bullet bodies for pack objects, fragments and impactors; contacts → runtime impacts.
#include "brittle/player/Player.h"

#include <btBulletDynamicsCommon.h>

#include <Eigen/Eigenvalues>
#include <LinearMath/btConvexHull.h>
#include <LinearMath/btConvexHullComputer.h>
#include <oneapi/tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <numbers>
#include <set>
#include <thread>

#include "brittle/core/Timing.h"
#include "brittle/precompute/MaterialLibrary.h"
#include "brittle/runtime/Fingerprint.h"

namespace brittle {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

btVector3 bt(const Eigen::Vector3d& v) { return btVector3(v.x(), v.y(), v.z()); }
Eigen::Vector3d eig(const btVector3& v) { return Eigen::Vector3d(v.x(), v.y(), v.z()); }
Eigen::Matrix3d eig(const btMatrix3x3& m) {
  Eigen::Matrix3d r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r(i, j) = m[i][j];
  return r;
}
btMatrix3x3 bt(const Eigen::Matrix3d& m) {
  return btMatrix3x3(m(0, 0), m(0, 1), m(0, 2), m(1, 0), m(1, 1), m(1, 2), m(2, 0), m(2, 1), m(2, 2));
}

// Principal axes: inertia = P diag(d) Pᵀ with P a rotation (det +1), d clamped away from zero so
// that slivers of debris stay integrable.
void principalAxes(const Eigen::Matrix3d& inertia, Eigen::Matrix3d& axes, Eigen::Vector3d& moments) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig3(0.5 * (inertia + inertia.transpose()));
  axes = eig3.eigenvectors();
  if (axes.determinant() < 0.0) axes.col(2) *= -1.0;
  moments = eig3.eigenvalues().cwiseMax(1e-6 * std::max(eig3.eigenvalues().maxCoeff(), 1e-300));
}

// The surface of an asset: its tet mesh's boundary, nodes renumbered compactly.
TriangleMesh assetSurface(const ObjectAsset& asset) {
  std::vector<int32_t> remap(static_cast<size_t>(asset.tetMesh.nodes.rows()), -1);
  int32_t count = 0;
  for (Eigen::Index f = 0; f < asset.surfaceFaces.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      int32_t& r = remap[static_cast<size_t>(asset.surfaceFaces(f, k))];
      if (r < 0) r = count++;
    }
  TriangleMesh s;
  s.vertices.resize(count, 3);
  s.faces.resize(asset.surfaceFaces.rows(), 3);
  for (size_t n = 0; n < remap.size(); ++n)
    if (remap[n] >= 0) s.vertices.row(remap[n]) = asset.tetMesh.nodes.row(static_cast<Eigen::Index>(n));
  for (Eigen::Index f = 0; f < asset.surfaceFaces.rows(); ++f)
    for (int k = 0; k < 3; ++k) s.faces(f, k) = remap[static_cast<size_t>(asset.surfaceFaces(f, k))];
  return s;
}

// The automatic fracture latency, s of play: two frames at 60 Hz.
constexpr double kAutoLatencyS = 2.0 / 60.0;

struct Body {
  BodyState state;
  ObjectId object;                 ///< valid: breakable
  Material material;
  std::unique_ptr<btCollisionShape> shape;
  std::unique_ptr<btRigidBody> rigid;
  bool alive = true;
  // Local (asset) frame relative to the Bullet body frame: x_local = comLocal + axes · x_body.
  Eigen::Vector3d comLocal = Eigen::Vector3d::Zero();
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();
  // The pose the runtime World holds for the object (it never moves there): impacts are mapped
  // from the body's local frame into that pose.
  Eigen::Matrix3d runtimeRotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d runtimeTranslation = Eigen::Vector3d::Zero();
  double sizeM = 0.0;              ///< largest distance of a surface point from the centre of mass
  double radiusForOthersM = kInf;  ///< what an impact on another body sees: sphere radius, else flat
  double cooldownUntilS = -kInf;
  bool fracturing = false;  ///< an impact on it is submitted and not applied yet
  Eigen::Vector3d preVelocity = Eigen::Vector3d::Zero(), preAngular = Eigen::Vector3d::Zero();

  double massKg() const { return state.massKg; }
  Eigen::Vector3d com() const { return eig(rigid->getCenterOfMassPosition()); }
  // Pose of the local frame in the world.
  void localPose(Eigen::Matrix3d& rotation, Eigen::Vector3d& translation) const {
    const btTransform& t = rigid->getCenterOfMassTransform();
    rotation = eig(t.getBasis()) * axes.transpose();
    translation = eig(t.getOrigin()) - rotation * comLocal;
  }
};

struct Candidate {
  int32_t body = -1, other = -1;
  double speedMps = 0.0;
  Eigen::Vector3d pointLocal, normalLocal;
  int32_t waited = 0;  ///< steps waited (impact cap or frame budget)
  bool operator<(const Candidate& o) const { return speedMps != o.speedMps ? speedMps > o.speedMps : body < o.body; }
};

struct Landing;

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

// Fragments born in the same step start interpenetrating (the convex hulls of concave fragments
// overlap, and two bodies that broke against each other left their fragments in contact). Bullet
// would push them apart with velocity, out of nothing. So a pair of such bodies whose boxes
// overlap at birth does not collide until their boxes have separated once.
struct SiblingFilter final : btOverlapFilterCallback {
  std::set<std::pair<int, int>> blocked;
  bool needBroadphaseCollision(btBroadphaseProxy* p0, btBroadphaseProxy* p1) const override {
    if ((p0->m_collisionFilterGroup & p1->m_collisionFilterMask) == 0 || (p1->m_collisionFilterGroup & p0->m_collisionFilterMask) == 0) {
      return false;
    }
    const int a = static_cast<const btCollisionObject*>(p0->m_clientObject)->getUserIndex();
    const int b = static_cast<const btCollisionObject*>(p1->m_clientObject)->getUserIndex();
    return a < 0 || b < 0 || !blocked.contains({std::min(a, b), std::max(a, b)});
  }
};

bool aabbsOverlap(const btRigidBody& a, const btRigidBody& b) {
  btVector3 amin, amax, bmin, bmax;
  a.getAabb(amin, amax);
  b.getAabb(bmin, bmax);
  for (int k = 0; k < 3; ++k)
    if (amax[k] < bmin[k] || bmax[k] < amin[k]) return false;
  return true;
}

// A body's Bullet shape, computed apart from Bullet's world so that the fragments of a break can
// be done in parallel: principal axes and moments, and the convex hull of the surface in them
// (what btConvexHullShape::optimizeConvexHull keeps, computed the same way; the shape's box is
// then that of the hull's vertices).
struct Hull {
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();
  Eigen::Vector3d moments = Eigen::Vector3d::Zero();
  btAlignedObjectArray<btVector3> points;
  double sizeM = 0.0;  ///< largest distance of a surface point from the centre of mass
};

Hull convexHull(const TriangleMesh& surface, const MassProperties& mass, int maxVertices) {
  Hull h;
  principalAxes(mass.inertiaKgM2, h.axes, h.moments);
  btAlignedObjectArray<btVector3> all;
  all.reserve(static_cast<int>(surface.vertices.rows()));
  for (Eigen::Index v = 0; v < surface.vertices.rows(); ++v) {
    const Eigen::Vector3d x = h.axes.transpose() * (surface.vertices.row(v).transpose() - mass.centerOfMassM);
    h.sizeM = std::max(h.sizeM, x.norm());
    all.push_back(bt(x));
  }
  if (maxVertices > 0) {
    // Candidates: the surface's extreme vertex in each of 4·maxVertices fixed directions of its
    // principal frame (a spherical Fibonacci lattice; ties: the lowest vertex), a pass over the
    // vertices per direction instead of the exact hull of a dense surface. Then at most
    // maxVertices of them, farthest point first (Bullet's HullLibrary, quadratic in its input,
    // hence the candidates): hull vertices all, so the shape lies inside the exact hull.
    const int directions = 4 * maxVertices;
    std::vector<int> chosen;
    chosen.reserve(static_cast<size_t>(directions));
    const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
    for (int k = 0; k < directions; ++k) {
      const double z = 1.0 - (2.0 * k + 1.0) / directions, r = std::sqrt(std::max(0.0, 1.0 - z * z));
      const btVector3 dir(static_cast<btScalar>(r * std::cos(golden * k)), static_cast<btScalar>(r * std::sin(golden * k)),
                          static_cast<btScalar>(z));
      int best = 0;
      btScalar bestDot = all[0].dot(dir);
      for (int v = 1; v < all.size(); ++v) {
        const btScalar d = all[v].dot(dir);
        if (d > bestDot) best = v, bestDot = d;
      }
      if (std::find(chosen.begin(), chosen.end(), best) == chosen.end()) chosen.push_back(best);
    }
    std::sort(chosen.begin(), chosen.end());
    btAlignedObjectArray<btVector3> candidates;
    for (int v : chosen) candidates.push_back(all[v]);
    if (candidates.size() >= 4 && candidates.size() <= maxVertices) {
      h.points = candidates;
      return h;
    }
    if (candidates.size() > maxVertices) {
      HullDesc desc(QF_DEFAULT, static_cast<unsigned>(candidates.size()), &candidates[0]);
      desc.mMaxVertices = static_cast<unsigned>(maxVertices);
      HullLibrary library;
      HullResult result;
      const bool capped = library.CreateConvexHull(desc, result) == QE_OK && result.mNumOutputVertices >= 4;
      if (capped) {
        for (unsigned i = 0; i < result.mNumOutputVertices; ++i) h.points.push_back(result.m_OutputVertices[static_cast<int>(i)]);
      }
      library.ReleaseResult(result);
      if (capped) return h;
    }
    // Fewer than four distinct extremes (a sliver), or a degenerate set: the exact hull below.
  }
  btConvexHullComputer conv;
  conv.compute(&all[0].getX(), sizeof(btVector3), all.size(), 0.f, 0.f);
  for (int i = 0; i < conv.vertices.size(); ++i) h.points.push_back(conv.vertices[i]);
  return h;
}

// The fragments' hulls, in parallel.
void buildHulls(const ImpactResult& r, int maxVertices, std::vector<Hull>& hulls) {
  hulls.resize(r.fragments.size());
  tbb::parallel_for(size_t{0}, hulls.size(), [&](size_t i) {
    hulls[i] = convexHull(r.fragments[i].surface, r.fragments[i].massProperties, maxVertices);
  });
}

// Hulls of submitted impacts' fragments, built on the World's workers as part of each impact's
// work (WorldSettings::onImpactComputed), by ticket until the impact is collected. A hull depends
// on the fragment alone, so where it is built changes nothing.
struct HullStore {
  std::mutex mutex;
  std::map<uint64_t, std::vector<Hull>> byTicket;

  void put(ImpactTicket t, std::vector<Hull> hulls) {
    std::lock_guard<std::mutex> lock(mutex);
    byTicket[t.id] = std::move(hulls);
  }
  bool take(ImpactTicket t, std::vector<Hull>& hulls) {
    std::lock_guard<std::mutex> lock(mutex);
    const auto it = byTicket.find(t.id);
    if (it == byTicket.end()) return false;
    hulls = std::move(it->second);
    byTicket.erase(it);
    return true;
  }
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

class Simulation {
 public:
  Simulation(World world, const Scene& scene, const PlayerSettings& settings, std::shared_ptr<HullStore> hulls)
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

  ~Simulation() {
    for (Body& b : mBodies)
      if (b.alive) mBullet->removeRigidBody(b.rigid.get());
    if (mFloor) mBullet->removeRigidBody(mFloor.get());
  }

  Status addFloor() {
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
  Body& addHullBody(BodyState state, const TriangleMesh& surface, const MassProperties& mass, bool isStatic,
                    const Eigen::Matrix3d& rotation, const Eigen::Vector3d& translation) {
    return addHullBody(std::move(state), surface, mass, convexHull(surface, mass, 0), isStatic, rotation, translation);
  }

  Body& addHullBody(BodyState state, const TriangleMesh& surface, const MassProperties& mass, const Hull& hull,
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

  void finishBody(Body& b, double massKg, const Eigen::Vector3d& moments, const Eigen::Matrix3d& bodyRotation,
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

  Status addObject(const SceneObject& o) {
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

  void addImpactor(const RigidImpactor& imp) {
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

  Status waitUntilPrepared() { return mWorld.waitUntilPrepared(); }

  Material materialOf(const std::string& name) const {
    for (const Material& m : mMaterials)
      if (m.name == name) return m;
    return materialPreset("glass").value();  // unreachable for a validated pack
  }
  void setMaterials(std::vector<Material> materials) { mMaterials = std::move(materials); }

  // The play, one frame at a time: begin(), stepFrame() until frameCount(), finish().
  void begin() {
    mOut = PlayResult{};
    mOut.scene = mScene.name;
    mOut.timeStepS = mScene.timeStepS;
    mOut.frames = std::max<int64_t>(1, std::llround(mScene.durationS / mScene.timeStepS));
    mFrame = 0;
    if (mSettings.recordTracks) recordPoses(0);
  }
  int64_t frameCount() const { return mOut.frames; }
  int64_t frame() const { return mFrame; }
  double timeS() const { return static_cast<double>(mFrame) * mScene.timeStepS; }
  const PlayResult& progress() const { return mOut; }

  FrameStats stepFrame() {
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

  PlayResult finish() {
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
    for (Body& b : mBodies) {
      if (b.alive && !mSettings.recordTracks) recordPose(b);
      if (b.alive) b.state.lowestPointM = lowestPoint(b);
      out.bodies.push_back(b.state);
    }
    return out;
  }

  Result<PlayResult> run() {
    begin();
    while (mFrame < mOut.frames) stepFrame();
    return finish();
  }

  // The live bodies as the viewer draws them.
  std::vector<BodyView> liveBodies() const {
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
  void throwImpactor(const RigidImpactor& imp) {
    addImpactor(imp);
    mBodies.back().state.firstFrame = mFrame;
    if (mSettings.recordTracks) recordPose(mBodies.back());
  }

 private:
  // Every breakable body's fastest new contact in this step (plus what waited), the fastest
  // maxImpactsPerStep of them handed to the runtime, within the frame's fracture budget (spentS:
  // fracture time this frame before this step). Returns whether a body broke.
  bool processContacts(int64_t frame, double timeS, double spentS, PlayResult& out) {
    const auto start = SteadyClock::now();
    std::map<int32_t, Candidate> best;  // by body: deterministic order
    auto consider = [&](const Candidate& c) {
      auto [it, inserted] = best.try_emplace(c.body, c);
      if (!inserted && c.speedMps > it->second.speedMps) {
        const int32_t waited = it->second.waited;
        it->second = c;
        it->second.waited = std::max(waited, c.waited);  // a body's wait is not reset by a new contact
      }
    };
    for (const Candidate& c : mDeferred)
      if (mBodies[static_cast<size_t>(c.body)].alive) consider(c);
    mDeferred.clear();

    const int manifolds = mDispatcher->getNumManifolds();
    for (int m = 0; m < manifolds; ++m) {
      const btPersistentManifold* manifold = mDispatcher->getManifoldByIndexInternal(m);
      const int a = manifold->getBody0()->getUserIndex(), b = manifold->getBody1()->getUserIndex();
      for (int p = 0; p < manifold->getNumContacts(); ++p) {
        const btManifoldPoint& pt = manifold->getContactPoint(p);
        if (pt.getDistance() > 2.0 * mSettings.collisionMarginM) continue;
        const Eigen::Vector3d n = eig(pt.m_normalWorldOnB);  // from B towards A
        const Eigen::Vector3d pa = eig(pt.getPositionWorldOnA()), pb = eig(pt.getPositionWorldOnB());
        const Eigen::Vector3d va = pointVelocity(a, pa), vb = pointVelocity(b, pb);
        const double approach = -(va - vb).dot(n);
        if (!(approach > mSettings.impactThresholdMps)) continue;
        if (breakable(a, timeS)) consider(candidate(a, b, approach, pa, -n));
        if (breakable(b, timeS)) consider(candidate(b, a, approach, pb, n));
      }
    }
    std::vector<Candidate> order;
    for (auto& [body, c] : best) order.push_back(c);
    std::sort(order.begin(), order.end());
    bool broke = false;
    for (size_t i = 0; i < order.size(); ++i) {
      if (!mBodies[static_cast<size_t>(order[i].body)].alive) continue;
      Candidate c = order[i];
      if (static_cast<int>(i) >= mSettings.maxImpactsPerStep) {
        ++c.waited;
        mDeferred.push_back(c);
        ++mDeferredCount;
        continue;
      }
      bool fast = false;
      if (mSettings.fractureBudgetS > 0.0 && spentS + secondsSince(start) >= mSettings.fractureBudgetS) {
        if (c.waited < mSettings.maxBudgetWaits) {
          ++c.waited;
          mDeferred.push_back(c);
          ++mBudgetDeferredCount;
          continue;
        }
        fast = true;  // waited long enough: runs now, simplified
        ++mSimplifiedCount;
      }
      broke = impact(c, frame, timeS, fast, out) || broke;
    }
    updateSiblingPairs();
    return broke;
  }

  void updateSiblingPairs() {
    for (auto it = mFilter.blocked.begin(); it != mFilter.blocked.end();) {
      const Body& a = mBodies[static_cast<size_t>(it->first)];
      const Body& b = mBodies[static_cast<size_t>(it->second)];
      it = !a.alive || !b.alive || !aabbsOverlap(*a.rigid, *b.rigid) ? mFilter.blocked.erase(it) : std::next(it);
    }
    for (size_t i = 0; i < mBornThisStep.size(); ++i)
      for (size_t j = i + 1; j < mBornThisStep.size(); ++j) {
        const Body& a = mBodies[static_cast<size_t>(mBornThisStep[i])];
        const Body& b = mBodies[static_cast<size_t>(mBornThisStep[j])];
        if (!a.alive || !b.alive || !aabbsOverlap(*a.rigid, *b.rigid)) continue;
        mFilter.blocked.insert({a.state.index, b.state.index});
        // Adding a body already paired it with what it overlaps: drop that pair.
        mBullet->getPairCache()->removeOverlappingPair(a.rigid->getBroadphaseHandle(), b.rigid->getBroadphaseHandle(), mDispatcher.get());
      }
    mBornThisStep.clear();
  }

  bool breakable(int index, double timeS) const {
    if (index < 0) return false;
    const Body& b = mBodies[static_cast<size_t>(index)];
    return b.alive && b.object.valid() && !b.fracturing && timeS >= b.cooldownUntilS;
  }

  Eigen::Vector3d pointVelocity(int index, const Eigen::Vector3d& point) const {
    if (index < 0) return Eigen::Vector3d::Zero();
    const Body& b = mBodies[static_cast<size_t>(index)];
    return b.preVelocity + b.preAngular.cross(point - b.com());
  }

  Candidate candidate(int body, int other, double speed, const Eigen::Vector3d& pointWorld, const Eigen::Vector3d& normalWorld) const {
    Eigen::Matrix3d r;
    Eigen::Vector3d t;
    mBodies[static_cast<size_t>(body)].localPose(r, t);
    return Candidate{body, other, speed, r.transpose() * (pointWorld - t), r.transpose() * normalWorld};
  }

  bool impact(const Candidate& c, int64_t frame, double timeS, bool fast, PlayResult& out) {
    Body& b = mBodies[static_cast<size_t>(c.body)];
    ImpactDesc d;
    d.object = b.object;
    d.pointWorld = b.runtimeRotation * c.pointLocal + b.runtimeTranslation;
    d.normalWorld = (b.runtimeRotation * c.normalLocal).normalized();
    d.speedMps = c.speedMps;
    d.pointToleranceM = mSettings.pointToleranceFraction * b.sizeM;
    d.flatPairRadiusM = b.sizeM;  // an edge or corner of the body's size meets the flat
    d.fast = fast;
    const Material* otherMaterial = &mFloorMaterial;
    if (c.other >= 0) {
      const Body& o = mBodies[static_cast<size_t>(c.other)];
      d.impactorMassKg = o.rigid->getInvMass() > 0.0 ? o.massKg() : kInf;
      d.impactorRadiusM = o.radiusForOthersM;
      otherMaterial = &o.material;
    } else {
      d.impactorMassKg = kInf;
      d.impactorRadiusM = kInf;
    }
    d.impactorYoungsModulusPa = otherMaterial->youngsModulusPa;
    d.impactorPoissonRatio = otherMaterial->poissonRatio;
    b.cooldownUntilS = timeS + mSettings.cooldownS;

    ImpactEvent e;
    e.timeS = timeS;
    e.frame = frame;
    e.body = c.body;
    e.object = b.state.name;
    e.otherBody = c.other;
    e.speedMps = c.speedMps;
    e.otherMassKg = d.impactorMassKg;
    e.waitedSteps = c.waited;
    e.simplified = fast;
    ++out.impacts;
    if (mSettings.fractureLatencyFrames == 0) {
      const Status st = mWorld.impact(d, mResult);
      e.appliedFrame = frame;
      out.events.push_back(std::move(e));
      return applyResult(st, mResult, nullptr, c, frame, out, out.events.back());
    }
    // The player counts its own impacts in flight, collected or not, against the World's
    // capacity: the World's count falls as results are collected early, which depends on the
    // machine's speed, and a refusal must not.
    Result<ImpactTicket> ticket = makeError(ErrorCode::CapacityExceeded,
                                            "impact refused: maxPendingImpacts = " +
                                                std::to_string(mSettings.world.maxPendingImpacts) + " impacts in flight");
    if (mInFlight.size() < static_cast<size_t>(mSettings.world.maxPendingImpacts)) ticket = mWorld.submitImpact(d);
    if (!ticket) {
      e.error = ticket.error().message;
      ++out.failedImpacts;
      out.events.push_back(std::move(e));
      return false;
    }
    InFlight f;
    f.ticket = ticket.value();
    f.candidate = c;
    f.applyFrame = frame + mSettings.fractureLatencyFrames;
    f.event = out.events.size();
    if (c.other >= 0) {
      const Body& o = mBodies[static_cast<size_t>(c.other)];
      f.otherTransform = o.rigid->getCenterOfMassTransform();
      f.otherPreVelocity = o.preVelocity;
      f.otherPreAngular = o.preAngular;
    }
    b.fracturing = true;
    mInFlight.push_back(f);
    out.events.push_back(std::move(e));
    return false;
  }

  // Submitted impacts whose work is done, collected at once in submission order, up to the first
  // one still running.
  void collectReady() {
    for (InFlight& f : mInFlight) {
      if (f.landing) continue;
      if (!mWorld.impactReady(f.ticket)) return;
      land(f);
    }
  }

  // Collects f's outcome (waiting if its work is not done), with the hulls built on the workers.
  void land(InFlight& f) {
    f.landing = std::make_shared<Landing>();
    Landing& l = *f.landing;
    l.status = mWorld.collectImpact(f.ticket, l.result);
    l.hullsBuilt = mHulls && mHulls->take(f.ticket, l.hulls) && l.hulls.size() == l.result.fragments.size();
  }

  // Submitted impacts due at the start of `frame`, in the order they were submitted: collected
  // (waiting if not done) and applied. Returns whether a body broke.
  bool applyDue(int64_t frame, PlayResult& out) {
    bool broke = false;
    size_t kept = 0;
    for (size_t i = 0; i < mInFlight.size(); ++i) {
      InFlight f = mInFlight[i];
      if (f.applyFrame > frame) {
        mInFlight[kept++] = f;
        continue;
      }
      const auto t0 = SteadyClock::now();
      if (!f.landing) land(f);  // waits for the work
      Landing& l = *f.landing;
      ImpactEvent& e = out.events[f.event];
      e.waitS = secondsSince(t0);
      e.appliedFrame = frame;
      mBodies[static_cast<size_t>(f.candidate.body)].fracturing = false;
      broke = applyResult(l.status, l.result, l.hullsBuilt ? &l.hulls : nullptr, f.candidate, frame, out, e, &f) || broke;
    }
    mInFlight.resize(kept);
    if (broke) updateSiblingPairs();
    return broke;
  }

  // An impact's outcome: the event's figures, and the fragments in place of a broken body.
  // hulls: the fragments' hulls when they were built already.
  bool applyResult(const Status& st, const ImpactResult& r, const std::vector<Hull>* hulls, const Candidate& c,
                   int64_t frame, PlayResult& out, ImpactEvent& e, const InFlight* flight = nullptr) {
    if (!st) {
      e.error = st.error().message;
      ++out.failedImpacts;
      return false;
    }
    e.broken = r.broken;
    e.staticCorrection = r.staticCorrectionUsed;
    e.modesUsed = r.modesUsed;
    e.peakPrincipalStressPa = r.peakPrincipalStressPa;
    e.times = r.times;
    if (r.broken) {
      ++out.breaks;
      e.fragments = static_cast<int32_t>(r.fragments.size());
      for (const FragmentResult& f : r.fragments) e.debris += f.debris ? 1 : 0;
      if (hulls) {
        spawnFragments(r, *hulls, c, frame, flight);
      } else {
        std::vector<Hull> built;
        buildHulls(r, mSettings.hullMaxVertices, built);
        spawnFragments(r, built, c, frame, flight);
      }
    }
    return r.broken;
  }

  // flight: the submitted impact (latency ≥ 1), whose impactor is put back where it touched.
  void spawnFragments(const ImpactResult& r, const std::vector<Hull>& hulls, const Candidate& c, int64_t frame,
                      const InFlight* flight) {
    // Index, not reference: adding bodies grows mBodies.
    const size_t parentIndex = static_cast<size_t>(c.body);
    Eigen::Matrix3d rotation;
    Eigen::Vector3d translation;
    mBodies[parentIndex].localPose(rotation, translation);
    const Eigen::Vector3d v = eig(mBodies[parentIndex].rigid->getLinearVelocity());
    const Eigen::Vector3d w = eig(mBodies[parentIndex].rigid->getAngularVelocity());
    const Eigen::Vector3d com = mBodies[parentIndex].com();
    const bool parentStatic = mBodies[parentIndex].state.isStatic;
    mBullet->removeRigidBody(mBodies[parentIndex].rigid.get());
    mBodies[parentIndex].alive = false;
    mBodies[parentIndex].state.lastFrame = frame;  // its last sample: the start of this frame
    if (!mSettings.recordTracks) recordPose(mBodies[parentIndex]);
    mBodies[parentIndex].state.lowestPointM = lowestPoint(mBodies[parentIndex]);
    // A static body cannot take the impactor's momentum: the impactor goes on as before the step.
    if (parentStatic && c.other >= 0) {
      Body& o = mBodies[static_cast<size_t>(c.other)];
      if (o.alive && o.rigid->getInvMass() > 0.0 && !flight) {
        o.rigid->setLinearVelocity(bt(o.preVelocity));
        o.rigid->setAngularVelocity(bt(o.preAngular));
      } else if (o.alive && o.rigid->getInvMass() > 0.0) {
        // Back where it touched the pane, with the velocities it had before: it meets the
        // fragments as it would have, `latency` frames later.
        o.rigid->setCenterOfMassTransform(flight->otherTransform);
        o.rigid->setInterpolationWorldTransform(flight->otherTransform);
        o.rigid->setLinearVelocity(bt(flight->otherPreVelocity));
        o.rigid->setAngularVelocity(bt(flight->otherPreAngular));
      }
    }
    for (size_t i = 0; i < r.fragments.size(); ++i) {
      const FragmentResult& f = r.fragments[i];
      const Body& parent = mBodies[parentIndex];
      BodyState state;
      state.name = parent.state.name + "/" + std::to_string(i);
      state.kind = f.object.valid() ? BodyKind::Fragment : BodyKind::Debris;
      state.parent = static_cast<int32_t>(parentIndex);
      state.firstFrame = frame + 1;  // first sample: the end of this frame
      const Material material = parent.material;
      const Eigen::Matrix3d runtimeRotation = parent.runtimeRotation;
      const Eigen::Vector3d runtimeTranslation = parent.runtimeTranslation;
      const double cooldown = parent.cooldownUntilS;
      Body& b = addHullBody(std::move(state), f.surface, f.massProperties, hulls[i], false, rotation, translation);
      b.object = f.object;
      b.material = material;
      b.rigid->setRestitution(material.restitution);
      b.runtimeRotation = runtimeRotation;
      b.runtimeTranslation = runtimeTranslation;
      b.cooldownUntilS = cooldown;
      b.rigid->setLinearVelocity(bt(Eigen::Vector3d(v + w.cross(b.com() - com))));
      b.rigid->setAngularVelocity(bt(w));
      b.preVelocity = eig(b.rigid->getLinearVelocity());
      b.preAngular = w;
      mBornThisStep.push_back(b.state.index);
    }
  }

  void energy(double& total, double& kinetic) const {
    total = kinetic = 0.0;
    for (const Body& b : mBodies) {
      if (!b.alive || b.rigid->getInvMass() == 0.0) continue;
      const double m = b.massKg();
      const Eigen::Vector3d v = eig(b.rigid->getLinearVelocity()), w = eig(b.rigid->getAngularVelocity());
      const Eigen::Matrix3d r = eig(b.rigid->getCenterOfMassTransform().getBasis());
      const Eigen::Vector3d iw = r.transpose() * w;
      const Eigen::Vector3d inertia = eig(b.rigid->getLocalInertia());
      const double k = 0.5 * m * v.squaredNorm() + 0.5 * iw.dot(inertia.cwiseProduct(iw));
      kinetic += k;
      total += k - m * mScene.gravityMps2.dot(b.com());
    }
  }

  double lowestPoint(const Body& b) const {
    Eigen::Matrix3d r;
    Eigen::Vector3d t;
    b.localPose(r, t);
    if (b.state.kind != BodyKind::Impactor) {
      double z = kInf;
      for (Eigen::Index v = 0; v < b.state.surface.vertices.rows(); ++v)
        z = std::min(z, (r * b.state.surface.vertices.row(v).transpose() + t).z());
      return z;
    }
    const RigidImpactor& imp = b.state.impactor;
    if (imp.shape == ImpactorShape::Sphere) return t.z() - imp.radiusM;
    return t.z() - (r.row(2).cwiseAbs() * imp.halfExtentsM)(0);
  }

  void recordPose(Body& b) {
    Eigen::Matrix3d r;
    Eigen::Vector3d t;
    b.localPose(r, t);
    if (!mSettings.recordTracks) {
      b.state.rotations.clear();
      b.state.translationsM.clear();
    }
    b.state.rotations.emplace_back(Eigen::Quaterniond(r).normalized());
    b.state.translationsM.push_back(t);
  }

  // Track samples: one per frame boundary, sample k = pose at the end of frame k − 1 (k = 0: start).
  void recordPoses(int64_t sample) {
    for (Body& b : mBodies)
      if (b.alive && b.state.firstFrame <= sample) recordPose(b);
  }

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

}  // namespace

std::string_view bodyKindName(BodyKind kind) {
  switch (kind) {
    case BodyKind::Object: return "object";
    case BodyKind::Fragment: return "fragment";
    case BodyKind::Debris: return "debris";
    case BodyKind::Impactor: return "impactor";
  }
  return "object";
}

Status validatePlayerSettings(const PlayerSettings& s) {
  auto bad = [](const std::string& what) { return makeError(ErrorCode::InvalidArgument, "player settings: " + what); };
  if (!(s.impactThresholdMps > 0.0) || !std::isfinite(s.impactThresholdMps)) return bad("impactThresholdMps must be finite and > 0");
  if (!(s.cooldownS >= 0.0) || !std::isfinite(s.cooldownS)) return bad("cooldownS must be finite and ≥ 0");
  if (s.maxImpactsPerStep < 1) return bad("maxImpactsPerStep must be ≥ 1");
  if (!(s.fractureBudgetS >= 0.0) || !std::isfinite(s.fractureBudgetS)) return bad("fractureBudgetS must be finite and ≥ 0");
  if (s.maxBudgetWaits < 0) return bad("maxBudgetWaits must be ≥ 0");
  if (s.fractureLatencyFrames < -1 || s.fractureLatencyFrames > 600) return bad("fractureLatencyFrames must be in [-1, 600]");
  if (!(s.frictionCoefficient >= 0.0) || !std::isfinite(s.frictionCoefficient)) return bad("frictionCoefficient must be finite and ≥ 0");
  if (!(s.collisionMarginM > 0.0 && s.collisionMarginM <= 0.05)) return bad("collisionMarginM must be in (0, 0.05]");
  if (!(s.pointToleranceFraction > 0.0 && s.pointToleranceFraction <= 1.0)) return bad("pointToleranceFraction must be in (0, 1]");
  if (s.hullMaxVertices != 0 && (s.hullMaxVertices < 8 || s.hullMaxVertices > 4096)) return bad("hullMaxVertices must be 0 or in [8, 4096]");
  return validateWorldSettings(s.world);
}

struct PlaySession::Impl {
  Scene scene;  // the Simulation keeps a reference to it
  std::unique_ptr<Simulation> sim;
  double loadS = 0.0;
};

PlaySession::PlaySession(std::unique_ptr<Impl> impl) : mImpl(std::move(impl)) {}
PlaySession::~PlaySession() = default;

Result<std::unique_ptr<PlaySession>> PlaySession::create(Pack pack, const Scene& scene, const PlayerSettings& settings) {
  if (Status st = validatePlayerSettings(settings); !st) return st.error();
  for (const SceneObject& o : scene.objects) {
    const bool known = std::any_of(pack.objects.begin(), pack.objects.end(), [&](const ObjectAsset& a) { return a.name == o.asset; });
    if (!known) return makeError(ErrorCode::InvalidArgument, "scene '" + scene.name + "': object '" + o.name + "' names asset '" + o.asset + "', which the pack does not have");
  }
  const auto t0 = SteadyClock::now();
  auto impl = std::make_unique<Impl>();
  impl->scene = scene;
  std::vector<Material> materials = pack.materials;
  WorldSettings ws = settings.world;
  ws.seed = scene.seed;
  auto hulls = std::make_shared<HullStore>();
  ws.onImpactComputed = [hulls, cap = settings.hullMaxVertices](ImpactTicket t, const ImpactResult& r) {
    if (!r.broken) return;
    std::vector<Hull> built;
    buildHulls(r, cap, built);
    hulls->put(t, std::move(built));
  };
  auto world = World::create(std::move(pack), ws);
  if (!world) return world.error();
  impl->sim = std::make_unique<Simulation>(std::move(world).value(), impl->scene, settings, hulls);
  impl->sim->setMaterials(std::move(materials));
  if (Status st = impl->sim->addFloor(); !st) return st.error();
  for (const SceneObject& o : impl->scene.objects)
    if (Status st = impl->sim->addObject(o); !st) return st.error();
  for (const RigidImpactor& imp : impl->scene.impactors) impl->sim->addImpactor(imp);
  // The objects' preparation (their K factorised on the World's workers) is part of loading, as a
  // level load would be: no first impact waits for it.
  if (Status st = impl->sim->waitUntilPrepared(); !st) return st.error();
  impl->sim->begin();
  impl->loadS = secondsSince(t0);
  return std::unique_ptr<PlaySession>(new PlaySession(std::move(impl)));
}

FrameStats PlaySession::stepFrame() { return mImpl->sim->stepFrame(); }
int64_t PlaySession::frame() const { return mImpl->sim->frame(); }
int64_t PlaySession::frameCount() const { return mImpl->sim->frameCount(); }
double PlaySession::timeS() const { return mImpl->sim->timeS(); }
const Scene& PlaySession::scene() const { return mImpl->scene; }
const PlayResult& PlaySession::progress() const { return mImpl->sim->progress(); }
std::vector<BodyView> PlaySession::bodies() const { return mImpl->sim->liveBodies(); }

Status PlaySession::throwSphere(const RigidImpactor& impactor) {
  auto bad = [](const std::string& what) { return makeError(ErrorCode::InvalidArgument, "throw: " + what); };
  if (impactor.shape != ImpactorShape::Sphere) return bad("only spheres are thrown");
  if (!(impactor.radiusM > 0.0 && std::isfinite(impactor.radiusM))) return bad("radius must be finite and > 0");
  if (!(impactor.massKg > 0.0 && std::isfinite(impactor.massKg))) return bad("mass must be finite and > 0");
  if (!impactor.positionWorldM.allFinite() || !impactor.velocityMps.allFinite() || !impactor.angularVelocityRadPerS.allFinite()) {
    return bad("position and velocities must be finite");
  }
  if (!materialPreset(impactor.material)) return makeError(ErrorCode::UnknownMaterial, "throw: unknown material '" + impactor.material + "'");
  mImpl->sim->throwImpactor(impactor);
  return Ok{};
}

PlayResult PlaySession::finish() {
  PlayResult r = mImpl->sim->finish();
  r.loadS = mImpl->loadS;
  return r;
}

Result<PlayResult> playScene(Pack pack, const Scene& scene, const PlayerSettings& settings) {
  auto session = PlaySession::create(std::move(pack), scene, settings);
  if (!session) return session.error();
  PlaySession& s = *session.value();
  while (s.frame() < s.frameCount()) s.stepFrame();
  return s.finish();
}

FrameTimeSummary summarizeFrameTimes(const std::vector<FrameStats>& frames) {
  FrameTimeSummary s;
  if (frames.empty()) return s;
  std::vector<double> t;
  t.reserve(frames.size());
  for (const FrameStats& f : frames) {
    t.push_back(f.bulletS + f.fractureS);
    s.bulletS += f.bulletS;
    s.fractureS += f.fractureS;
  }
  std::sort(t.begin(), t.end());
  auto quantile = [&](double q) { return t[std::min(t.size() - 1, static_cast<size_t>(std::ceil(q * static_cast<double>(t.size())) - 1))]; };
  s.medianS = quantile(0.5);
  s.p99S = quantile(0.99);
  s.maxS = t.back();
  return s;
}

}  // namespace brittle
