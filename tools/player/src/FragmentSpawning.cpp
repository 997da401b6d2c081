// FragmentSpawning.cpp — an impact's outcome in the play: its figures in the event, and a broken
// body replaced by its fragments, which inherit its velocity field and its material.
#include "Simulation.h"

#include <string>

namespace brittle::play {

// An impact's outcome: the event's figures, and the fragments in place of a broken body.
// hulls: the fragments' hulls when they were built already.
bool Simulation::applyResult(const Status& st, const ImpactResult& r, const std::vector<Hull>* hulls, const Candidate& c,
                             int64_t frame, PlayResult& out, ImpactEvent& e, const InFlight* flight) {
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
void Simulation::spawnFragments(const ImpactResult& r, const std::vector<Hull>& hulls, const Candidate& c, int64_t frame,
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

}  // namespace brittle::play
