// Recording.cpp — what the play reports of its bodies: pose tracks, energy, lowest points.
#include "Simulation.h"

#include <algorithm>

namespace brittle::play {

void Simulation::energy(double& total, double& kinetic) const {
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

double Simulation::lowestPoint(const Body& b) const {
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

void Simulation::recordPose(Body& b) {
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
void Simulation::recordPoses(int64_t sample) {
  for (Body& b : mBodies)
    if (b.alive && b.state.firstFrame <= sample) recordPose(b);
}

}  // namespace brittle::play
