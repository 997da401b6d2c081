#include "brittle/precompute/MeshValidation.h"

#include <gtest/gtest.h>

#include "brittle/testing/Fixtures.h"

namespace brittle {
namespace {

ErrorCode codeOf(const TriangleMesh& mesh) {
  const Status s = validateSurfaceMesh(mesh);
  EXPECT_FALSE(s.ok());
  return s.ok() ? ErrorCode::InvalidArgument : s.error().code;
}

TriangleMesh dropFace(TriangleMesh m, Eigen::Index f) {
  TriangleMesh out = m;
  out.faces.resize(m.faces.rows() - 1, 3);
  for (Eigen::Index i = 0, j = 0; i < m.faces.rows(); ++i)
    if (i != f) out.faces.row(j++) = m.faces.row(i);
  return out;
}

// Two meshes as one (indices of b shifted).
TriangleMesh merge(const TriangleMesh& a, const TriangleMesh& b) {
  TriangleMesh m;
  m.vertices.resize(a.vertices.rows() + b.vertices.rows(), 3);
  m.vertices << a.vertices, b.vertices;
  m.faces.resize(a.faces.rows() + b.faces.rows(), 3);
  m.faces << a.faces, (b.faces.array() + static_cast<int32_t>(a.vertices.rows())).matrix();
  return m;
}

TEST(MeshValidation, AcceptsClosedOutwardMeshes) {
  EXPECT_TRUE(validateSurfaceMesh(testing::makeBoxSurface(1, 2, 3)).ok());
  EXPECT_TRUE(validateSurfaceMesh(testing::makeIcosphere(0.5, 3)).ok());
}

TEST(MeshValidation, OpenMeshSaysWhere) {
  const Status s = validateSurfaceMesh(dropFace(testing::makeBoxSurface(1, 1, 1), 0));
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error().code, ErrorCode::OpenMesh);
  EXPECT_EQ(s.error().message, "open mesh: 3 boundary edges, first at vertex 0");
}

TEST(MeshValidation, EmptyAndNonFinite) {
  EXPECT_EQ(codeOf(TriangleMesh{}), ErrorCode::EmptyMesh);
  auto box = testing::makeBoxSurface(1, 1, 1);
  box.vertices(3, 1) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(codeOf(box), ErrorCode::NonFiniteValue);
}

TEST(MeshValidation, DegenerateFace) {
  auto repeated = testing::makeBoxSurface(1, 1, 1);
  repeated.faces(0, 2) = repeated.faces(0, 0);
  EXPECT_EQ(codeOf(repeated), ErrorCode::DegenerateFace);
  auto collinear = testing::makeBoxSurface(1, 1, 1);
  collinear.vertices.row(2) << 0.5, 0.0, 0.0;  // face (0, 2, 1) becomes a segment
  const Status s = validateSurfaceMesh(collinear);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error().code, ErrorCode::DegenerateFace);
  EXPECT_NE(s.error().message.find("face 0"), std::string::npos) << s.error().message;
}

TEST(MeshValidation, NonManifoldEdgeAndVertex) {
  // Two boxes sharing one edge: that edge has four faces.
  auto a = testing::makeBoxSurface(1, 1, 1);
  auto b = testing::makeBoxSurface(1, 1, 1);
  b.vertices.rowwise() += Eigen::RowVector3d(1, 1, 0);
  auto edgeShared = merge(a, b);
  // Weld b's corners (0,0,*) onto a's corners (1,1,*): vertices 3 and 7 of a.
  for (Eigen::Index f = 0; f < edgeShared.faces.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      if (edgeShared.faces(f, k) == 8) edgeShared.faces(f, k) = 3;
      if (edgeShared.faces(f, k) == 12) edgeShared.faces(f, k) = 7;
    }
  EXPECT_EQ(codeOf(edgeShared), ErrorCode::NonManifold);

  // Two boxes touching at one corner: a pinched vertex.
  auto c = testing::makeBoxSurface(1, 1, 1);
  c.vertices.rowwise() += Eigen::RowVector3d(1, 1, 1);
  auto pinched = merge(a, c);
  for (Eigen::Index f = 0; f < pinched.faces.rows(); ++f)
    for (int k = 0; k < 3; ++k)
      if (pinched.faces(f, k) == 8) pinched.faces(f, k) = 7;
  const Status s = validateSurfaceMesh(pinched);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error().code, ErrorCode::NonManifold);
  EXPECT_NE(s.error().message.find("pinched"), std::string::npos) << s.error().message;
}

TEST(MeshValidation, SeparateComponentsAreRejected) {
  auto b = testing::makeBoxSurface(1, 1, 1);
  b.vertices.rowwise() += Eigen::RowVector3d(3, 0, 0);
  const Status s = validateSurfaceMesh(merge(testing::makeBoxSurface(1, 1, 1), b));
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error().code, ErrorCode::NonManifold);
  EXPECT_NE(s.error().message.find("2 separate components"), std::string::npos);
}

TEST(MeshValidation, OrientationErrors) {
  auto box = testing::makeBoxSurface(1, 1, 1);
  box.faces.row(4).reverseInPlace();  // one face flipped
  EXPECT_EQ(codeOf(box), ErrorCode::InconsistentOrientation);
  auto inward = testing::makeBoxSurface(1, 1, 1);
  inward.faces.col(1).swap(inward.faces.col(2));
  EXPECT_EQ(codeOf(inward), ErrorCode::InwardFacing);
}

TEST(MeshValidation, SelfIntersection) {
  // Push one corner of a cube through the opposite faces: the surface stays closed and
  // consistently oriented but crosses itself.
  auto box = testing::makeBoxSurface(1, 1, 1);
  box.vertices.row(7) << -0.5, -0.4, -0.3;
  const Status s = validateSurfaceMesh(box);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error().code, ErrorCode::SelfIntersection) << s.error().message;
}

}  // namespace
}  // namespace brittle
