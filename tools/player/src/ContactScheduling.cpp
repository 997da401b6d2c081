// ContactScheduling.cpp — the play's contacts become runtime impacts: each breakable body's fastest
// contact in a step, capped per step and by the frame's fracture budget, submitted to the World's
// workers and collected and applied at a fixed latency, in submission order.
#include "Simulation.h"

#include <algorithm>
#include <map>
#include <string>

namespace brittle::play {

// Every breakable body's fastest new contact in this step (plus what waited), the fastest
// maxImpactsPerStep of them handed to the runtime, within the frame's fracture budget (spentS:
// fracture time this frame before this step). Returns whether a body broke.
bool Simulation::processContacts(int64_t frame, double timeS, double spentS, PlayResult& out) {
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

void Simulation::updateSiblingPairs() {
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

bool Simulation::breakable(int index, double timeS) const {
  if (index < 0) return false;
  const Body& b = mBodies[static_cast<size_t>(index)];
  return b.alive && b.object.valid() && !b.fracturing && timeS >= b.cooldownUntilS;
}

Eigen::Vector3d Simulation::pointVelocity(int index, const Eigen::Vector3d& point) const {
  if (index < 0) return Eigen::Vector3d::Zero();
  const Body& b = mBodies[static_cast<size_t>(index)];
  return b.preVelocity + b.preAngular.cross(point - b.com());
}

Candidate Simulation::candidate(int body, int other, double speed, const Eigen::Vector3d& pointWorld, const Eigen::Vector3d& normalWorld) const {
  Eigen::Matrix3d r;
  Eigen::Vector3d t;
  mBodies[static_cast<size_t>(body)].localPose(r, t);
  return Candidate{body, other, speed, r.transpose() * (pointWorld - t), r.transpose() * normalWorld};
}

bool Simulation::impact(const Candidate& c, int64_t frame, double timeS, bool fast, PlayResult& out) {
  Body& b = mBodies[static_cast<size_t>(c.body)];
  ImpactDesc d;
  d.object = b.object;
  d.pointWorld = b.runtimeRotation * c.pointLocal + b.runtimeTranslation;
  d.normalWorld = (b.runtimeRotation * c.normalLocal).normalized();
  d.speedMps = c.speedMps;
  d.pointToleranceM = mSettings.pointToleranceFraction * b.sizeM;
  d.flatPairRadiusM = b.sizeM;  // an edge or corner of the body's size meets the flat
  d.fast = fast;
  d.timeS = timeS;  // the scene's clock: a piece's later mesh check applies at a fixed time after its break
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
void Simulation::collectReady() {
  for (InFlight& f : mInFlight) {
    if (f.landing) continue;
    if (!mWorld.impactReady(f.ticket)) return;
    land(f);
  }
}

// Collects f's outcome (waiting if its work is not done), with the hulls built on the workers.
void Simulation::land(InFlight& f) {
  f.landing = std::make_shared<Landing>();
  Landing& l = *f.landing;
  l.status = mWorld.collectImpact(f.ticket, l.result);
  l.hullsBuilt = mHulls && mHulls->take(f.ticket, l.hulls) && l.hulls.size() == l.result.fragments.size();
}

// Submitted impacts due at the start of `frame`, in the order they were submitted: collected
// (waiting if not done) and applied. Returns whether a body broke.
bool Simulation::applyDue(int64_t frame, PlayResult& out) {
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

}  // namespace brittle::play
