#include "brittle/runtime/QuadraticTetMesh.h"

#include <gtest/gtest.h>

#include <map>
#include <utility>

#include "brittle/runtime/TetTopology.h"
#include "brittle/testing/Fixtures.h"

namespace brittle {
namespace {

TEST(QuadraticTetMesh, OneTetGetsItsMidEdgeNodesInTheC3d10Order) {
  TetMesh tet;
  tet.nodes.resize(4, 3);
  tet.nodes << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1;
  tet.tets.resize(1, 4);
  tet.tets << 0, 1, 2, 3;
  const QuadraticTetMesh q = makeQuadraticTetMesh(tet).value();
  ASSERT_EQ(q.nodes.rows(), 10);
  // Mid-edge nodes are numbered in kTetEdges order, (0,1) (0,2) (0,3) (1,2) (1,3) (2,3) → 4..9;
  // the connectivity lists them in the C3D10 order (0,1) (1,2) (2,0) (0,3) (1,3) (2,3).
  Eigen::Matrix<int32_t, 1, 10> expected;
  expected << 0, 1, 2, 3, 4, 7, 5, 6, 8, 9;
  EXPECT_EQ(q.tets.row(0), expected);
  EXPECT_TRUE(q.nodes.row(7).isApprox(Eigen::RowVector3d(0.5, 0.5, 0.0)));
}

TEST(QuadraticTetMesh, MidEdgeNodesAreSharedAndFollowTheTopologysEdges) {
  const TetMesh mesh = testing::makeBoxTetMesh(0.3, 0.2, 0.1, 3, 2, 2);
  const QuadraticTetMesh q = makeQuadraticTetMesh(mesh).value();
  const TetTopology topo = buildTetTopology(mesh).value();
  const Eigen::Index n = mesh.nodes.rows();
  ASSERT_EQ(q.nodes.rows(), n + topo.edges.rows());
  ASSERT_EQ(q.tets.rows(), mesh.tets.rows());
  EXPECT_EQ(q.nodes.topRows(n), mesh.nodes);
  EXPECT_EQ(q.tets.leftCols<4>(), mesh.tets);
  // Mid-edge node of topology edge e is node N + e, at the edge's midpoint.
  for (Eigen::Index e = 0; e < topo.edges.rows(); ++e) {
    const Eigen::RowVector3d mid = 0.5 * (mesh.nodes.row(topo.edges(e, 0)) + mesh.nodes.row(topo.edges(e, 1)));
    EXPECT_EQ(q.nodes.row(n + e), mid) << "edge " << e;
  }
  // Every tet's mid-edge node is the one of its edge: one node per edge, shared by all its tets.
  std::map<std::pair<int32_t, int32_t>, int32_t> nodeOfEdge;
  for (Eigen::Index t = 0; t < q.tets.rows(); ++t) {
    for (int k = 0; k < 6; ++k) {
      auto [i, j] = kQuadraticTetEdges[static_cast<size_t>(k)];
      auto key = std::minmax(q.tets(t, i), q.tets(t, j));
      auto [it, inserted] = nodeOfEdge.try_emplace(key, q.tets(t, 4 + k));
      EXPECT_EQ(it->second, q.tets(t, 4 + k)) << "tet " << t << " edge " << k;
      EXPECT_EQ(q.nodes.row(q.tets(t, 4 + k)), 0.5 * (q.nodes.row(q.tets(t, i)) + q.nodes.row(q.tets(t, j))));
    }
  }
  EXPECT_EQ(static_cast<Eigen::Index>(nodeOfEdge.size()), topo.edges.rows());
  // The corners and tets come back unchanged.
  const TetMesh back = linearTetMesh(q, n);
  EXPECT_EQ(back.nodes, mesh.nodes);
  EXPECT_EQ(back.tets, mesh.tets);
}

TEST(QuadraticTetMesh, RejectsEmptyMeshesAndIndicesOutOfRange) {
  EXPECT_EQ(makeQuadraticTetMesh(TetMesh{}).error().code, ErrorCode::InvalidArgument);
  TetMesh mesh = testing::makeFiveTetBox(1, 1, 1);
  mesh.tets(3, 2) = 8;
  EXPECT_EQ(makeQuadraticTetMesh(mesh).error().code, ErrorCode::InvalidArgument);
  mesh.tets(3, 2) = -1;
  EXPECT_EQ(makeQuadraticTetMesh(mesh).error().code, ErrorCode::InvalidArgument);
}

}  // namespace
}  // namespace brittle
