// SupernodalCholesky.h (private to the runtime): the supernodal factor of a quadratic-tet solid's
// K + M solves it to rounding and agrees with Eigen's SimplicialLDLT, in its nodes' order and in
// the DOF's own; what is not positive definite, not finite or not square is refused; factorInOrder
// hands it over in SimplicialLDLT's form, with Eigen's pattern, in a given order and in AMD's; and
// the own-mesh check that uses it gives the frequencies of the exact path's modal analysis.
#include "SupernodalCholesky.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>

#include "brittle/runtime/FemAssembly.h"
#include "brittle/runtime/FragmentModes.h"
#include "brittle/runtime/StaticCorrection.h"
#include "brittle/testing/BakeFixtures.h"
#include "brittle/testing/Fixtures.h"

namespace brittle {
namespace {

using detail::SupernodalCholesky;

// K and M of a glass box in quadratic tets (8 × 4 × 3 cells, 2.2k DOF).
FemSystem glassBoxSystem() {
  const TetMesh box = testing::makeBoxTetMesh(0.08, 0.04, 0.03, 8, 4, 3);
  auto mesh = makeFemMesh(box, ElementOrder::P2);  // it points into `box`
  EXPECT_TRUE(mesh);
  auto fem = assembleFem(mesh.value(), testing::presetGlass(), FemSettings{});
  EXPECT_TRUE(fem);
  return fem.value();
}

Eigen::VectorXd randomVector(Eigen::Index n, unsigned seed) {
  std::mt19937_64 rng(seed);
  Eigen::VectorXd v(n);
  for (Eigen::Index i = 0; i < n; ++i) v[i] = static_cast<double>(rng() >> 11) * 0x1.0p-53 - 0.5;
  return v;
}

TEST(SupernodalCholesky, SolvesAQuadraticSolidAsEigensFactorDoes) {
  // K + μM with μ at 1 kHz: the rigid motions' eigenvalue μ keeps A's condition near 10⁶, where
  // K + M's (~10¹²) would leave both solutions' rigid parts uncertain in their fourth digit.
  const FemSystem fem = glassBoxSystem();
  const Eigen::SparseMatrix<double> a = fem.stiffness + std::pow(2.0 * M_PI * 1e3, 2) * fem.mass;
  const Eigen::Index n = a.rows();
  ASSERT_GT(n, 2000);
  const Eigen::VectorXd b = randomVector(n, 7);
  const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> eigen(a);
  ASSERT_EQ(eigen.info(), Eigen::Success);
  const Eigen::VectorXd reference = eigen.solve(b);
  for (Eigen::Index block : {Eigen::Index{1}, Eigen::Index{3}}) {
    SCOPED_TRACE(block);
    SupernodalCholesky factor;
    ASSERT_TRUE(factor.compute(a, block));
    EXPECT_EQ(factor.rows(), n);
    EXPECT_LT(factor.supernodeCount(), n / 3);  // a node's three columns at least, most of them wider
    // The same order fills L as Eigen's does; the nodes' order within a few per cent of it.
    const auto eigenNonZeros = static_cast<double>(eigen.matrixL().nestedExpression().nonZeros() + n);
    EXPECT_LT(static_cast<double>(factor.nonZeros()), 1.1 * eigenNonZeros);
    if (block == 1) {
      EXPECT_EQ(static_cast<double>(factor.nonZeros()), eigenNonZeros);
    }
    Eigen::VectorXd x = b;
    factor.solve(x);
    std::printf("block %ld: residual %.3g (Eigen's %.3g), difference %.3g\n", static_cast<long>(block), (a * x - b).norm() / b.norm(), (a * reference - b).norm() / b.norm(), (x - reference).norm() / reference.norm());
    EXPECT_LT((a * x - b).norm() / b.norm(), std::max(1e-11, 2.0 * (a * reference - b).norm() / b.norm()));
    EXPECT_LT((x - reference).norm() / reference.norm(), 1e-10);
    // ‖Lᵀ P v‖² = vᵀ A v, and L L⁻¹ (through Lᵀ and its solve) is the identity.
    const Eigen::VectorXd v = randomVector(n, 11);
    Eigen::VectorXd pv(n), ltpv(n);
    factor.permute(v.data(), pv.data());
    factor.multiplyLt(pv.data(), ltpv.data());
    EXPECT_NEAR(ltpv.squaredNorm() / v.dot(a * v), 1.0, 1e-12);
    Eigen::VectorXd back = ltpv;
    factor.solveLt(back.data());
    EXPECT_LT((back - pv).norm() / pv.norm(), 1e-12);
    Eigen::VectorXd unpermuted(n);
    factor.permuteBack(pv.data(), unpermuted.data());
    EXPECT_EQ(unpermuted, v);
  }
}

TEST(SupernodalCholesky, RefusesWhatIsNotPositiveDefiniteFiniteOrSquare) {
  const FemSystem fem = glassBoxSystem();
  SupernodalCholesky factor;
  // K − λM with λ past the lowest elastic eigenvalues (tens of kHz here) is indefinite.
  const double lambda = std::pow(2.0 * M_PI * 1e5, 2);
  EXPECT_FALSE(factor.compute(fem.stiffness - lambda * fem.mass, 3));
  EXPECT_EQ(factor.rows(), 0);
  Eigen::SparseMatrix<double> nan = fem.stiffness + fem.mass;
  nan.coeffs()[17] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(factor.compute(nan, 3));
  EXPECT_FALSE(factor.compute(Eigen::SparseMatrix<double>(4, 5)));
  EXPECT_FALSE(factor.compute(Eigen::SparseMatrix<double>(0, 0)));
  // A zero pivot: the identity with one diagonal entry zero.
  Eigen::SparseMatrix<double> singular(6, 6);
  for (int i = 0; i < 6; ++i) singular.insert(i, i) = i == 4 ? 0.0 : 1.0;
  EXPECT_FALSE(factor.compute(singular, 3));
  EXPECT_TRUE(factor.compute(fem.stiffness + fem.mass, 3));
}

// Both Lanczos runs on the supernodal factor: the own-mesh check's with the rigid motions projected
// out of the operator, the exact path's with them computed as modes: a box of 7.4k quadratic DOF
// checks to the exact path's frequencies of it.
TEST(SupernodalCholesky, TheLargeQuadraticChecksFrequenciesAreTheExactPaths) {
  const FragmentSubMesh sub{testing::makeBoxTetMesh(0.12, 0.05, 0.04, 12, 5, 4), 0, 0, 0.0};
  ASSERT_GT(3 * makeFemMesh(sub.mesh, ElementOrder::P2).value().nodes().rows(), 7000);
  auto ratios = meshFrequencyRatios(sub, testing::presetGlass(), 5, kMeshRatioModes, ElementOrder::P2);
  ASSERT_TRUE(ratios) << ratios.error().message;
  ExactModesSettings es;
  es.modeCount = kMeshRatioModes;
  es.elementOrder = ElementOrder::P2;
  auto own = exactFragmentAsset(sub, testing::presetGlass(), es, "own");
  ASSERT_TRUE(own) << own.error().message;
  for (int k = 0; k < kMeshRatioModes; ++k) EXPECT_NEAR(ratios.value().meshHz[k] / own.value().modal.frequenciesHz[k], 1.0, 1e-9) << k;
}

// factorInOrder's factor is SimplicialLDLT's state: Eigen's pattern (the same non-zeros of L, in
// AMD's order and in a given one), its solve() within rounding of Eigen's own factor's, and
// L D Lᵀ = P A Pᵀ entry by entry.
TEST(SupernodalCholesky, FactorInOrderHandsOverSimplicialLdltsForm) {
  const FemSystem fem = glassBoxSystem();
  const Eigen::SparseMatrix<double> a = fem.stiffness + std::pow(2.0 * M_PI * 1e3, 2) * fem.mass;
  const Eigen::Index n = a.rows();
  const Eigen::VectorXd b = randomVector(n, 5);
  // A given order: AMD's on the nodes' graph, which Eigen's analysis would not choose.
  SupernodalCholesky byNodes;
  ASSERT_TRUE(byNodes.compute(a, 3));
  Eigen::VectorXi given(n);
  for (Eigen::Index i = 0; i < n; ++i) given[i] = byNodes.orderAt(i);
  for (const Eigen::VectorXi& order : {Eigen::VectorXi(), given}) {
    SCOPED_TRACE(order.size());
    auto made = factorInOrder(a, order);
    ASSERT_TRUE(made) << made.error().message;
    const ShiftedFactor& factor = *made.value();
    ASSERT_EQ(factor.info(), Eigen::Success);
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> eigen;
    if (order.size() == 0) {
      eigen.compute(a);
    } else {
      // Eigen's own with the same order: the natural order of P A Pᵀ.
      Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> inverse(n);
      inverse.indices() = order;
      Eigen::SparseMatrix<double> ap(n, n);
      ap.selfadjointView<Eigen::Lower>() = a.selfadjointView<Eigen::Lower>().twistedBy(inverse.inverse());
      Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower, Eigen::NaturalOrdering<int>> natural(ap);
      ASSERT_EQ(natural.info(), Eigen::Success);
      EXPECT_EQ(factor.matrixL().nestedExpression().nonZeros(), natural.matrixL().nestedExpression().nonZeros());
      EXPECT_EQ(factor.permutationPinv().indices(), order);
    }
    if (order.size() == 0) {
      ASSERT_EQ(eigen.info(), Eigen::Success);
      EXPECT_EQ(factor.matrixL().nestedExpression().nonZeros(), eigen.matrixL().nestedExpression().nonZeros());
      EXPECT_EQ(factor.permutationP().indices(), eigen.permutationP().indices());
      EXPECT_LT((factor.vectorD() - eigen.vectorD()).cwiseAbs().maxCoeff() / eigen.vectorD().cwiseAbs().maxCoeff(), 1e-12);
    }
    const Eigen::VectorXd x = factor.solve(b);
    EXPECT_LT((a * x - b).norm() / b.norm(), 1e-11);
    const Eigen::SparseMatrix<double> l = factor.matrixL();
    const Eigen::SparseMatrix<double> ldlt = l * factor.vectorD().asDiagonal() * l.transpose();
    Eigen::SparseMatrix<double> pap(n, n);
    pap = a.selfadjointView<Eigen::Lower>().twistedBy(factor.permutationP());
    const Eigen::SparseMatrix<double> difference = ldlt - pap;
    EXPECT_LT(difference.coeffs().cwiseAbs().maxCoeff() / pap.coeffs().cwiseAbs().maxCoeff(), 1e-13);
  }
  Eigen::VectorXi twice = given;
  twice[0] = twice[1];
  EXPECT_EQ(factorInOrder(a, twice).error().code, ErrorCode::InvalidArgument);
  EXPECT_EQ(factorInOrder(fem.stiffness - std::pow(2.0 * M_PI * 1e5, 2) * fem.mass, Eigen::VectorXi()).error().code,
            ErrorCode::FactorizationFailed);
}

// The lower triangle alone, or in a matrix not compressed, is read as the full matrix: the same
// bits; a block that does not divide n orders the DOF's own graph; one row and a diagonal are
// solved exactly; computeInOrder refuses what is not a permutation.
TEST(SupernodalCholesky, ReadsTheLowerTriangleAloneAndSmallMatricesExactly) {
  const FemSystem fem = glassBoxSystem();
  const Eigen::SparseMatrix<double> a = fem.stiffness + std::pow(2.0 * M_PI * 1e3, 2) * fem.mass;
  const Eigen::Index n = a.rows();
  const Eigen::VectorXd b = randomVector(n, 3);
  Eigen::SparseMatrix<double> lower = a.triangularView<Eigen::Lower>();
  Eigen::SparseMatrix<double> uncompressed(n, n);
  uncompressed.reserve(Eigen::VectorXi::Constant(n, 200));
  for (Eigen::Index col = 0; col < n; ++col)
    for (Eigen::SparseMatrix<double>::InnerIterator it(a, col); it; ++it) uncompressed.insert(it.row(), col) = it.value();
  ASSERT_FALSE(uncompressed.isCompressed());
  for (Eigen::Index block : {Eigen::Index{1}, Eigen::Index{3}}) {
    SupernodalCholesky full, alone, loose;
    ASSERT_TRUE(full.compute(a, block));
    ASSERT_TRUE(alone.compute(lower, block));
    ASSERT_TRUE(loose.compute(uncompressed, block));
    Eigen::VectorXd x = b, y = b, z = b;
    full.solve(x);
    alone.solve(y);
    loose.solve(z);
    EXPECT_EQ(x, y) << block;
    EXPECT_EQ(x, z) << block;
  }
  // A NaN above the diagonal is never read.
  Eigen::SparseMatrix<double> upperNan = a;
  for (Eigen::SparseMatrix<double>::InnerIterator it(upperNan, n - 1); it; ++it)
    if (it.row() < n - 1) it.valueRef() = std::numeric_limits<double>::quiet_NaN();
  SupernodalCholesky factor;
  EXPECT_TRUE(factor.compute(upperNan, 3));

  Eigen::SparseMatrix<double> one(1, 1);
  one.insert(0, 0) = 4.0;
  ASSERT_TRUE(factor.compute(one, 3));  // 3 does not divide 1: the DOF's own order
  Eigen::VectorXd x = Eigen::VectorXd::Constant(1, 2.0);
  factor.solve(x);
  EXPECT_EQ(x[0], 0.5);
  Eigen::SparseMatrix<double> diagonal(7, 7);
  for (int i = 0; i < 7; ++i) diagonal.insert(i, i) = 1.0 + i;
  ASSERT_TRUE(factor.compute(diagonal, 3));
  EXPECT_EQ(factor.supernodeCount(), 7);
  EXPECT_EQ(factor.nonZeros(), 7);
  Eigen::VectorXd d = Eigen::VectorXd::LinSpaced(7, 1.0, 7.0);
  factor.solve(d);
  EXPECT_TRUE(d.isApprox(Eigen::VectorXd::Ones(7), 1e-15));

  Eigen::VectorXi order = Eigen::VectorXi::LinSpaced(7, 0, 6);
  EXPECT_TRUE(factor.computeInOrder(diagonal, order));
  order[3] = 2;  // twice
  EXPECT_FALSE(factor.computeInOrder(diagonal, order));
  order[3] = 7;  // out of range
  EXPECT_FALSE(factor.computeInOrder(diagonal, order));
  EXPECT_FALSE(factor.computeInOrder(diagonal, Eigen::VectorXi::LinSpaced(6, 0, 5)));
  EXPECT_EQ(factor.rows(), 0);
}

// The check's frequencies on a quadratic box small enough for Eigen's dense generalised solver,
// which shares nothing with the factor, but above the check's own dense limit.
TEST(SupernodalCholesky, TheChecksFrequenciesAreTheDenseSolversOnAQuadraticBox) {
  const FragmentSubMesh sub{testing::makeBoxTetMesh(0.06, 0.03, 0.02, 4, 2, 2), 0, 0, 0.0};
  auto mesh = makeFemMesh(sub.mesh, ElementOrder::P2);
  ASSERT_TRUE(mesh);
  auto fem = assembleFem(mesh.value(), testing::presetGlass(), FemSettings{});
  ASSERT_TRUE(fem);
  ASSERT_GT(fem.value().stiffness.rows(), 2 * ExactModesSettings{}.denseMaxDof);
  const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> dense(Eigen::MatrixXd(fem.value().stiffness),
                                                                        Eigen::MatrixXd(fem.value().mass), Eigen::EigenvaluesOnly);
  ASSERT_EQ(dense.info(), Eigen::Success);
  auto ratios = meshFrequencyRatios(sub, testing::presetGlass(), 5, kMeshRatioModes, ElementOrder::P2);
  ASSERT_TRUE(ratios) << ratios.error().message;
  for (int k = 0; k < kMeshRatioModes; ++k) {
    const double hz = std::sqrt(dense.eigenvalues()[6 + k]) / (2.0 * M_PI);
    EXPECT_NEAR(ratios.value().meshHz[k] / hz, 1.0, 1e-9) << k;
  }
}

}  // namespace
}  // namespace brittle
