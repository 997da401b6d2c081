#include "brittle/precompute/TetMeshQuality.h"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <limits>
#include <numbers>
#include <numeric>
#include <vector>

#include "brittle/descriptors/MassProperties.h"

namespace brittle {
namespace {

// Faces of tet (0,1,2,3) oriented outward when the tet is positive.
constexpr int kTetFaces[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};

Eigen::Vector3d node(const TetMesh& m, int32_t i) { return m.nodes.row(i).transpose(); }

}  // namespace

MeshQuality computeMeshQuality(const TetMesh& mesh) {
  MeshQuality q;
  q.nodeCount = mesh.nodes.rows();
  q.tetCount = mesh.tets.rows();
  q.surfaceFaceCount = boundaryFaces(mesh).rows();
  q.minDihedralDeg = 180.0;
  q.maxDihedralDeg = 0.0;
  q.minTetVolumeM3 = std::numeric_limits<double>::infinity();
  double sumRatio = 0.0;
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
    std::array<Eigen::Vector3d, 4> p;
    for (int k = 0; k < 4; ++k) p[k] = node(mesh, mesh.tets(t, k));
    q.minTetVolumeM3 = std::min(q.minTetVolumeM3, signedTetVolume(p[0], p[1], p[2], p[3]));
    // Outward face normals; the dihedral angle at the edge shared by faces i and j is
    // π − angle(n_i, n_j).
    std::array<Eigen::Vector3d, 4> n;
    for (int f = 0; f < 4; ++f) {
      n[f] = (p[kTetFaces[f][1]] - p[kTetFaces[f][0]]).cross(p[kTetFaces[f][2]] - p[kTetFaces[f][0]]).normalized();
    }
    for (int i = 0; i < 4; ++i) {
      for (int j = i + 1; j < 4; ++j) {
        const double c = std::clamp(-n[i].dot(n[j]), -1.0, 1.0);
        const double angle = std::acos(c) * 180.0 / std::numbers::pi;
        q.minDihedralDeg = std::min(q.minDihedralDeg, angle);
        q.maxDihedralDeg = std::max(q.maxDihedralDeg, angle);
      }
    }
    // Circumcentre c solves 2(p_k − p_0)·c = |p_k|² − |p_0|², k = 1..3.
    Eigen::Matrix3d a;
    Eigen::Vector3d b;
    for (int k = 1; k < 4; ++k) {
      a.row(k - 1) = 2.0 * (p[k] - p[0]).transpose();
      b(k - 1) = p[k].squaredNorm() - p[0].squaredNorm();
    }
    const Eigen::Vector3d center = a.fullPivLu().solve(b);
    const double radius = (center - p[0]).norm();
    double shortest = std::numeric_limits<double>::infinity();
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) shortest = std::min(shortest, (p[i] - p[j]).norm());
    const double ratio = radius / shortest;
    q.maxRadiusEdgeRatio = std::max(q.maxRadiusEdgeRatio, ratio);
    sumRatio += ratio;
  }
  q.meanRadiusEdgeRatio = mesh.tets.rows() > 0 ? sumRatio / static_cast<double>(mesh.tets.rows()) : 0.0;
  if (mesh.tets.rows() == 0) q.minTetVolumeM3 = 0.0;
  return q;
}

Triangles boundaryFaces(const TetMesh& mesh) {
  // Key each face by its sorted corners; a face seen once is on the boundary.
  std::map<std::array<int32_t, 3>, std::pair<int, std::array<int32_t, 3>>> faces;
  std::vector<std::array<int32_t, 3>> order;
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
    for (const auto& f : kTetFaces) {
      std::array<int32_t, 3> face = {mesh.tets(t, f[0]), mesh.tets(t, f[1]), mesh.tets(t, f[2])};
      std::array<int32_t, 3> key = face;
      std::sort(key.begin(), key.end());
      auto [it, inserted] = faces.emplace(key, std::make_pair(0, face));
      ++it->second.first;
      if (inserted) order.push_back(key);
    }
  }
  std::vector<std::array<int32_t, 3>> out;
  for (const auto& key : order) {
    const auto& entry = faces.at(key);
    if (entry.first == 1) out.push_back(entry.second);
  }
  Triangles result(static_cast<Eigen::Index>(out.size()), 3);
  for (size_t i = 0; i < out.size(); ++i) {
    result.row(static_cast<Eigen::Index>(i)) << out[i][0], out[i][1], out[i][2];
  }
  return result;
}

std::vector<int32_t> labelFaceConnectedComponents(const TetMesh& mesh) {
  const auto count = static_cast<size_t>(mesh.tets.rows());
  std::vector<int64_t> parent(count);
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int64_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  std::map<std::array<int32_t, 3>, int64_t> firstTetOfFace;
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
    for (const auto& f : kTetFaces) {
      std::array<int32_t, 3> key = {mesh.tets(t, f[0]), mesh.tets(t, f[1]), mesh.tets(t, f[2])};
      std::sort(key.begin(), key.end());
      auto [it, inserted] = firstTetOfFace.emplace(key, t);
      if (!inserted) {
        const int64_t a = find(it->second), b = find(t);
        if (a != b) parent[std::max(a, b)] = std::min(a, b);
      }
    }
  }
  // Roots are each group's smallest tet, so numbering roots in tet order numbers groups by their
  // first tet.
  std::vector<int32_t> labels(count, -1);
  int32_t next = 0;
  for (size_t t = 0; t < count; ++t) {
    const auto root = static_cast<size_t>(find(static_cast<int64_t>(t)));
    if (root == t) labels[t] = next++;
    labels[t] = labels[root];
  }
  return labels;
}

int64_t countFaceConnectedComponents(const TetMesh& mesh) {
  const auto labels = labelFaceConnectedComponents(mesh);
  return labels.empty() ? 0 : int64_t{*std::max_element(labels.begin(), labels.end())} + 1;
}

TetMesh compactNodes(const TetMesh& mesh) {
  std::vector<int32_t> newIndex(static_cast<size_t>(mesh.nodes.rows()), -1);
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t)
    for (int k = 0; k < 4; ++k) newIndex[mesh.tets(t, k)] = 0;
  int32_t next = 0;
  for (auto& i : newIndex)
    if (i == 0) i = next++;
  TetMesh out;
  out.nodes.resize(next, 3);
  for (size_t i = 0; i < newIndex.size(); ++i) {
    if (newIndex[i] >= 0) out.nodes.row(newIndex[i]) = mesh.nodes.row(static_cast<Eigen::Index>(i));
  }
  out.tets.resize(mesh.tets.rows(), 4);
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t)
    for (int k = 0; k < 4; ++k) out.tets(t, k) = newIndex[mesh.tets(t, k)];
  return out;
}

}  // namespace brittle
