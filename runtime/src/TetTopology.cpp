#include "brittle/runtime/TetTopology.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <string>
#include <unordered_map>

#include "brittle/descriptors/MassProperties.h"

namespace brittle {

std::array<int, 3> tetFaceNodes(int face) {
  // For a positive tet (0,1,2,3), these triangles wind counter-clockwise seen from outside.
  static constexpr std::array<std::array<int, 3>, 4> kFaces = {{{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}}};
  return kFaces[static_cast<size_t>(face)];
}

TetEdges numberTetEdges(const Tetrahedra& tets) {
  const Eigen::Index t = tets.rows();
  std::unordered_map<uint64_t, int32_t> edgeIds;  // only looked up: the order is the tets'
  edgeIds.reserve(static_cast<size_t>(t) * 2);
  std::vector<std::array<int32_t, 2>> edges;
  edges.reserve(static_cast<size_t>(t) * 2);
  TetEdges out;
  out.tetEdges.resize(t, 6);
  for (Eigen::Index e = 0; e < t; ++e) {
    for (int k = 0; k < 6; ++k) {
      int32_t p = tets(e, kTetEdges[static_cast<size_t>(k)][0]), q = tets(e, kTetEdges[static_cast<size_t>(k)][1]);
      if (p > q) std::swap(p, q);
      const uint64_t key = (static_cast<uint64_t>(p) << 32) | static_cast<uint32_t>(q);
      auto [it, inserted] = edgeIds.try_emplace(key, static_cast<int32_t>(edges.size()));
      if (inserted) edges.push_back({p, q});
      out.tetEdges(e, k) = it->second;
    }
  }
  out.edges.resize(static_cast<Eigen::Index>(edges.size()), 2);
  for (size_t i = 0; i < edges.size(); ++i) out.edges.row(static_cast<Eigen::Index>(i)) << edges[i][0], edges[i][1];
  return out;
}

namespace {

// The tet's signed volume, an error unless it is positive.
Status measureTet(const TetMesh& mesh, Eigen::Index e, double& volume) {
  const Eigen::Vector3d a = mesh.nodes.row(mesh.tets(e, 0)), b = mesh.nodes.row(mesh.tets(e, 1)),
                        c = mesh.nodes.row(mesh.tets(e, 2)), d = mesh.nodes.row(mesh.tets(e, 3));
  volume = signedTetVolume(a, b, c, d);
  if (!(volume > 0.0)) {
    return makeError(ErrorCode::InvalidArgument, "tet topology: tet " + std::to_string(e) + " is not positively oriented");
  }
  return Ok{};
}

// The mean edge length, the boundary triangles' node areas and the volume, from the connectivity
// (edges, boundary faces) and the tets' volumes already in topo.
void measureTopology(const TetMesh& mesh, TetTopology& topo) {
  double edgeLength = 0.0;
  for (Eigen::Index i = 0; i < topo.edges.rows(); ++i) {
    edgeLength += (mesh.nodes.row(topo.edges(i, 0)) - mesh.nodes.row(topo.edges(i, 1))).norm();
  }
  topo.meanEdgeLengthM = edgeLength / static_cast<double>(topo.edges.rows());
  topo.nodeAreasM2.setZero(mesh.nodes.rows());
  for (Eigen::Index i = 0; i < topo.boundaryTriangles.rows(); ++i) {
    const Eigen::Vector3d a = mesh.nodes.row(topo.boundaryTriangles(i, 0));
    const Eigen::Vector3d b = mesh.nodes.row(topo.boundaryTriangles(i, 1));
    const Eigen::Vector3d c = mesh.nodes.row(topo.boundaryTriangles(i, 2));
    const double area = 0.5 * (b - a).cross(c - a).norm();
    for (int k = 0; k < 3; ++k) topo.nodeAreasM2[topo.boundaryTriangles(i, k)] += area / 3.0;
  }
  topo.volumeM3 = topo.tetVolumesM3.sum();
}

Status checkNodeIds(const TetMesh& mesh) {
  if (mesh.tets.rows() == 0) return makeError(ErrorCode::InvalidArgument, "tet topology: no tetrahedra");
  if (mesh.tets.minCoeff() < 0 || mesh.tets.maxCoeff() >= mesh.nodes.rows()) {
    return makeError(ErrorCode::InvalidArgument, "tet topology: node index out of range");
  }
  return Ok{};
}

}  // namespace

Result<TetTopology> buildTetTopology(const TetMesh& mesh) {
  if (Status st = checkNodeIds(mesh); !st) return st.error();
  const auto t = mesh.tets.rows();
  TetTopology topo;
  TetEdges numbered = numberTetEdges(mesh.tets);
  topo.edges = std::move(numbered.edges);
  topo.tetEdges = std::move(numbered.tetEdges);
  topo.neighbours.setConstant(t, 4, -1);
  topo.tetVolumesM3.resize(t);
  // Faces keyed by their sorted nodes; the value is the first (tet, face) seen.
  struct FaceKey {
    std::array<int32_t, 3> v;
    bool operator==(const FaceKey&) const = default;
  };
  struct FaceHash {
    size_t operator()(const FaceKey& k) const {
      return (static_cast<size_t>(k.v[0]) * 73856093u) ^ (static_cast<size_t>(k.v[1]) * 19349663u) ^
             (static_cast<size_t>(k.v[2]) * 83492791u);
    }
  };
  std::unordered_map<FaceKey, std::array<int32_t, 2>, FaceHash> faces;
  faces.reserve(static_cast<size_t>(t) * 3);
  for (Eigen::Index e = 0; e < t; ++e) {
    if (Status st = measureTet(mesh, e, topo.tetVolumesM3[e]); !st) return st.error();
    for (int f = 0; f < 4; ++f) {
      const auto local = tetFaceNodes(f);
      FaceKey key{{mesh.tets(e, local[0]), mesh.tets(e, local[1]), mesh.tets(e, local[2])}};
      std::sort(key.v.begin(), key.v.end());
      auto [it, inserted] = faces.try_emplace(key, std::array<int32_t, 2>{static_cast<int32_t>(e), f});
      if (inserted) continue;
      const auto [other, otherFace] = it->second;
      if (other < 0 || topo.neighbours(other, otherFace) >= 0) {
        return makeError(ErrorCode::InvalidArgument, "tet topology: a face of tet " + std::to_string(e) +
                                                         " is shared by more than two tets");
      }
      topo.neighbours(e, f) = other;
      topo.neighbours(other, otherFace) = static_cast<int32_t>(e);
    }
  }
  for (Eigen::Index e = 0; e < t; ++e) {
    for (int f = 0; f < 4; ++f) {
      if (topo.neighbours(e, f) < 0) topo.boundaryFaces.push_back({static_cast<int32_t>(e), f});
    }
  }
  topo.boundaryTriangles.resize(static_cast<Eigen::Index>(topo.boundaryFaces.size()), 3);
  for (size_t i = 0; i < topo.boundaryFaces.size(); ++i) {
    const auto [e, f] = topo.boundaryFaces[i];
    const auto local = tetFaceNodes(f);
    for (int k = 0; k < 3; ++k) topo.boundaryTriangles(static_cast<Eigen::Index>(i), k) = mesh.tets(e, local[static_cast<size_t>(k)]);
  }
  measureTopology(mesh, topo);
  return topo;
}

Result<TetTopology> buildTetTopology(const TetMesh& mesh, const TetTopology& sameTets) {
  if (Status st = checkNodeIds(mesh); !st) return st.error();
  const auto t = mesh.tets.rows();
  const auto n = mesh.nodes.rows();
  const auto faces = static_cast<Eigen::Index>(sameTets.boundaryFaces.size());
  if (sameTets.tetEdges.rows() != t || sameTets.neighbours.rows() != t || sameTets.edges.rows() == 0 ||
      sameTets.edges.maxCoeff() >= n || sameTets.boundaryTriangles.rows() != faces ||
      (faces > 0 && sameTets.boundaryTriangles.maxCoeff() >= n)) {
    return makeError(ErrorCode::InvalidArgument, "tet topology: the connectivity given is not of a mesh of these " +
                                                     std::to_string(t) + " tets and " + std::to_string(mesh.nodes.rows()) + " nodes");
  }
  TetTopology topo;
  topo.edges = sameTets.edges;
  topo.tetEdges = sameTets.tetEdges;
  topo.neighbours = sameTets.neighbours;
  topo.boundaryFaces = sameTets.boundaryFaces;
  topo.boundaryTriangles = sameTets.boundaryTriangles;
  topo.tetVolumesM3.resize(t);
  for (Eigen::Index e = 0; e < t; ++e) {
    if (Status st = measureTet(mesh, e, topo.tetVolumesM3[e]); !st) return st.error();
  }
  measureTopology(mesh, topo);
  return topo;
}

}  // namespace brittle
