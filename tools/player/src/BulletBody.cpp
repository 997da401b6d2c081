// BulletBody.cpp — principal frames, asset surfaces and box overlap for the player's bodies.
#include "BulletBody.h"

#include <Eigen/Eigenvalues>
#include <algorithm>

namespace brittle::play {

void principalAxes(const Eigen::Matrix3d& inertia, Eigen::Matrix3d& axes, Eigen::Vector3d& moments) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig3(0.5 * (inertia + inertia.transpose()));
  axes = eig3.eigenvectors();
  if (axes.determinant() < 0.0) axes.col(2) *= -1.0;
  moments = eig3.eigenvalues().cwiseMax(1e-6 * std::max(eig3.eigenvalues().maxCoeff(), 1e-300));
}

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

bool aabbsOverlap(const btRigidBody& a, const btRigidBody& b) {
  btVector3 amin, amax, bmin, bmax;
  a.getAabb(amin, amax);
  b.getAabb(bmin, bmax);
  for (int k = 0; k < 3; ++k)
    if (amax[k] < bmin[k] || bmax[k] < amin[k]) return false;
  return true;
}

}  // namespace brittle::play
