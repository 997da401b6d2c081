// BackwardSolve.h (private to the runtime): the backward solve by supernodes, split over subtrees
// of the elimination tree, gives the same bits for any number of parts and equals Eigen's serial
// solve within rounding, on the factors the static correction makes (a P1 and a P2 glass box), and
// most of it runs in parallel; the forward solve is Eigen's bit for bit.
#include "BackwardSolve.h"

#include <gtest/gtest.h>

#include <Eigen/SparseCholesky>
#include <cstring>
#include <functional>
#include <memory>
#include <random>

#include "brittle/runtime/FemAssembly.h"
#include "brittle/runtime/StaticCorrection.h"
#include "brittle/testing/BakeFixtures.h"
#include "brittle/testing/Fixtures.h"

namespace brittle {
namespace {

// The factor the static correction makes of a glass box's K + M (1.2k tets of `order`).
std::unique_ptr<ShiftedFactor> glassBoxFactor(ElementOrder order) {
  const ObjectAsset plate = testing::makeGlassPlatePack(1200, 6, 0.1, order).value().objects[0];
  auto mesh = makeFemMesh(plate.tetMesh, order);
  if (!mesh) return nullptr;
  auto fem = assembleFem(mesh.value(), testing::presetGlass(), FemSettings{});
  if (!fem) return nullptr;
  auto factor = std::make_unique<ShiftedFactor>(fem.value().stiffness + 1.0 * fem.value().mass);
  return factor->info() == Eigen::Success ? std::move(factor) : nullptr;
}

// `check` on the factors of a P1 and a P2 box.
void forEachBoxFactor(
    const std::function<void(ElementOrder, const ShiftedFactor&, const Eigen::SparseMatrix<double>&)>& check) {
  for (ElementOrder order : {ElementOrder::P1, ElementOrder::P2}) {
    SCOPED_TRACE(elementOrderName(order));
    const std::unique_ptr<ShiftedFactor> factor = glassBoxFactor(order);
    ASSERT_NE(factor, nullptr);
    check(order, *factor, factor->matrixL().nestedExpression());
  }
}

TEST(BackwardSolve, SameBitsOnAnyNumberOfPartsAndEigensSerialSolveWithinRounding) {
  forEachBoxFactor([&](ElementOrder order, const ShiftedFactor& factor, const Eigen::SparseMatrix<double>& lower) {
    std::mt19937_64 rng(5);
    std::normal_distribution<double> g(0.0, 1.0);
    Eigen::VectorXd y(lower.rows());
    for (Eigen::Index i = 0; i < y.size(); ++i) y[i] = g(rng);
    Eigen::VectorXd eigen = y;
    factor.matrixU().solveInPlace(eigen);
    Eigen::VectorXd serial = y;
    detail::BackwardSolvePlan::make(lower, 1).solveInPlace(lower, serial);
    // The sums run in another order than Eigen's: equal within a few ulps of the largest |x|.
    EXPECT_LT((serial - eigen).cwiseAbs().maxCoeff(), 1e-13 * eigen.cwiseAbs().maxCoeff());
    EXPECT_GT((serial - eigen).cwiseAbs().maxCoeff(), 0.0);  // (it is not Eigen's order)
    detail::BackwardSolvePlan::Scratch scratch;  // reused by every plan below
    for (int parts : {1, 2, 3, 7}) {
      const detail::BackwardSolvePlan plan = detail::BackwardSolvePlan::make(lower, parts);
      EXPECT_EQ(plan.valueBytes(), sizeof(double) * static_cast<size_t>(lower.nonZeros()));  // each value once
      Eigen::VectorXd x = y;
      plan.solveInPlace(lower, x, scratch);
      EXPECT_EQ(std::memcmp(x.data(), serial.data(), sizeof(double) * static_cast<size_t>(x.size())), 0)
          << parts << " parts: max difference " << (x - serial).cwiseAbs().maxCoeff();
      if (parts == 1) {
        EXPECT_EQ(plan.parallelShare(), 0.0);
        EXPECT_EQ(plan.criticalShare(), 1.0);
      } else {
        EXPECT_EQ(plan.parts(), parts);
        // A 3D mesh's tree is bushy below its top separators: most of L is in the subtrees, and
        // the critical path is well under the serial solve's.
        EXPECT_GT(plan.parallelShare(), 0.5) << parts << " parts";
        EXPECT_LT(plan.criticalShare(), parts == 2 ? 0.7 : 0.8) << parts << " parts";
        std::printf("%s, %lld unknowns, %lld non-zeros in L, %d parts: %.1f %% of L in parallel, critical path %.1f %%\n",
                    elementOrderName(order), static_cast<long long>(lower.rows()),
                    static_cast<long long>(lower.nonZeros()), parts, 100.0 * plan.parallelShare(),
                    100.0 * plan.criticalShare());
      }
    }
  });
}

TEST(BackwardSolve, TheForwardSolveIsEigensBitForBitForSparseAndDenseRightHandSides) {
  // Eigen's loop passes x_j on to the rows of column j, column by column, skipping exact zeros;
  // gathering each supernode's rows below it changes where the sums live, not their order.
  forEachBoxFactor([&](ElementOrder, const ShiftedFactor& factor, const Eigen::SparseMatrix<double>& lower) {
    const detail::BackwardSolvePlan plan = detail::BackwardSolvePlan::make(lower, 2);
    std::mt19937_64 rng(7);
    std::normal_distribution<double> g(0.0, 1.0);
    std::uniform_int_distribution<Eigen::Index> row(0, lower.rows() - 1);
    detail::BackwardSolvePlan::Scratch gathered;
    for (int nonZeros : {1, 3, 12, -1}) {  // -1: every entry
      Eigen::VectorXd y = Eigen::VectorXd::Zero(lower.rows());
      if (nonZeros < 0) {
        for (Eigen::Index i = 0; i < y.size(); ++i) y[i] = g(rng);
      } else {
        for (int k = 0; k < nonZeros; ++k) y[row(rng)] = g(rng);
      }
      Eigen::VectorXd expected = y, x = y;
      factor.matrixL().solveInPlace(expected);
      plan.forwardInPlace(lower, x, gathered);
      EXPECT_EQ(std::memcmp(x.data(), expected.data(), sizeof(double) * static_cast<size_t>(x.size())), 0)
          << nonZeros << " non-zeros: max difference " << (x - expected).cwiseAbs().maxCoeff();
      EXPECT_GT((x - y).cwiseAbs().maxCoeff(), 0.0);  // (the solve did pass values on)
    }
  });
}

TEST(BackwardSolve, AChainIsSolvedAloneAndAnEmptyFactorIsFine) {
  // A tridiagonal matrix's tree is one chain: whatever goes to a part waits for the rest, so the
  // critical path is the whole solve, and the answer still equals the serial solve (one
  // supernode, each column one product: Eigen's arithmetic exactly).
  const int n = 50;
  Eigen::SparseMatrix<double> a(n, n);
  for (int i = 0; i < n; ++i) {
    a.insert(i, i) = 4.0;
    if (i + 1 < n) a.insert(i + 1, i) = a.insert(i, i + 1) = -1.0;
  }
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower, Eigen::NaturalOrdering<int>> factor(a);
  ASSERT_EQ(factor.info(), Eigen::Success);
  const Eigen::SparseMatrix<double>& lower = factor.matrixL().nestedExpression();
  const detail::BackwardSolvePlan plan = detail::BackwardSolvePlan::make(lower, 2);
  EXPECT_NEAR(plan.criticalShare(), 1.0, 1e-12);
  Eigen::VectorXd x = Eigen::VectorXd::LinSpaced(n, 1.0, 2.0), expected = x;
  factor.matrixU().solveInPlace(expected);
  plan.solveInPlace(lower, x);
  EXPECT_EQ(x, expected);
  Eigen::VectorXd forward = Eigen::VectorXd::LinSpaced(n, 1.0, 2.0), forwardExpected = forward;
  factor.matrixL().solveInPlace(forwardExpected);
  detail::BackwardSolvePlan::Scratch gathered;
  plan.forwardInPlace(lower, forward, gathered);
  EXPECT_EQ(forward, forwardExpected);
  const Eigen::SparseMatrix<double> empty(0, 0);
  Eigen::VectorXd none;
  detail::BackwardSolvePlan::make(empty, 2).solveInPlace(empty, none);
  detail::BackwardSolvePlan::make(empty, 2).forwardInPlace(empty, none, gathered);
  EXPECT_EQ(none.size(), 0);
}

}  // namespace
}  // namespace brittle
