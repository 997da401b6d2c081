#include "brittle/runtime/QuadraticTetMesh.h"

#include <string>
#include <vector>

#include "brittle/runtime/TetTopology.h"

namespace brittle {

Result<QuadraticTetMesh> makeQuadraticTetMesh(const TetMesh& mesh) {
  const Eigen::Index n = mesh.nodes.rows(), t = mesh.tets.rows();
  if (t == 0) return makeError(ErrorCode::InvalidArgument, "quadratic tet mesh: no tetrahedra");
  if (mesh.tets.minCoeff() < 0 || mesh.tets.maxCoeff() >= n) {
    return makeError(ErrorCode::InvalidArgument, "quadratic tet mesh: node index out of range (" + std::to_string(n) + " nodes)");
  }
  const TetEdges numbered = numberTetEdges(mesh.tets);  // TetTopology's numbering: mid-node of edge e is N + e
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
  const Eigen::Index edgeCount = numbered.edges.rows();
  out.nodes.resize(n + edgeCount, 3);
  out.nodes.topRows(n) = mesh.nodes;
  for (Eigen::Index i = 0; i < edgeCount; ++i) {
    out.nodes.row(n + i) = 0.5 * (mesh.nodes.row(numbered.edges(i, 0)) + mesh.nodes.row(numbered.edges(i, 1)));
  }
  out.tets.resize(t, 10);
  out.tets.leftCols<4>() = mesh.tets;
  for (Eigen::Index e = 0; e < t; ++e) {
    for (int k = 0; k < 6; ++k) out.tets(e, 4 + k) = static_cast<int32_t>(n) + numbered.tetEdges(e, fromTetEdge[static_cast<size_t>(k)]);
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
