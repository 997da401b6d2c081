#include "brittle/runtime/FragmentSurfaces.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <array>
#include <string>
#include <unordered_map>

namespace brittle {
namespace {

struct Builder {
  const TetMesh& mesh;
  const TetTopology& topo;
  const Eigen::VectorXi& labels;
  const Eigen::VectorXd& cuts;
  std::vector<Eigen::Vector3d> points;           // nodes first, then created points
  std::vector<int32_t> edgePoint;                // per edge, −1 until created
  struct FaceHash {
    size_t operator()(const std::array<int32_t, 3>& v) const {
      return (static_cast<size_t>(v[0]) * 73856093u) ^ (static_cast<size_t>(v[1]) * 19349663u) ^
             (static_cast<size_t>(v[2]) * 83492791u);
    }
  };
  std::unordered_map<std::array<int32_t, 3>, int32_t, FaceHash> facePoint;
  std::vector<std::vector<std::array<int32_t, 3>>> triangles;  // per label, into points

  Builder(const TetMesh& m, const TetTopology& t, const Eigen::VectorXi& l, const Eigen::VectorXd& c, int labelCount)
      : mesh(m), topo(t), labels(l), cuts(c), edgePoint(static_cast<size_t>(t.edges.rows()), -1),
        triangles(static_cast<size_t>(labelCount)) {
    points.reserve(static_cast<size_t>(m.nodes.rows()));
    for (Eigen::Index i = 0; i < m.nodes.rows(); ++i) points.emplace_back(m.nodes.row(i).transpose());
  }

  bool mixed(int32_t edge) const { return labels[topo.edges(edge, 0)] != labels[topo.edges(edge, 1)]; }

  int32_t onEdge(int32_t edge) {
    int32_t& id = edgePoint[static_cast<size_t>(edge)];
    if (id < 0) {
      const double s = std::clamp(cuts[edge], 0.05, 0.95);
      const Eigen::Vector3d a = points[static_cast<size_t>(topo.edges(edge, 0))];
      const Eigen::Vector3d b = points[static_cast<size_t>(topo.edges(edge, 1))];
      id = static_cast<int32_t>(points.size());
      points.push_back(a + s * (b - a));
    }
    return id;
  }

  // The edge id joining two nodes of tet e (local ids).
  int32_t edgeOf(Eigen::Index e, int i, int j) const {
    for (int k = 0; k < 6; ++k) {
      if ((kTetEdges[k][0] == i && kTetEdges[k][1] == j) || (kTetEdges[k][0] == j && kTetEdges[k][1] == i)) {
        return topo.tetEdges(e, k);
      }
    }
    return -1;
  }

  // The point of a mixed face (three local nodes of tet e): mean of its mixed-edge points. Shared
  // by the two tets of an interior face, so it is keyed by the face's sorted node ids.
  int32_t onFace(Eigen::Index e, std::array<int, 3> local) {
    std::array<int32_t, 3> v{mesh.tets(e, local[0]), mesh.tets(e, local[1]), mesh.tets(e, local[2])};
    std::sort(v.begin(), v.end());
    auto [it, inserted] = facePoint.try_emplace(v, static_cast<int32_t>(points.size()));
    if (!inserted) return it->second;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    int count = 0;
    for (int k = 0; k < 3; ++k) {
      const int32_t edge = edgeOf(e, local[static_cast<size_t>(k)], local[static_cast<size_t>((k + 1) % 3)]);
      if (mixed(edge)) {
        sum += points[static_cast<size_t>(onEdge(edge))];
        ++count;
      }
    }
    it->second = static_cast<int32_t>(points.size());  // onEdge may have added points meanwhile
    points.push_back(sum / count);
    return it->second;
  }

  void fan(int label, const std::vector<int32_t>& polygon) {
    for (size_t k = 1; k + 1 < polygon.size(); ++k) {
      triangles[static_cast<size_t>(label)].push_back({polygon[0], polygon[k], polygon[k + 1]});
    }
  }

  void boundaryFace(size_t i) {
    const auto [e, f] = topo.boundaryFaces[i];
    const auto local = tetFaceNodes(f);
    std::array<int32_t, 3> node{}, label{};
    for (int k = 0; k < 3; ++k) {
      node[static_cast<size_t>(k)] = mesh.tets(e, local[static_cast<size_t>(k)]);
      label[static_cast<size_t>(k)] = labels[node[static_cast<size_t>(k)]];
    }
    if (label[0] == label[1] && label[1] == label[2]) {
      triangles[static_cast<size_t>(label[0])].push_back(node);
      return;
    }
    const int32_t center = onFace(e, local);
    // With three corners, the corners of one label are consecutive around the face: walk from the
    // first corner of each run to its last, then through the edge point after it, the face point
    // and the edge point before it.
    for (int start = 0; start < 3; ++start) {
      const int prev = (start + 2) % 3;
      if (label[static_cast<size_t>(prev)] == label[static_cast<size_t>(start)]) continue;  // not a run start
      std::vector<int32_t> polygon;
      int k = start;
      while (true) {
        polygon.push_back(node[static_cast<size_t>(k)]);
        const int next = (k + 1) % 3;
        if (label[static_cast<size_t>(next)] != label[static_cast<size_t>(start)]) {
          polygon.push_back(onEdge(edgeOf(e, local[static_cast<size_t>(k)], local[static_cast<size_t>(next)])));
          break;
        }
        k = next;
      }
      polygon.push_back(center);
      polygon.push_back(onEdge(edgeOf(e, local[static_cast<size_t>(prev)], local[static_cast<size_t>(start)])));
      fan(label[static_cast<size_t>(start)], polygon);
    }
  }

