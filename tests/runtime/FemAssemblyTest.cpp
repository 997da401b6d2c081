#include "brittle/runtime/FemAssembly.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cstring>
#include <numeric>
#include <random>
#include <vector>

#include "brittle/runtime/QuadraticTetMesh.h"
#include "brittle/testing/BakeFixtures.h"
#include "brittle/testing/TetQuadrature.h"

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

// K and M are assembled straight into their columns, in element order: each entry must be the
// bits setFromTriplets makes from the same elements in the same order. The reference takes each
// element's entries from the assembly of that element alone (one contribution an entry: its
// value exactly). Nodes are numbered at random, so that a node's neighbours are not in order.
template <class Mesh>
void expectTheTripletAssemblysBits(const Mesh& mesh) {
  for (bool lumped : {false, true}) {
    const FemSystem whole = assembleFem(mesh, presetGlass(), FemSettings{lumped}).value();
    std::vector<Eigen::Triplet<double>> k, m;
    for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
      Mesh one = mesh;
      one.tets = mesh.tets.row(t);
      const FemSystem element = assembleFem(one, presetGlass(), FemSettings{lumped}).value();
      for (Eigen::Index c = 0; c < element.stiffness.outerSize(); ++c) {
        for (SparseMatrixd::InnerIterator it(element.stiffness, c); it; ++it) k.emplace_back(it.row(), it.col(), it.value());
        for (SparseMatrixd::InnerIterator it(element.mass, c); it; ++it) m.emplace_back(it.row(), it.col(), it.value());
      }
    }
    SparseMatrixd kRef(whole.stiffness.rows(), whole.stiffness.cols()), mRef(whole.mass.rows(), whole.mass.cols());
    kRef.setFromTriplets(k.begin(), k.end());
    mRef.setFromTriplets(m.begin(), m.end());
    for (const auto& [got, want] : {std::pair{&whole.stiffness, &kRef}, std::pair{&whole.mass, &mRef}}) {
      ASSERT_EQ(got->nonZeros(), want->nonZeros()) << (lumped ? "lumped" : "consistent");
      for (Eigen::Index c = 0; c <= got->outerSize(); ++c) ASSERT_EQ(got->outerIndexPtr()[c], want->outerIndexPtr()[c]);
      for (Eigen::Index q = 0; q < got->nonZeros(); ++q) {
        ASSERT_EQ(got->innerIndexPtr()[q], want->innerIndexPtr()[q]);
        ASSERT_EQ(std::memcmp(got->valuePtr() + q, want->valuePtr() + q, sizeof(double)), 0) << "entry " << q;
      }
    }
  }
}

template <class Mesh>
Mesh renumbered(Mesh mesh, unsigned seed) {
  std::vector<int32_t> order(static_cast<size_t>(mesh.nodes.rows()));
  std::iota(order.begin(), order.end(), 0);
  std::shuffle(order.begin(), order.end(), std::mt19937(seed));
  Points nodes(mesh.nodes.rows(), 3);
  for (Eigen::Index v = 0; v < mesh.nodes.rows(); ++v) nodes.row(order[static_cast<size_t>(v)]) = mesh.nodes.row(v);
  mesh.nodes = nodes;
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t)
    for (Eigen::Index a = 0; a < mesh.tets.cols(); ++a) mesh.tets(t, a) = order[static_cast<size_t>(mesh.tets(t, a))];
  return mesh;
}

