#include "brittle/runtime/QuadraticTetMesh.h"

#include <string>
#include <unordered_map>
#include <vector>

#include "brittle/runtime/TetTopology.h"

namespace brittle {

Result<QuadraticTetMesh> makeQuadraticTetMesh(const TetMesh& mesh) {
  const Eigen::Index n = mesh.nodes.rows(), t = mesh.tets.rows();
  if (t == 0) return makeError(ErrorCode::InvalidArgument, "quadratic tet mesh: no tetrahedra");
  if (mesh.tets.minCoeff() < 0 || mesh.tets.maxCoeff() >= n) {
    return makeError(ErrorCode::InvalidArgument, "quadratic tet mesh: node index out of range (" + std::to_string(n) + " nodes)");
  }
  // Edge ids in order of first appearance over (tet, kTetEdges); the map only looks them up.
  std::unordered_map<uint64_t, int32_t> edgeIds;
  edgeIds.reserve(static_cast<size_t>(t) * 2);
  std::vector<std::array<int32_t, 2>> edges;
  edges.reserve(static_cast<size_t>(t) * 2);
  Eigen::Matrix<int32_t, Eigen::Dynamic, 6, Eigen::RowMajor> tetEdges(t, 6);
  for (Eigen::Index e = 0; e < t; ++e) {
    for (int k = 0; k < 6; ++k) {
      int32_t p = mesh.tets(e, kTetEdges[k][0]), q = mesh.tets(e, kTetEdges[k][1]);
      if (p > q) std::swap(p, q);
      const uint64_t key = (static_cast<uint64_t>(p) << 32) | static_cast<uint32_t>(q);
      auto [it, inserted] = edgeIds.try_emplace(key, static_cast<int32_t>(edges.size()));
      if (inserted) edges.push_back({p, q});
      tetEdges(e, k) = it->second;
    }
  }
  // Local edge k of kQuadraticTetEdges as an index into kTetEdges.
  std::array<int, 6> fromTetEdge{};
  for (int k = 0; k < 6; ++k) {
    for (int j = 0; j < 6; ++j) {
      const auto [a, b] = kQuadraticTetEdges[static_cast<size_t>(k)];
      const auto [c, d] = kTetEdges[static_cast<size_t>(j)];
      if ((a == c && b == d) || (a == d && b == c)) fromTetEdge[static_cast<size_t>(k)] = j;
    }
  }
  QuadraticTetMesh out;
  const auto edgeCount = static_cast<Eigen::Index>(edges.size());
  out.nodes.resize(n + edgeCount, 3);
  out.nodes.topRows(n) = mesh.nodes;
  for (Eigen::Index i = 0; i < edgeCount; ++i) {
    const auto& [p, q] = edges[static_cast<size_t>(i)];
    out.nodes.row(n + i) = 0.5 * (mesh.nodes.row(p) + mesh.nodes.row(q));
  }
  out.tets.resize(t, 10);
  out.tets.leftCols<4>() = mesh.tets;
  for (Eigen::Index e = 0; e < t; ++e) {
    for (int k = 0; k < 6; ++k) out.tets(e, 4 + k) = static_cast<int32_t>(n) + tetEdges(e, fromTetEdge[static_cast<size_t>(k)]);
  }
  return out;
}

TetMesh linearTetMesh(const QuadraticTetMesh& mesh, Eigen::Index cornerNodes) {
  TetMesh out;
  out.nodes = mesh.nodes.topRows(cornerNodes);
  out.tets = mesh.tets.leftCols<4>();
  return out;
}

}  // namespace brittle
