#include "brittle/runtime/FragmentSurfaces.h"

#include <gtest/gtest.h>
#include <oneapi/tbb/task_arena.h>

#include <random>

#include "brittle/descriptors/MassProperties.h"
#include "brittle/precompute/MeshValidation.h"
#include "brittle/runtime/CrackPropagation.h"
#include "brittle/testing/Fixtures.h"

namespace brittle {
namespace {

double volumeOf(const TriangleMesh& m) { return computeSurfaceMassProperties(m, 1.0).volumeM3; }

using testing::isClosedAndOriented;

// Cuts every edge that crosses one of the planes n·x = d (first plane wins), as a crack would.
Eigen::VectorXd cutsByPlanes(const TetMesh& mesh, const TetTopology& topo, const std::vector<Eigen::Vector4d>& planes) {
  Eigen::VectorXd cuts = Eigen::VectorXd::Constant(topo.edges.rows(), std::nan(""));
  for (Eigen::Index e = 0; e < topo.edges.rows(); ++e) {
    const Eigen::Vector3d a = mesh.nodes.row(topo.edges(e, 0)), b = mesh.nodes.row(topo.edges(e, 1));
    for (const auto& p : planes) {
      const double da = p.head<3>().dot(a) - p[3], db = p.head<3>().dot(b) - p[3];
      if ((da > 0) != (db > 0)) {
        cuts[e] = da / (da - db);
        break;
      }
    }
  }
  return cuts;
}

class FragmentSurfacesTest : public ::testing::Test {
 protected:
  TetMesh mesh = testing::makeBoxTetMesh(0.3, 0.2, 0.1, 6, 4, 2);
  TetTopology topo = buildTetTopology(mesh).value();
};

TEST_F(FragmentSurfacesTest, OnePlaneSplitsTheBoxExactlyAlongIt) {
  // The box spans [0, 0.3] in x with 0.05 cells: x = 0.163 cuts edges at parameter 0.26.
  const double x0 = mesh.nodes.col(0).minCoeff() + 0.163;
  const Eigen::VectorXd cuts = cutsByPlanes(mesh, topo, {Eigen::Vector4d(1, 0, 0, x0)});
  Eigen::VectorXi labels;
  ASSERT_EQ(labelFragments(topo, cuts, mesh.nodes.rows(), labels), 2);
  auto surfaces = buildFragmentSurfaces(mesh, topo, labels, 2, cuts);
  ASSERT_TRUE(surfaces) << surfaces.error().message;
  double total = 0.0;
  for (const TriangleMesh& s : surfaces.value()) {
    EXPECT_TRUE(isClosedAndOriented(s));
    const Status valid = validateSurfaceMesh(s);
    EXPECT_TRUE(valid) << valid.error().message;
    total += volumeOf(s);
  }
  EXPECT_NEAR(total, topo.volumeM3, 1e-9 * topo.volumeM3);
  // The crack faces lie on the plane, so each side has exactly its slab's volume.
  const double left = 0.163 * 0.2 * 0.1;
  const int leftLabel = labels[0];  // node 0 is at the minimum corner in makeBoxTetMesh
  EXPECT_NEAR(volumeOf(surfaces.value()[static_cast<size_t>(leftLabel)]), left, 1e-12);
}

TEST_F(FragmentSurfacesTest, ThreePlanesGiveClosedFragmentsThatConserveVolume) {
  const Eigen::Vector3d c = mesh.nodes.colwise().mean();
  std::vector<Eigen::Vector4d> planes;
  for (const Eigen::Vector3d& n : {Eigen::Vector3d(1, 0.3, 0.1).normalized(), Eigen::Vector3d(-0.2, 1, 0.05).normalized(),
                                   Eigen::Vector3d(0.6, -0.7, 0.2).normalized()}) {
    planes.emplace_back(n.x(), n.y(), n.z(), n.dot(c) + 0.0071);
  }
  const Eigen::VectorXd cuts = cutsByPlanes(mesh, topo, planes);
  Eigen::VectorXi labels;
  const int count = labelFragments(topo, cuts, mesh.nodes.rows(), labels);
  EXPECT_GE(count, 4);
  auto surfaces = buildFragmentSurfaces(mesh, topo, labels, count, cuts);
  ASSERT_TRUE(surfaces) << surfaces.error().message;
  double total = 0.0;
  for (const TriangleMesh& s : surfaces.value()) {
    EXPECT_TRUE(isClosedAndOriented(s));
    EXPECT_GT(volumeOf(s), 0.0);
    total += volumeOf(s);
  }
  EXPECT_NEAR(total, topo.volumeM3, 1e-9 * topo.volumeM3);
}

TEST_F(FragmentSurfacesTest, AnyLabellingPartitionsTheVolume) {
  std::mt19937_64 rng(5);
  for (int trial = 0; trial < 5; ++trial) {
    Eigen::VectorXi labels(mesh.nodes.rows());
    for (Eigen::Index i = 0; i < labels.size(); ++i) labels[i] = static_cast<int>(rng() % 3);
    Eigen::VectorXd cuts(topo.edges.rows());
    for (Eigen::Index e = 0; e < cuts.size(); ++e) cuts[e] = static_cast<double>(rng() % 1000) / 1000.0;
    auto surfaces = buildFragmentSurfaces(mesh, topo, labels, 3, cuts);
    ASSERT_TRUE(surfaces) << surfaces.error().message;
    double total = 0.0;
    for (const TriangleMesh& s : surfaces.value()) {
      EXPECT_TRUE(isClosedAndOriented(s));
      total += volumeOf(s);
    }
    EXPECT_NEAR(total, topo.volumeM3, 1e-9 * topo.volumeM3);
  }
}

// The moments summed over tets and cut cells equal those of the built surfaces, to rounding, per
// monomial relative to V·Lⁿ (L the box's largest side): for plane cracks and for random labels
// with up to four labels in one tet.
void expectMomentsOfTheSurfaces(const TetMesh& mesh, const TetTopology& topo, const Eigen::VectorXi& labels, int count,
                                const Eigen::VectorXd& cuts) {
  const Eigen::Vector3d origin(0.14, 0.11, 0.04);
  std::vector<double> moments;
  ASSERT_TRUE(fragmentVolumeMoments(mesh, topo, tetVolumeMoments(mesh, origin), labels, count, cuts, moments));
  ASSERT_EQ(moments.size(), static_cast<size_t>(count * kFragmentMomentCount));
  auto surfaces = buildFragmentSurfaces(mesh, topo, labels, count, cuts);
  ASSERT_TRUE(surfaces) << surfaces.error().message;
  double total = 0.0;
  for (int l = 0; l < count; ++l) {
    const auto expected = computeVolumeMoments(surfaces.value()[static_cast<size_t>(l)], kFragmentMomentOrder, origin);
    ASSERT_TRUE(expected.ok()) << expected.error().message;
    for (int m = 0; m < kFragmentMomentCount; ++m) {
      const double scale = topo.volumeM3 * std::pow(0.3, monomialExponents(m)[0] + monomialExponents(m)[1] + monomialExponents(m)[2]);
      EXPECT_NEAR(moments[static_cast<size_t>(l * kFragmentMomentCount + m)], expected.value().values[m], 1e-12 * scale)
          << "fragment " << l << ", monomial " << m;
    }
    total += moments[static_cast<size_t>(l * kFragmentMomentCount)];
  }
  EXPECT_NEAR(total, topo.volumeM3, 1e-12 * topo.volumeM3);
}

TEST_F(FragmentSurfacesTest, FragmentMomentsFromTetsEqualThoseOfTheirSurfaces) {
  const Eigen::Vector3d c = mesh.nodes.colwise().mean();
  std::vector<Eigen::Vector4d> planes;
  for (const Eigen::Vector3d& n : {Eigen::Vector3d(1, 0.3, 0.1).normalized(), Eigen::Vector3d(-0.2, 1, 0.05).normalized()}) {
    planes.emplace_back(n.x(), n.y(), n.z(), n.dot(c) + 0.0071);
  }
  const Eigen::VectorXd planeCuts = cutsByPlanes(mesh, topo, planes);
  Eigen::VectorXi labels;
  const int count = labelFragments(topo, planeCuts, mesh.nodes.rows(), labels);
  ASSERT_GE(count, 3);
  expectMomentsOfTheSurfaces(mesh, topo, labels, count, planeCuts);

  std::mt19937_64 rng(11);
  for (int trial = 0; trial < 3; ++trial) {
    for (Eigen::Index i = 0; i < labels.size(); ++i) labels[i] = static_cast<int>(rng() % 4);
    Eigen::VectorXd cuts(topo.edges.rows());
    for (Eigen::Index e = 0; e < cuts.size(); ++e) cuts[e] = static_cast<double>(rng() % 1000) / 1000.0;
    expectMomentsOfTheSurfaces(mesh, topo, labels, 4, cuts);
  }
  std::vector<double> moments;
  EXPECT_EQ(fragmentVolumeMoments(mesh, topo, TetMoments{Eigen::Vector3d::Zero(), std::vector<double>(7), {}}, labels, 4,
                                  Eigen::VectorXd::Constant(topo.edges.rows(), 0.5), moments)
                .error()
                .code,
            ErrorCode::InvalidArgument);
}

// The fixed ranges are summed in their order whatever runs them: one thread, two, or the default
// arena give the same bits.
TEST_F(FragmentSurfacesTest, FragmentMomentsAreTheSameBitsOnAnyNumberOfThreads) {
  std::mt19937_64 rng(5);
  Eigen::VectorXi labels(mesh.nodes.rows());
  for (Eigen::Index i = 0; i < labels.size(); ++i) labels[i] = static_cast<int>(rng() % 5);
  Eigen::VectorXd cuts(topo.edges.rows());
  for (Eigen::Index e = 0; e < cuts.size(); ++e) cuts[e] = static_cast<double>(rng() % 1000) / 1000.0;
  const TetMoments tetMoments = tetVolumeMoments(mesh, mesh.nodes.colwise().mean().transpose());
  auto momentsOn = [&](int threads) {
    std::vector<double> moments, chunkSums;
    tbb::task_arena arena(threads);
    arena.execute([&] { EXPECT_TRUE(fragmentVolumeMoments(mesh, topo, tetMoments, labels, 5, cuts, chunkSums, moments)); });
    return moments;
  };
  const std::vector<double> one = momentsOn(1);
  ASSERT_EQ(one.size(), 5u * kFragmentMomentCount);
  EXPECT_EQ(momentsOn(2), one);
  EXPECT_EQ(momentsOn(4), one);
  std::vector<double> plain;
  ASSERT_TRUE(fragmentVolumeMoments(mesh, topo, tetMoments, labels, 5, cuts, plain));
  EXPECT_EQ(plain, one);
}

TEST_F(FragmentSurfacesTest, BadInputsGiveTypedErrors) {
  Eigen::VectorXi labels = Eigen::VectorXi::Zero(mesh.nodes.rows());
  const Eigen::VectorXd cuts = Eigen::VectorXd::Constant(topo.edges.rows(), 0.5);
  EXPECT_EQ(buildFragmentSurfaces(mesh, topo, labels, 2, cuts).error().code, ErrorCode::InvalidArgument);  // label 1 empty
  labels[0] = 7;
  EXPECT_EQ(buildFragmentSurfaces(mesh, topo, labels, 2, cuts).error().code, ErrorCode::InvalidArgument);
  EXPECT_FALSE(buildFragmentSurfaces(mesh, topo, Eigen::VectorXi::Zero(3), 1, cuts));
  TetMesh inverted = mesh;
  inverted.tets.col(0).swap(inverted.tets.col(1));
  EXPECT_EQ(buildTetTopology(inverted).error().code, ErrorCode::InvalidArgument);
}

}  // namespace
}  // namespace brittle