TEST(FemAssembly, AssembledInPlaceAsFromTripletsBitForBit) {
  const TetMesh mesh = renumbered(testing::makeBoxTetMesh(0.3, 0.2, 0.1, 3, 2, 2), 7);
  expectTheTripletAssemblysBits(mesh);
  expectTheTripletAssemblysBits(renumbered(makeQuadraticTetMesh(testing::makeBoxTetMesh(0.3, 0.2, 0.1, 2, 2, 1)).value(), 11));
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

// ---- Quadratic (P2) tetrahedra -------------------------------------------------------------

QuadraticTetMesh quadraticBox(double sx, double sy, double sz, int nx, int ny, int nz) {
  return makeQuadraticTetMesh(testing::makeBoxTetMesh(sx, sy, sz, nx, ny, nz)).value();
}

/// Nodal values of a displacement field u(x) on every node.
template <class Field>
MatrixXdRow nodalField(const Points& nodes, Field u) {
  MatrixXdRow out(3 * nodes.rows(), 1);
  for (Eigen::Index i = 0; i < nodes.rows(); ++i) out.middleRows(3 * i, 3) = u(Eigen::Vector3d(nodes.row(i).transpose()));
  return out;
}

TEST(FemAssemblyP2, UnitMassIsTheExactIntegralOfTheShapeFunctions) {
  // Against an independent degree-5 rule: the P2 mass integrand has degree 4.
  Eigen::Matrix<double, 10, 10> quadrature = Eigen::Matrix<double, 10, 10>::Zero();
  for (const auto& [l, w] : testing::degreeFiveTetRule()) {
    const auto n = quadraticTetShapeFunctions(l);
    quadrature += w * n * n.transpose();
  }
  EXPECT_LT((quadraticTetUnitMass() - quadrature).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_NEAR(quadraticTetUnitMass().sum(), 1.0, 1e-15);
  // Shape functions: a partition of unity, 1 at their own node and 0 at the others.
  for (int a = 0; a < 10; ++a) {
    Eigen::Vector4d l = Eigen::Vector4d::Zero();
    if (a < 4) {
      l(a) = 1.0;
    } else {
      l(kQuadraticTetEdges[static_cast<size_t>(a - 4)][0]) = 0.5;
      l(kQuadraticTetEdges[static_cast<size_t>(a - 4)][1]) = 0.5;
    }
    EXPECT_TRUE(quadraticTetShapeFunctions(l).isApprox(Eigen::Matrix<double, 10, 1>::Unit(a))) << "node " << a;
  }
}

TEST(FemAssemblyP2, StiffnessIsSymmetricAndAnnihilatesTheSixRigidMotions) {
  const auto mesh = quadraticBox(0.3, 0.2, 0.1, 3, 2, 2);
  auto sys = assembleFem(mesh, presetGlass(), {});
  ASSERT_TRUE(sys.ok()) << sys.error().message;
  const SparseMatrixd& k = sys.value().stiffness;
  ASSERT_EQ(k.rows(), 3 * mesh.nodes.rows());
  EXPECT_NEAR((SparseMatrixd(k.transpose()) - k).norm(), 0.0, 1e-12 * k.norm());
  const Eigen::MatrixXd rigid = rigidBodyModes(mesh.nodes, sys.value().mass);
  for (int j = 0; j < 6; ++j) EXPECT_LT((k * rigid.col(j)).norm(), 1e-9 * k.norm() * rigid.col(j).norm()) << "rigid mode " << j;
  EXPECT_TRUE((rigid.transpose() * sys.value().mass * rigid).isApprox(Eigen::MatrixXd::Identity(6, 6), 1e-12));
  // Exactly six zero modes: the smallest elastic eigenvalue of K is far from zero.
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(Eigen::MatrixXd(k), Eigen::EigenvaluesOnly);
  EXPECT_LT(std::abs(eig.eigenvalues()(5)), 1e-9 * eig.eigenvalues().maxCoeff());
  EXPECT_GT(eig.eigenvalues()(6), 1e-6 * eig.eigenvalues().maxCoeff());
}

TEST(FemAssemblyP2, MassCarriesTheTotalMassAndIntegratesQuadraticFieldsExactly) {
  const double sx = 0.3, sy = 0.2, sz = 0.1;
  const auto mesh = quadraticBox(sx, sy, sz, 3, 2, 2);
  const Material m = presetGlass();
  const double rho = m.densityKgPerM3, mass = rho * sx * sy * sz;
  for (bool lumped : {false, true}) {
    const FemSystem sys = assembleFem(mesh, m, FemSettings{lumped}).value();
    for (int axis = 0; axis < 3; ++axis) {
      const MatrixXdRow u = nodalField(mesh.nodes, [&](const Eigen::Vector3d&) { return Eigen::Vector3d::Unit(axis); });
      EXPECT_NEAR(u.col(0).dot(sys.mass * u.col(0)), mass, 1e-12 * mass) << (lumped ? "lumped" : "consistent");
    }
    if (lumped) {
      EXPECT_GT(Eigen::VectorXd(sys.mass.diagonal()).minCoeff(), 0.0);
      EXPECT_EQ(sys.mass.nonZeros(), sys.mass.rows());
      continue;
    }
    // Kinetic energy of a rigid spin about the box centre (the node centroid): ω·Jω.
    const Eigen::Vector3d centre(sx / 2, sy / 2, sz / 2);
    const MatrixXdRow spin = nodalField(mesh.nodes, [&](const Eigen::Vector3d& x) { return Eigen::Vector3d(Eigen::Vector3d::UnitZ().cross(x - centre)); });
    EXPECT_NEAR(spin.col(0).dot(sys.mass * spin.col(0)) / (mass * (sx * sx + sy * sy) / 12.0), 1.0, 1e-12);
    // A quadratic field is interpolated exactly and its ρ∫u·u dV (degree 4) integrated exactly:
    // u = (xy, z², 0): ρ(sx³sy³sz/9 + sx sy sz⁵/5).
    const MatrixXdRow q = nodalField(mesh.nodes, [](const Eigen::Vector3d& x) { return Eigen::Vector3d(x.x() * x.y(), x.z() * x.z(), 0.0); });
    const double exact = rho * (std::pow(sx * sy, 3) * sz / 9.0 + sx * sy * std::pow(sz, 5) / 5.0);
    EXPECT_NEAR(q.col(0).dot(sys.mass * q.col(0)) / exact, 1.0, 1e-12);
  }
}

TEST(FemAssemblyP2, PatchTestLinearFieldGivesConstantStressAndNoInteriorForces) {
  const auto mesh = quadraticBox(1.0, 1.0, 1.0, 2, 2, 2);
  const Material m = presetGlass();
  Eigen::Matrix3d grad;
  grad << 1e-4, 2e-5, 0, 0, -3e-5, 1e-5, 4e-5, 0, 2e-5;
  const MatrixXdRow u = nodalField(mesh.nodes, [&](const Eigen::Vector3d& x) { return Eigen::Vector3d(grad * x); });
  Eigen::Matrix<double, 6, 1> strain;
  strain << grad(0, 0), grad(1, 1), grad(2, 2), grad(1, 2) + grad(2, 1), grad(0, 2) + grad(2, 0), grad(0, 1) + grad(1, 0);
  const Eigen::Matrix<double, 6, 1> expected = isotropicElasticity(m.youngsModulusPa, m.poissonRatio) * strain;
  const MatrixXdRow s = computeStressModes(mesh, m, u);
  ASSERT_EQ(s.rows(), 24 * mesh.tets.rows());
  for (Eigen::Index e = 0; e < mesh.tets.rows(); ++e) {
    for (int c = 0; c < 4; ++c) EXPECT_TRUE(s.middleRows(24 * e + 6 * c, 6).isApprox(expected, 1e-10)) << "tet " << e << " corner " << c;
  }
  // Equilibrium: K u vanishes at every node off the boundary (interior corners and mid-edge nodes).
  const FemSystem sys = assembleFem(mesh, m, {}).value();
  const Eigen::VectorXd f = sys.stiffness * u.col(0);
  int interior = 0;
  for (Eigen::Index i = 0; i < mesh.nodes.rows(); ++i) {
    const Eigen::Vector3d x = mesh.nodes.row(i).transpose();
    if ((x.array() > 1e-9).all() && (x.array() < 1.0 - 1e-9).all()) {
      ++interior;
      EXPECT_LT(f.segment<3>(3 * i).norm(), 1e-9 * f.norm()) << "node " << i;
    }
  }
  EXPECT_GT(interior, 10);
}

TEST(FemAssemblyP2, QuadraticFieldIsRepresentedExactly) {
  // u = a quadratic polynomial: P2 interpolation reproduces it and its (linear) strain everywhere
  // in every element, and the corner stresses are the exact stresses at the corners.
  const auto mesh = quadraticBox(0.3, 0.2, 0.1, 2, 2, 1);
  const Material m = presetGlass();
  const auto c = isotropicElasticity(m.youngsModulusPa, m.poissonRatio);
  auto field = [](const Eigen::Vector3d& x) {
    return Eigen::Vector3d(1e-3 * x.x() * x.x() - 2e-3 * x.y() * x.z() + 1e-4, 3e-3 * x.x() * x.y() + 1e-3 * x.z(),
                           -2e-3 * x.z() * x.z() + 1e-3 * x.x() * x.z());
  };
  auto strainOf = [](const Eigen::Vector3d& x) {
    Eigen::Matrix3d g;  // g(i, j) = ∂u_i/∂x_j
    g << 2e-3 * x.x(), -2e-3 * x.z(), -2e-3 * x.y(), 3e-3 * x.y(), 3e-3 * x.x(), 1e-3, 1e-3 * x.z(), 0.0, -4e-3 * x.z() + 1e-3 * x.x();
    Eigen::Matrix<double, 6, 1> e;
    e << g(0, 0), g(1, 1), g(2, 2), g(1, 2) + g(2, 1), g(0, 2) + g(2, 0), g(0, 1) + g(1, 0);
    return e;
  };
  const MatrixXdRow u = nodalField(mesh.nodes, field);
  const Eigen::Vector4d samples[] = {{0.25, 0.25, 0.25, 0.25}, {0.1, 0.2, 0.3, 0.4}, {0.7, 0.1, 0.15, 0.05}, {0.0, 0.5, 0.5, 0.0}};
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
    Eigen::Matrix<double, 30, 1> ue;
    Eigen::Matrix<double, 4, 3> corners;
    for (int a = 0; a < 10; ++a) ue.segment<3>(3 * a) = u.middleRows(3 * mesh.tets(t, a), 3);
    for (int a = 0; a < 4; ++a) corners.row(a) = mesh.nodes.row(mesh.tets(t, a));
    for (const Eigen::Vector4d& l : samples) {
      const Eigen::Vector3d x = corners.transpose() * l;
      const auto n = quadraticTetShapeFunctions(l);
      Eigen::Vector3d interpolated = Eigen::Vector3d::Zero();
      for (int a = 0; a < 10; ++a) interpolated += n(a) * ue.segment<3>(3 * a);
      EXPECT_LT((interpolated - field(x)).norm(), 1e-15) << "tet " << t;
      const auto b = quadraticTetStrainDisplacement(corners.row(0).transpose(), corners.row(1).transpose(), corners.row(2).transpose(),
                                                    corners.row(3).transpose(), l, nullptr);
      EXPECT_LT((b * ue - strainOf(x)).norm(), 1e-13) << "tet " << t;
    }
  }
  const MatrixXdRow s = computeStressModes(mesh, m, u);
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector3d x = mesh.nodes.row(mesh.tets(t, k)).transpose();
      EXPECT_TRUE(s.middleRows(24 * t + 6 * k, 6).isApprox(c * strainOf(x), 1e-10)) << "tet " << t << " corner " << k;
    }
  }
}