  void interior(Eigen::Index e) {
    std::array<int32_t, 6> edge{};
    bool any = false;
    for (int k = 0; k < 6; ++k) {
      edge[static_cast<size_t>(k)] = topo.tetEdges(e, k);
      any = any || mixed(edge[static_cast<size_t>(k)]);
    }
    if (!any) return;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    int count = 0;
    for (int32_t id : edge) {
      if (!mixed(id)) continue;
      sum += points[static_cast<size_t>(onEdge(id))];
      ++count;
    }
    const auto center = static_cast<int32_t>(points.size());
    points.push_back(sum / count);
    for (int k = 0; k < 6; ++k) {
      if (!mixed(edge[static_cast<size_t>(k)])) continue;
      const int i = kTetEdges[k][0], j = kTetEdges[k][1];
      int others[2], o = 0;
      for (int m = 0; m < 4; ++m) {
        if (m != i && m != j) others[o++] = m;
      }
      const int32_t p = onEdge(edge[static_cast<size_t>(k)]);
      const int32_t f1 = onFace(e, {i, j, others[0]});
      const int32_t f2 = onFace(e, {i, j, others[1]});
      std::vector<int32_t> quad = {p, f1, center, f2};
      // Orient the quad from node i's cell towards node j's.
      const Eigen::Vector3d normal = (points[static_cast<size_t>(center)] - points[static_cast<size_t>(p)])
                                         .cross(points[static_cast<size_t>(f2)] - points[static_cast<size_t>(f1)]);
      const Eigen::Vector3d along = mesh.nodes.row(mesh.tets(e, j)) - mesh.nodes.row(mesh.tets(e, i));
      if (normal.dot(along) < 0.0) std::swap(quad[1], quad[3]);
      fan(labels[mesh.tets(e, i)], quad);
      std::reverse(quad.begin(), quad.end());
      // Same diagonal (p, centre) for the other side: rotate so p leads again.
      std::rotate(quad.begin(), quad.begin() + 3, quad.end());
      fan(labels[mesh.tets(e, j)], quad);
    }
  }
};

}  // namespace

Result<std::vector<TriangleMesh>> buildFragmentSurfaces(const TetMesh& mesh, const TetTopology& topology,
                                                        const Eigen::VectorXi& nodeLabels, int labelCount,
                                                        const Eigen::VectorXd& edgeCuts) {
  if (nodeLabels.size() != mesh.nodes.rows() || edgeCuts.size() != topology.edges.rows() || labelCount < 1) {
    return makeError(ErrorCode::InvalidArgument, "fragment surfaces: label or cut arrays do not match the mesh");
  }
  if (nodeLabels.minCoeff() < 0 || nodeLabels.maxCoeff() >= labelCount) {
    return makeError(ErrorCode::InvalidArgument, "fragment surfaces: node label out of range");
  }
  for (Eigen::Index e = 0; e < topology.edges.rows(); ++e) {
    if (nodeLabels[topology.edges(e, 0)] != nodeLabels[topology.edges(e, 1)] && !std::isfinite(edgeCuts[e])) {
      return makeError(ErrorCode::InvalidArgument, "fragment surfaces: edge " + std::to_string(e) +
                                                       " joins two fragments but has no finite cut");
    }
  }
  Builder b(mesh, topology, nodeLabels, edgeCuts, labelCount);
  for (size_t i = 0; i < topology.boundaryFaces.size(); ++i) b.boundaryFace(i);
  for (Eigen::Index e = 0; e < mesh.tets.rows(); ++e) b.interior(e);

  std::vector<TriangleMesh> out(static_cast<size_t>(labelCount));
  std::vector<int32_t> local(b.points.size(), -1);
  for (int l = 0; l < labelCount; ++l) {
    const auto& tris = b.triangles[static_cast<size_t>(l)];
    if (tris.empty()) return makeError(ErrorCode::InvalidArgument, "fragment surfaces: label " + std::to_string(l) + " has no surface");
    std::vector<int32_t> used;
    for (const auto& t : tris) {
      for (int32_t p : t) {
        if (local[static_cast<size_t>(p)] < 0) {
          local[static_cast<size_t>(p)] = static_cast<int32_t>(used.size());
          used.push_back(p);
        }
      }
    }
    TriangleMesh& m = out[static_cast<size_t>(l)];
    m.vertices.resize(static_cast<Eigen::Index>(used.size()), 3);
    for (size_t i = 0; i < used.size(); ++i) m.vertices.row(static_cast<Eigen::Index>(i)) = b.points[static_cast<size_t>(used[i])].transpose();
    m.faces.resize(static_cast<Eigen::Index>(tris.size()), 3);
    for (size_t i = 0; i < tris.size(); ++i) {
      for (int k = 0; k < 3; ++k) m.faces(static_cast<Eigen::Index>(i), k) = local[static_cast<size_t>(tris[i][static_cast<size_t>(k)])];
    }
    for (int32_t p : used) local[static_cast<size_t>(p)] = -1;
  }
  return out;
}

}  // namespace brittle
