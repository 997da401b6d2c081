#include "brittle/runtime/FemAssembly.h"

#include <gtest/gtest.h>

#include "brittle/testing/BakeFixtures.h"

namespace brittle {
namespace {

using testing::presetGlass;

TEST(FemAssembly, StiffnessIsSymmetricAndAnnihilatesRigidMotion) {
  const auto mesh = testing::makeBoxTetMesh(0.3, 0.2, 0.1, 3, 2, 2);
  auto sys = assembleFem(mesh, presetGlass(), {});
  ASSERT_TRUE(sys.ok()) << sys.error().message;
  const SparseMatrixd& k = sys.value().stiffness;
  EXPECT_NEAR((SparseMatrixd(k.transpose()) - k).norm(), 0.0, 1e-12 * k.norm());
  const Eigen::MatrixXd rigid = rigidBodyModes(mesh.nodes, sys.value().mass);
  EXPECT_LT((k * rigid).norm(), 1e-9 * k.norm() * rigid.norm());
  // The rigid basis is M-orthonormal.
  EXPECT_TRUE((rigid.transpose() * sys.value().mass * rigid).isApprox(Eigen::MatrixXd::Identity(6, 6), 1e-12));
}

TEST(FemAssembly, MassMatricesCarryTheTotalMass) {
  const auto mesh = testing::makeBoxTetMesh(0.3, 0.2, 0.1, 3, 2, 2);
  const double expected = presetGlass().densityKgPerM3 * 0.3 * 0.2 * 0.1;
  for (bool lumped : {false, true}) {
    auto sys = assembleFem(mesh, presetGlass(), FemSettings{lumped});
    ASSERT_TRUE(sys.ok());
    Eigen::VectorXd ux = Eigen::VectorXd::Zero(sys.value().mass.rows());
    for (Eigen::Index i = 0; i < mesh.nodes.rows(); ++i) ux(3 * i) = 1.0;
    EXPECT_NEAR(ux.dot(sys.value().mass * ux), expected, 1e-12 * expected) << (lumped ? "lumped" : "consistent");
  }
}

TEST(FemAssembly, ConsistentMassCarriesTheExactRotationalInertia) {
  // Rigid rotations are linear fields, which P1 represents exactly, so with the consistent mass
  // the kinetic energy of a rotation is exact: ω·Jω with the tet mesh's inertia about the
  // centroid of the nodes. Lumping moves mass to the nodes and gets it wrong.
  const auto mesh = testing::makeBoxTetMesh(0.3, 0.2, 0.1, 3, 2, 2);
  const Material m = presetGlass();
  const double mass = m.densityKgPerM3 * 0.3 * 0.2 * 0.1;
  const double jz = mass * (0.3 * 0.3 + 0.2 * 0.2) / 12.0;  // box centre = node centroid here
  for (bool lumped : {false, true}) {
    auto sys = assembleFem(mesh, m, FemSettings{lumped}).value();
    Eigen::VectorXd spin(sys.mass.rows());
    const Eigen::RowVector3d c = mesh.nodes.colwise().mean();
    for (Eigen::Index i = 0; i < mesh.nodes.rows(); ++i) {
      const Eigen::Vector3d p = (mesh.nodes.row(i) - c).transpose();
      spin.segment<3>(3 * i) = Eigen::Vector3d::UnitZ().cross(p);
    }
    const double energy = spin.dot(sys.mass * spin);
    if (lumped) {
      EXPECT_GT(std::abs(energy / jz - 1.0), 0.05);
    } else {
      EXPECT_NEAR(energy / jz, 1.0, 1e-12);
    }
  }
}

TEST(FemAssembly, PatchTestUniformStrainGivesUniformStress) {
  // Linear displacement u = ε x reproduces a uniform strain exactly on P1 elements.
  const auto mesh = testing::makeBoxTetMesh(1.0, 1.0, 1.0, 2, 2, 2);
  const Material m = presetGlass();
  Eigen::Matrix3d grad;
  grad << 1e-4, 2e-5, 0, 0, -3e-5, 1e-5, 4e-5, 0, 2e-5;
  MatrixXdRow u(3 * mesh.nodes.rows(), 1);
  for (Eigen::Index i = 0; i < mesh.nodes.rows(); ++i) u.middleRows(3 * i, 3) = grad * mesh.nodes.row(i).transpose();
  const MatrixXdRow s = computeStressModes(mesh, m, u);
  Eigen::Matrix<double, 6, 1> strain;
  strain << grad(0, 0), grad(1, 1), grad(2, 2), grad(1, 2) + grad(2, 1), grad(0, 2) + grad(2, 0), grad(0, 1) + grad(1, 0);
  const Eigen::Matrix<double, 6, 1> expected = isotropicElasticity(m.youngsModulusPa, m.poissonRatio) * strain;
  for (Eigen::Index e = 0; e < mesh.tets.rows(); ++e) {
    EXPECT_TRUE(s.middleRows(6 * e, 6).isApprox(expected, 1e-10)) << "tet " << e;
  }
  // Uniaxial check of C: σ_xx = E(1−ν)/((1+ν)(1−2ν)) ε_xx for ε = ε_xx e_x.
  const double e = m.youngsModulusPa, nu = m.poissonRatio;
  EXPECT_NEAR(isotropicElasticity(e, nu)(0, 0), e * (1 - nu) / ((1 + nu) * (1 - 2 * nu)), 1e-6 * e);
  EXPECT_NEAR(isotropicElasticity(e, nu)(3, 3), e / (2 * (1 + nu)), 1e-6 * e);
}

TEST(FemAssembly, RejectsDegenerateAndInvertedTets) {
  auto mesh = testing::makeBoxTetMesh(1.0, 1.0, 1.0, 1, 1, 1);
  std::swap(mesh.tets(2, 0), mesh.tets(2, 1));
  auto inverted = assembleFem(mesh, presetGlass(), {});
  ASSERT_FALSE(inverted.ok());
  EXPECT_EQ(inverted.error().code, ErrorCode::DegenerateElement);
  EXPECT_NE(inverted.error().message.find("tet 2"), std::string::npos);
  // A flat tet: volume above zero but at the threshold the mesher checks against.
  auto flat = testing::makeBoxTetMesh(2.0, 1.0, 0.5, 1, 1, 1);
  EXPECT_DOUBLE_EQ(degenerateTetVolumeM3(flat.nodes), 1e-12);
  flat.nodes.row(flat.tets(0, 3)) = (flat.nodes.row(flat.tets(0, 0)) + flat.nodes.row(flat.tets(0, 1)) + flat.nodes.row(flat.tets(0, 2))) / 3.0;
  auto degenerate = assembleFem(flat, presetGlass(), {});
  ASSERT_FALSE(degenerate.ok());
  EXPECT_EQ(degenerate.error().code, ErrorCode::DegenerateElement);
  Material bad = presetGlass();
  bad.poissonRatio = 0.5;
  EXPECT_EQ(assembleFem(testing::makeBoxTetMesh(1, 1, 1, 1, 1, 1), bad, {}).error().code, ErrorCode::InvalidMaterial);
}

}  // namespace
}  // namespace brittle
