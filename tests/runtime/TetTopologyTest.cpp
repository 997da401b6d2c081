// TetTopology.h: edges, face neighbours, outward boundary faces, volumes and node areas, on a cube
// cut into five tets (counted by hand) and on a generated box mesh (counted by formula).
#include "brittle/runtime/TetTopology.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <map>
#include <set>

#include "brittle/descriptors/MassProperties.h"
#include "brittle/testing/Fixtures.h"

namespace brittle {
namespace {

using FaceKey = std::array<int32_t, 3>;

FaceKey sortedFace(const TetMesh& mesh, Eigen::Index tet, int face) {
  const auto local = tetFaceNodes(face);
  FaceKey key{mesh.tets(tet, local[0]), mesh.tets(tet, local[1]), mesh.tets(tet, local[2])};
  std::sort(key.begin(), key.end());
  return key;
}

// The invariants that hold on any valid mesh.
void expectConsistent(const TetMesh& mesh, const TetTopology& topo) {
  const Eigen::Index t = mesh.tets.rows();
  ASSERT_EQ(topo.tetEdges.rows(), t);
  ASSERT_EQ(topo.neighbours.rows(), t);
  // Edges: (low, high), each once, and each tet's edge k joins its nodes kTetEdges[k].
  std::set<std::pair<int32_t, int32_t>> edges;
  for (Eigen::Index e = 0; e < topo.edges.rows(); ++e) {
    EXPECT_LT(topo.edges(e, 0), topo.edges(e, 1));
    EXPECT_TRUE(edges.insert({topo.edges(e, 0), topo.edges(e, 1)}).second) << "edge " << e << " twice";
  }
  for (Eigen::Index e = 0; e < t; ++e) {
    for (int k = 0; k < 6; ++k) {
      const int32_t a = mesh.tets(e, kTetEdges[k][0]), b = mesh.tets(e, kTetEdges[k][1]);
      const int32_t id = topo.tetEdges(e, k);
      EXPECT_EQ(topo.edges(id, 0), std::min(a, b));
      EXPECT_EQ(topo.edges(id, 1), std::max(a, b));
    }
  }
  // Faces: each is shared by one tet (boundary) or two (then they are each other's neighbours
  // across it).
  std::map<FaceKey, std::vector<std::pair<Eigen::Index, int>>> faces;
  for (Eigen::Index e = 0; e < t; ++e) {
    for (int f = 0; f < 4; ++f) faces[sortedFace(mesh, e, f)].push_back({e, f});
  }
  size_t boundary = 0;
  for (const auto& [key, tets] : faces) {
    ASSERT_LE(tets.size(), 2u);
    if (tets.size() == 1) {
      ++boundary;
      EXPECT_EQ(topo.neighbours(tets[0].first, tets[0].second), -1);
    } else {
      EXPECT_EQ(topo.neighbours(tets[0].first, tets[0].second), tets[1].first);
      EXPECT_EQ(topo.neighbours(tets[1].first, tets[1].second), tets[0].first);
    }
  }
  EXPECT_EQ(topo.boundaryFaces.size(), boundary);
  ASSERT_EQ(topo.boundaryTriangles.rows(), static_cast<Eigen::Index>(boundary));
  // Boundary triangles point away from the node their tet leaves out, and together bound the
  // solid: closed, oriented, enclosing the tets' volume.
  for (size_t i = 0; i < topo.boundaryFaces.size(); ++i) {
    const auto [e, f] = topo.boundaryFaces[i];
    const Eigen::Index row = static_cast<Eigen::Index>(i);
    const Eigen::Vector3d a = mesh.nodes.row(topo.boundaryTriangles(row, 0)), b = mesh.nodes.row(topo.boundaryTriangles(row, 1)),
                          c = mesh.nodes.row(topo.boundaryTriangles(row, 2)), apex = mesh.nodes.row(mesh.tets(e, f));
    EXPECT_LT((b - a).cross(c - a).dot(apex - a), 0.0) << "boundary face " << i;
  }
  const TriangleMesh surface{mesh.nodes, topo.boundaryTriangles};
  EXPECT_TRUE(testing::isClosedAndOriented(surface));
  EXPECT_NEAR(computeSurfaceMassProperties(surface, 1.0).volumeM3, topo.volumeM3, 1e-12 * topo.volumeM3);
  EXPECT_NEAR(topo.tetVolumesM3.sum(), topo.volumeM3, 1e-15 * topo.volumeM3);
  EXPECT_GT(topo.tetVolumesM3.minCoeff(), 0.0);
  // Mean edge length, from the edge list.
  double length = 0.0;
  for (Eigen::Index e = 0; e < topo.edges.rows(); ++e) length += (mesh.nodes.row(topo.edges(e, 0)) - mesh.nodes.row(topo.edges(e, 1))).norm();
  EXPECT_NEAR(topo.meanEdgeLengthM, length / static_cast<double>(topo.edges.rows()), 1e-15);
}

TEST(TetTopology, FaceNodesPointAwayFromTheOppositeNode) {
  // The reference tet (0,0,0), (1,0,0), (0,1,0), (0,0,1): face i leaves out node i.
  const Eigen::Matrix<double, 4, 3> x = (Eigen::Matrix<double, 4, 3>() << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1).finished();
  for (int face = 0; face < 4; ++face) {
    const auto n = tetFaceNodes(face);
    EXPECT_EQ(std::count(n.begin(), n.end(), face), 0);
    const Eigen::Vector3d a = x.row(n[0]), b = x.row(n[1]), c = x.row(n[2]), apex = x.row(face);
    EXPECT_LT((b - a).cross(c - a).dot(apex - a), 0.0) << "face " << face;
  }
}

TEST(TetTopology, CubeInFiveTets) {
  const double sx = 0.3, sy = 0.2, sz = 0.1, volume = sx * sy * sz;
  const TetMesh mesh = testing::makeFiveTetBox(sx, sy, sz);
  auto built = buildTetTopology(mesh);
  ASSERT_TRUE(built) << built.error().message;
  const TetTopology& topo = built.value();
  expectConsistent(mesh, topo);
  // 12 cube edges and one diagonal per face; two triangles per face; 20 tet faces, 12 of them on
  // the boundary, the other 8 paired into the central tet's 4.
  EXPECT_EQ(topo.edges.rows(), 12 + 6);
  EXPECT_EQ(topo.boundaryFaces.size(), 12u);
  for (int f = 0; f < 4; ++f) EXPECT_GE(topo.neighbours(0, f), 1) << "the central tet has a neighbour across every face";
  for (Eigen::Index e = 1; e < 5; ++e) {
    EXPECT_EQ((topo.neighbours.row(e).array() == 0).count(), 1) << "corner tet " << e;
    EXPECT_EQ((topo.neighbours.row(e).array() == -1).count(), 3) << "corner tet " << e;
  }
  EXPECT_NEAR(topo.volumeM3, volume, 1e-15);
  EXPECT_NEAR(topo.tetVolumesM3[0], volume / 3, 1e-16);
  for (Eigen::Index e = 1; e < 5; ++e) EXPECT_NEAR(topo.tetVolumesM3[e], volume / 6, 1e-16);
  // Node areas: a face's two triangles (half the face each) share the diagonal between two odd
  // corners, so an odd corner (1, 2, 4, 7) touches both triangles of its three faces, an even one
  // only one: A/3 per face against A/6.
  const double xy = sx * sy, yz = sy * sz, xz = sx * sz;
  for (int i = 0; i < 8; ++i) {
    const bool odd = i == 1 || i == 2 || i == 4 || i == 7;
    EXPECT_NEAR(topo.nodeAreasM2[i], (xy + yz + xz) / (odd ? 3.0 : 6.0), 1e-15) << "node " << i;
  }
  EXPECT_NEAR(topo.nodeAreasM2.sum(), 2 * (xy + yz + xz), 1e-15);
}

TEST(TetTopology, GeneratedBoxMatchesTheCountingFormulas) {
  // nx × ny × nz cells of 6 Kuhn tets.
  const int nx = 3, ny = 2, nz = 2;
  const double sx = 0.3, sy = 0.2, sz = 0.1;
  const TetMesh mesh = testing::makeBoxTetMesh(sx, sy, sz, nx, ny, nz);
  auto built = buildTetTopology(mesh);
  ASSERT_TRUE(built) << built.error().message;
  const TetTopology& topo = built.value();
  expectConsistent(mesh, topo);
  EXPECT_EQ(mesh.tets.rows(), 6 * nx * ny * nz);
  // Edges: along the axes, one diagonal per grid square, one diagonal per cell.
  const int axis = nx * (ny + 1) * (nz + 1) + (nx + 1) * ny * (nz + 1) + (nx + 1) * (ny + 1) * nz;
  const int squares = nx * ny * (nz + 1) + nx * (ny + 1) * nz + (nx + 1) * ny * nz;
  EXPECT_EQ(topo.edges.rows(), axis + squares + nx * ny * nz);
  // Two triangles per boundary square.
  EXPECT_EQ(topo.boundaryFaces.size(), static_cast<size_t>(4 * (nx * ny + ny * nz + nx * nz)));
  // Euler for a ball: V − E + F − T = 1, F counting each face once.
  const Eigen::Index faces = (4 * mesh.tets.rows() + static_cast<Eigen::Index>(topo.boundaryFaces.size())) / 2;
  EXPECT_EQ(mesh.nodes.rows() - topo.edges.rows() + faces - mesh.tets.rows(), 1);
  EXPECT_NEAR(topo.volumeM3, sx * sy * sz, 1e-15);
  EXPECT_NEAR(topo.nodeAreasM2.sum(), 2 * (sx * sy + sy * sz + sx * sz), 1e-14);
  // Interior nodes carry no boundary area.
  for (Eigen::Index i = 0; i < mesh.nodes.rows(); ++i) {
    const Eigen::Vector3d p = mesh.nodes.row(i);
    const bool inside = p.x() > 1e-9 && p.x() < sx - 1e-9 && p.y() > 1e-9 && p.y() < sy - 1e-9 && p.z() > 1e-9 &&
                        p.z() < sz - 1e-9;
    if (inside) EXPECT_EQ(topo.nodeAreasM2[i], 0.0) << "node " << i;
    else EXPECT_GT(topo.nodeAreasM2[i], 0.0) << "node " << i;
  }
}

TEST(TetTopology, BadMeshesGiveTypedErrors) {
  const TetMesh cube = testing::makeFiveTetBox(1.0, 1.0, 1.0);
  TetMesh empty = cube;
  empty.tets.resize(0, 4);
  EXPECT_EQ(buildTetTopology(empty).error().code, ErrorCode::InvalidArgument);
  TetMesh outOfRange = cube;
  outOfRange.tets(3, 2) = 8;
  EXPECT_EQ(buildTetTopology(outOfRange).error().code, ErrorCode::InvalidArgument);
  outOfRange.tets(3, 2) = -1;
  EXPECT_EQ(buildTetTopology(outOfRange).error().code, ErrorCode::InvalidArgument);
  TetMesh inverted = cube;
  std::swap(inverted.tets(2, 0), inverted.tets(2, 1));
  const auto invertedError = buildTetTopology(inverted);
  ASSERT_FALSE(invertedError);
  EXPECT_EQ(invertedError.error().code, ErrorCode::InvalidArgument);
  EXPECT_NE(invertedError.error().message.find("tet 2"), std::string::npos) << invertedError.error().message;
  TetMesh flat = cube;
  flat.nodes.row(0) = flat.nodes.row(1);  // corner tet 1 collapses to a triangle
  EXPECT_EQ(buildTetTopology(flat).error().code, ErrorCode::InvalidArgument);
  // Three positive tets on the triangle (0, 1, 2): one below it, two above.
  TetMesh fan;
  fan.nodes.resize(6, 3);
  fan.nodes << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0.2, 0.2, 1, 0.2, 0.2, -1, 0.3, 0.3, 2;
  fan.tets.resize(3, 4);
  fan.tets << 0, 1, 2, 3, 0, 2, 1, 4, 0, 1, 2, 5;
  const auto fanError = buildTetTopology(fan);
  ASSERT_FALSE(fanError);
  EXPECT_EQ(fanError.error().code, ErrorCode::InvalidArgument);
  EXPECT_NE(fanError.error().message.find("more than two"), std::string::npos) << fanError.error().message;
}


// A placed copy of a mesh (a database entry at a fragment's size and pose) shares its tets: the
// topology from the original's connectivity is buildTetTopology's own, bit for bit, in every field
// (the measured ones recomputed from the copy's nodes in the same order), and the copy's own
// defects are still reported.
TEST(TetTopology, TheSameTetsConnectivityGivesBuildTetTopologysBits) {
  const TetMesh original = testing::makeBoxTetMesh(0.3, 0.2, 0.1, 3, 2, 2);
  const TetTopology connectivity = buildTetTopology(original).value();
  TetMesh placed = original;
  const Eigen::Matrix3d rotation = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1.0, 2.0, -0.5).normalized()).toRotationMatrix();
  placed.nodes = ((original.nodes * (0.37 * rotation.transpose())).rowwise() + Eigen::RowVector3d(1.5, -0.25, 3.0)).eval();
  const TetTopology direct = buildTetTopology(placed).value();
  auto shared = buildTetTopology(placed, connectivity);
  ASSERT_TRUE(shared) << shared.error().message;
  const TetTopology& t = shared.value();
  EXPECT_EQ(t.edges, direct.edges);
  EXPECT_EQ(t.tetEdges, direct.tetEdges);
  EXPECT_EQ(t.neighbours, direct.neighbours);
  EXPECT_EQ(t.boundaryFaces, direct.boundaryFaces);
  EXPECT_EQ(t.boundaryTriangles, direct.boundaryTriangles);
  auto sameBits = [](const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), sizeof(double) * static_cast<size_t>(a.size())) == 0;
  };
  EXPECT_TRUE(sameBits(t.tetVolumesM3, direct.tetVolumesM3));
  EXPECT_TRUE(sameBits(t.nodeAreasM2, direct.nodeAreasM2));
  EXPECT_EQ(std::bit_cast<uint64_t>(t.volumeM3), std::bit_cast<uint64_t>(direct.volumeM3));
  EXPECT_EQ(std::bit_cast<uint64_t>(t.meanEdgeLengthM), std::bit_cast<uint64_t>(direct.meanEdgeLengthM));
  EXPECT_NEAR(t.volumeM3, 0.3 * 0.2 * 0.1 * std::pow(0.37, 3), 1e-15);
  expectConsistent(placed, t);

  // Another mesh's connectivity, or a copy whose tet turned inside out: typed errors.
  const TetMesh other = testing::makeBoxTetMesh(0.3, 0.2, 0.1, 2, 2, 2);
  EXPECT_EQ(buildTetTopology(placed, buildTetTopology(other).value()).error().code, ErrorCode::InvalidArgument);
  TetMesh mirrored = placed;
  mirrored.nodes.col(0) *= -1.0;
  const auto inverted = buildTetTopology(mirrored, connectivity);
  ASSERT_FALSE(inverted);
  EXPECT_EQ(inverted.error().code, ErrorCode::InvalidArgument);
  EXPECT_NE(inverted.error().message.find("not positively oriented"), std::string::npos) << inverted.error().message;
}

}  // namespace
}  // namespace brittle