TEST(FemAssemblyP2, CornerStressMeansAreVolumeWeightedAndKeepALinearStrainExact) {
  // CornerStressMeans: every corner of a node becomes the volume-weighted mean of the node's
  // corners (checked by hand on random rows); a quadratic displacement's stress, linear and so
  // already equal at each node, comes out unchanged; a tet without volume is a typed error.
  const TetMesh mesh = testing::makeBoxTetMesh(0.3, 0.2, 0.1, 3, 2, 2);
  const auto means = CornerStressMeans::make(mesh);
  ASSERT_TRUE(means) << means.error().message;
  EXPECT_EQ(means.value().elementCount(), mesh.tets.rows());
  std::mt19937_64 rng(11);
  std::normal_distribution<double> g(0.0, 1.0);
  const Eigen::Index t = mesh.tets.rows(), cols = 3;
  MatrixXdRow rows(24 * t, cols);
  for (Eigen::Index i = 0; i < rows.size(); ++i) rows.data()[i] = g(rng);
  MatrixXdRow expected = rows;
  for (Eigen::Index v = 0; v < mesh.nodes.rows(); ++v) {
    Eigen::MatrixXd sum = Eigen::MatrixXd::Zero(6, cols);
    double volume = 0.0;
    for (Eigen::Index e = 0; e < t; ++e) {
      for (int c = 0; c < 4; ++c) {
        if (mesh.tets(e, c) != v) continue;
        const Eigen::Vector3d p0 = mesh.nodes.row(mesh.tets(e, 0)), p1 = mesh.nodes.row(mesh.tets(e, 1)),
                              p2 = mesh.nodes.row(mesh.tets(e, 2)), p3 = mesh.nodes.row(mesh.tets(e, 3));
        const double ve = std::abs((p1 - p0).cross(p2 - p0).dot(p3 - p0)) / 6.0;
        sum += ve * rows.middleRows(6 * (4 * e + c), 6);
        volume += ve;
      }
    }
    for (Eigen::Index e = 0; e < t; ++e) {
      for (int c = 0; c < 4; ++c) {
        if (mesh.tets(e, c) == v) expected.middleRows(6 * (4 * e + c), 6) = sum / volume;
      }
    }
  }
  MatrixXdRow averaged = rows;
  means.value().apply(averaged.data(), cols);
  EXPECT_LT((averaged - expected).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_GT((averaged - rows).cwiseAbs().maxCoeff(), 0.1);  // random corners do differ at a node
  // One field at a time (the static correction's recovery, cols = 1: six sums, points first) and
  // many at once (stress modes: one sum at a time) are the same bits.
  const Eigen::Index wide = 11;
  MatrixXdRow block(24 * t, wide);
  for (Eigen::Index i = 0; i < block.size(); ++i) block.data()[i] = g(rng);
  MatrixXdRow together = block;
  means.value().apply(together.data(), wide);
  for (Eigen::Index j = 0; j < wide; ++j) {
    Eigen::VectorXd alone = block.col(j);
    means.value().apply(alone.data(), 1);
    EXPECT_EQ(std::memcmp(alone.data(), Eigen::VectorXd(together.col(j)).data(), sizeof(double) * static_cast<size_t>(alone.size())), 0)
        << "column " << j;
  }

  const Material m = presetGlass();
  const FemMesh fem = makeFemMesh(mesh, ElementOrder::P2).value();
  const MatrixXdRow u = nodalField(fem.nodes(), [](const Eigen::Vector3d& x) {
    return Eigen::Vector3d(1e-3 * x.x() * x.x() - 2e-3 * x.y() * x.z(), 3e-3 * x.x() * x.y() + 1e-3 * x.z(), -2e-3 * x.z() * x.z());
  });
  const MatrixXdRow own = computeStressModes(fem, m, u);
  MatrixXdRow mean = own;
  means.value().apply(mean.data(), mean.cols());
  EXPECT_LE((mean - own).cwiseAbs().maxCoeff(), 1e-9 * own.cwiseAbs().maxCoeff());

  TetMesh flat = mesh;
  flat.nodes.row(flat.tets(0, 3)) = flat.nodes.row(flat.tets(0, 0));  // tet 0 loses its volume
  const auto refused = CornerStressMeans::make(flat);
  ASSERT_FALSE(refused);
  EXPECT_EQ(refused.error().code, ErrorCode::InvalidArgument);
  EXPECT_NE(refused.error().message.find("no volume"), std::string::npos) << refused.error().message;
}

TEST(FemAssemblyP2, ElementStressesRecoverTheStressModesOfAnyDisplacementAtEitherOrder) {
  // The static correction's and the full-FEM reference's stress recovery equals the bake's stress
  // modes for the same displacement, point by point (P2: both as nodal means, as a body reads its
  // modes), and the order dispatch builds the same FEM nodes the pack reader counts.
  const TetMesh mesh = testing::makeBoxTetMesh(0.3, 0.2, 0.1, 3, 2, 1);
  const Material m = presetGlass();
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> unit(-1e-6, 1e-6);
  for (const ElementOrder order : {ElementOrder::P1, ElementOrder::P2}) {
    const FemMesh fem = makeFemMesh(mesh, order).value();
    const Points& nodes = fem.nodes();
    EXPECT_EQ(nodes.rows(), femNodeCount(mesh, order));
    EXPECT_EQ(assembleFem(fem, m, {}).value().stiffness.rows(), 3 * nodes.rows());
    MatrixXdRow u(3 * nodes.rows(), 1);
    for (Eigen::Index i = 0; i < u.rows(); ++i) u(i, 0) = unit(rng);
    MatrixXdRow modes = computeStressModes(fem, m, u);
    const MatrixXdRow own = modes;
    if (order == ElementOrder::P2) CornerStressMeans::make(mesh).value().apply(modes.data(), modes.cols());
    const auto recovery = ElementStresses::make(fem, m);
    ASSERT_TRUE(recovery.ok()) << recovery.error().message;
    EXPECT_EQ(recovery.value().pointsPerElement(), stressPointsPerElement(order));
    EXPECT_EQ(recovery.value().femNodeCount(), nodes.rows());
    Eigen::VectorXd stress;
    recovery.value().all(u.col(0), stress);
    ASSERT_EQ(stress.size(), modes.rows());
    EXPECT_LE((stress - modes.col(0)).cwiseAbs().maxCoeff(), 1e-9 * modes.cwiseAbs().maxCoeff()) << elementOrderName(order);
    Eigen::VectorXd single(6 * stressPointsPerElement(order));
    for (Eigen::Index e = 0; e < mesh.tets.rows(); ++e) {  // element(): the element's own stresses
      recovery.value().element(e, u.col(0), single.data());
      EXPECT_LE((single - own.col(0).segment(single.size() * e, single.size())).cwiseAbs().maxCoeff(),
                1e-9 * modes.cwiseAbs().maxCoeff());
    }
  }
  EXPECT_EQ(femNodeCount(mesh, ElementOrder::P2), quadraticBox(0.3, 0.2, 0.1, 3, 2, 1).nodes.rows());
}

TEST(FemAssemblyP2, CornerStressesBoundTheStressEverywhereInTheElement) {
  // The stress of a straight-sided P2 tet is linear, so any convex function of it (the largest
  // principal stress, the norm) peaks at a corner: what the stress scan's bounds rely on.
  const auto mesh = quadraticBox(0.3, 0.2, 0.1, 2, 1, 1);
  const Material m = presetGlass();
  const auto c = isotropicElasticity(m.youngsModulusPa, m.poissonRatio);
  std::mt19937 random(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  MatrixXdRow u(3 * mesh.nodes.rows(), 1);
  for (Eigen::Index i = 0; i < u.rows(); ++i) u(i, 0) = 1e-6 * (2.0 * unit(random) - 1.0);
  const MatrixXdRow s = computeStressModes(mesh, m, u);
  auto largestPrincipal = [](const Eigen::Matrix<double, 6, 1>& v) {
    Eigen::Matrix3d t;
    t << v(0), v(5), v(4), v(5), v(1), v(3), v(4), v(3), v(2);
    return Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(t, Eigen::EigenvaluesOnly).eigenvalues()(2);
  };
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
    double cornerPrincipal = -1e300, cornerNorm = 0.0;
    for (int k = 0; k < 4; ++k) {
      const Eigen::Matrix<double, 6, 1> corner = s.middleRows(24 * t + 6 * k, 6);
      cornerPrincipal = std::max(cornerPrincipal, largestPrincipal(corner));
      cornerNorm = std::max(cornerNorm, corner.norm());
    }
    Eigen::Matrix<double, 30, 1> ue;
    for (int a = 0; a < 10; ++a) ue.segment<3>(3 * a) = u.middleRows(3 * mesh.tets(t, a), 3);
    for (int sample = 0; sample < 50; ++sample) {
      Eigen::Vector4d l(unit(random), unit(random), unit(random), unit(random));
      l /= l.sum();
      const auto b = quadraticTetStrainDisplacement(mesh.nodes.row(mesh.tets(t, 0)).transpose(), mesh.nodes.row(mesh.tets(t, 1)).transpose(),
                                                    mesh.nodes.row(mesh.tets(t, 2)).transpose(), mesh.nodes.row(mesh.tets(t, 3)).transpose(), l, nullptr);
      const Eigen::Matrix<double, 6, 1> inside = c * b * ue;
      EXPECT_LE(largestPrincipal(inside), cornerPrincipal + 1e-9 * cornerNorm) << "tet " << t;
      EXPECT_LE(inside.norm(), cornerNorm * (1.0 + 1e-12)) << "tet " << t;
      // And it is the linear interpolation of the corner values.
      Eigen::Matrix<double, 6, 1> interpolated = Eigen::Matrix<double, 6, 1>::Zero();
      for (int k = 0; k < 4; ++k) interpolated += l(k) * s.middleRows(24 * t + 6 * k, 6).transpose();
      EXPECT_LT((inside - interpolated).norm(), 1e-9 * cornerNorm) << "tet " << t;
    }
  }
}

TEST(FemAssemblyP2, RejectsDegenerateInvertedAndCurvedTets) {
  auto linear = testing::makeBoxTetMesh(1.0, 1.0, 1.0, 1, 1, 1);
  std::swap(linear.tets(2, 0), linear.tets(2, 1));
  auto inverted = assembleFem(makeQuadraticTetMesh(linear).value(), presetGlass(), {});
  ASSERT_FALSE(inverted.ok());
  EXPECT_EQ(inverted.error().code, ErrorCode::DegenerateElement);
  EXPECT_NE(inverted.error().message.find("tet 2"), std::string::npos);
  auto flat = testing::makeBoxTetMesh(2.0, 1.0, 0.5, 1, 1, 1);
  flat.nodes.row(flat.tets(0, 3)) = (flat.nodes.row(flat.tets(0, 0)) + flat.nodes.row(flat.tets(0, 1)) + flat.nodes.row(flat.tets(0, 2))) / 3.0;
  EXPECT_EQ(assembleFem(makeQuadraticTetMesh(flat).value(), presetGlass(), {}).error().code, ErrorCode::DegenerateElement);
  auto q = quadraticBox(1.0, 1.0, 1.0, 1, 1, 1);
  q.tets(4, 7) = static_cast<int32_t>(q.nodes.rows());
  EXPECT_EQ(assembleFem(q, presetGlass(), {}).error().code, ErrorCode::DegenerateElement);
  auto curved = quadraticBox(1.0, 1.0, 1.0, 1, 1, 1);
  curved.nodes(curved.tets(3, 6), 2) += 1e-3;
  auto notStraight = assembleFem(curved, presetGlass(), {});
  ASSERT_FALSE(notStraight.ok());
  EXPECT_EQ(notStraight.error().code, ErrorCode::InvalidArgument);
  EXPECT_NE(notStraight.error().message.find("midpoint"), std::string::npos);
  Material bad = presetGlass();
  bad.densityKgPerM3 = -1.0;
  EXPECT_EQ(assembleFem(quadraticBox(1, 1, 1, 1, 1, 1), bad, {}).error().code, ErrorCode::InvalidMaterial);
}

}  // namespace
}  // namespace brittle
