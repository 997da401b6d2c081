// BackwardSolve.h (private to the runtime): the backward solve by supernodes, split over subtrees
// of the elimination tree, gives the same bits for any number of parts and equals Eigen's serial
// solve within rounding, on the factors the static correction makes (a P1 and a P2 glass box), and
// most of it runs in parallel, in SSE2 or AVX registers alike, from L's values in double or in
// float; the forward solve is Eigen's bit for bit.
#include "BackwardSolve.h"

#include <gtest/gtest.h>

#include <Eigen/SparseCholesky>
#include <cstring>
#include <functional>
#include <map>
#include <memory>
#include <random>
#include <vector>

#include "brittle/runtime/FemAssembly.h"
#include "brittle/runtime/StaticCorrection.h"
#include "brittle/testing/BakeFixtures.h"
#include "brittle/testing/Fixtures.h"

namespace brittle {
namespace {

// The factor the static correction makes of a glass box's K + M (1.2k tets of `order`), made once
// per process and element (the suite is one ctest test: SHARED_SUITES); the tests only read it.
const ShiftedFactor* glassBoxFactor(ElementOrder order) {
  static std::map<ElementOrder, std::unique_ptr<ShiftedFactor>> made;
  auto [it, inserted] = made.try_emplace(order);
  if (!inserted) return it->second.get();
  const ObjectAsset plate = testing::makeGlassPlatePack(1200, 6, 0.1, order).value().objects[0];
  auto mesh = makeFemMesh(plate.tetMesh, order);
  if (!mesh) return nullptr;
  auto fem = assembleFem(mesh.value(), testing::presetGlass(), FemSettings{});
  if (!fem) return nullptr;
  auto factor = std::make_unique<ShiftedFactor>(fem.value().stiffness + 1.0 * fem.value().mass);
  if (factor->info() == Eigen::Success) it->second = std::move(factor);
  return it->second.get();
}

// `check` on the factors of a P1 and a P2 box.
void forEachBoxFactor(
    const std::function<void(ElementOrder, const ShiftedFactor&, const Eigen::SparseMatrix<double>&)>& check) {
  for (ElementOrder order : {ElementOrder::P1, ElementOrder::P2}) {
    SCOPED_TRACE(elementOrderName(order));
    const ShiftedFactor* factor = glassBoxFactor(order);
    ASSERT_NE(factor, nullptr);
    check(order, *factor, factor->matrixL().nestedExpression());
  }
}

// The lanes this CPU runs: SSE2 always, AVX where it has it.
std::vector<Lanes> lanesHere() {
  std::vector<Lanes> lanes{Lanes::Narrow};
  if (widestLanes() == Lanes::Wide) lanes.push_back(Lanes::Wide);
  return lanes;
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
    detail::BackwardSolvePlan::Scratch scratch;  // reused by every plan below
    detail::BackwardSolvePlan::make(lower, 1).solveInPlace(lower, serial, scratch, Lanes::Narrow);
    // L's values in float, the sums in double: within float rounding of the double solve.
    Eigen::VectorXd serialFloat = y;
    detail::BackwardSolvePlan::make(lower, 1, true).solveInPlace(lower, serialFloat, scratch, Lanes::Narrow);
    const double movedByFloat = (serialFloat - serial).cwiseAbs().maxCoeff();
    EXPECT_LT(movedByFloat, 1e-5 * serial.cwiseAbs().maxCoeff());
    EXPECT_GT(movedByFloat, 1e-10 * serial.cwiseAbs().maxCoeff()) << "the float copy was not read";
    // The sums run in another order than Eigen's: equal within a few ulps of the largest |x|.
    EXPECT_LT((serial - eigen).cwiseAbs().maxCoeff(), 1e-13 * eigen.cwiseAbs().maxCoeff());
    EXPECT_GT((serial - eigen).cwiseAbs().maxCoeff(), 0.0);  // (it is not Eigen's order)
    for (int parts : {1, 2, 3, 7}) {
      const detail::BackwardSolvePlan plan = detail::BackwardSolvePlan::make(lower, parts);
      const detail::BackwardSolvePlan floats = detail::BackwardSolvePlan::make(lower, parts, true);
      EXPECT_EQ(plan.valueBytes(), sizeof(double) * static_cast<size_t>(lower.nonZeros()));  // each value once
      // in float each value twice: in the backward solve's order, and in Eigen's for the forward solve
      EXPECT_EQ(floats.valueBytes(), 2 * sizeof(float) * static_cast<size_t>(lower.nonZeros()));
      for (Lanes lanes : lanesHere()) {  // SSE2 and, where the CPU has it, AVX: the same bits
        for (const auto& [p, expected] : {std::pair{&plan, &serial}, std::pair{&floats, &serialFloat}}) {
          Eigen::VectorXd x = y;
          p->solveInPlace(lower, x, scratch, lanes);
          EXPECT_EQ(std::memcmp(x.data(), expected->data(), sizeof(double) * static_cast<size_t>(x.size())), 0)
              << parts << " parts, " << (lanes == Lanes::Wide ? "AVX" : "SSE2") << (p == &floats ? ", float" : "")
              << ": max difference " << (x - *expected).cwiseAbs().maxCoeff();
        }
      }
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

TEST(BackwardSolve, TheFloatPlansForwardSolveIsEigensOnTheFactorRoundedToFloat) {
  // A plan with float values reads L rounded to float in the forward solve too: bit for bit
  // Eigen's solve of that rounded L, and not Eigen's solve of L itself (the rounding is there).
  forEachBoxFactor([&](ElementOrder order, const ShiftedFactor& factor, const Eigen::SparseMatrix<double>& lower) {
    const detail::BackwardSolvePlan plan = detail::BackwardSolvePlan::make(lower, 2, true);
    Eigen::SparseMatrix<double> rounded = lower;
    for (Eigen::Index p = 0; p < rounded.nonZeros(); ++p) {
      rounded.valuePtr()[p] = static_cast<double>(static_cast<float>(rounded.valuePtr()[p]));
    }
    std::mt19937_64 rng(11);
    std::normal_distribution<double> g(0.0, 1.0);
    std::uniform_int_distribution<Eigen::Index> row(0, lower.rows() - 1);
    detail::BackwardSolvePlan::Scratch gathered;
    for (int nonZeros : {1, 12, -1}) {  // -1: every entry
      Eigen::VectorXd y = Eigen::VectorXd::Zero(lower.rows());
      if (nonZeros < 0) {
        for (Eigen::Index i = 0; i < y.size(); ++i) y[i] = g(rng);
      } else {
        for (int k = 0; k < nonZeros; ++k) y[row(rng)] = g(rng);
      }
      Eigen::VectorXd expected = y, exact = y, x = y;
      rounded.triangularView<Eigen::UnitLower>().solveInPlace(expected);
      factor.matrixL().solveInPlace(exact);
      plan.forwardInPlace(lower, x, gathered);
      EXPECT_EQ(std::memcmp(x.data(), expected.data(), sizeof(double) * static_cast<size_t>(x.size())), 0)
          << elementOrderName(order) << ", " << nonZeros << " non-zeros: max difference " << (x - expected).cwiseAbs().maxCoeff();
      if (nonZeros < 0) {
        EXPECT_GT((x - exact).cwiseAbs().maxCoeff(), 0.0) << elementOrderName(order);
      }
      EXPECT_LE((x - exact).cwiseAbs().maxCoeff(), 1e-5 * exact.cwiseAbs().maxCoeff()) << elementOrderName(order);
    }
  });
}

// y_i ← (y_i − h_i·c) s_i, the static correction's pass over H = L⁻¹PM[Ψ Φ]: each row's dot
// product in four running sums (k mod 4) added pairwise, exactly, for float and double rows, row
// counts and widths that are not whole registers, in either lanes.
template <class V>
void checkRowProducts() {
  std::mt19937_64 rng(11);
  std::normal_distribution<double> g(0.0, 1.0);
  for (Eigen::Index m : {1, 7, 46}) {
    const Eigen::Index rows = 37;
    std::vector<V> h(static_cast<size_t>(rows * m));
    for (V& v : h) v = static_cast<V>(g(rng));
    std::vector<double> c(static_cast<size_t>(m)), scale(static_cast<size_t>(rows)), y0(static_cast<size_t>(rows));
    for (double& v : c) v = g(rng);
    for (double& v : scale) v = g(rng);
    for (double& v : y0) v = g(rng);
    std::vector<double> expected = y0;
    for (Eigen::Index i = 3; i < rows; ++i) {  // rows [3, rows): the rows before stay
      double acc[4] = {};
      for (Eigen::Index k = 0; k < m; ++k) acc[k % 4] += static_cast<double>(h[static_cast<size_t>(i * m + k)]) * c[static_cast<size_t>(k)];
      expected[static_cast<size_t>(i)] = (y0[static_cast<size_t>(i)] - ((acc[0] + acc[1]) + (acc[2] + acc[3]))) * scale[static_cast<size_t>(i)];
    }
    for (Lanes lanes : lanesHere()) {
      std::vector<double> y = y0;
      detail::subtractRowProducts(h.data(), m, 3, rows, c.data(), scale.data(), y.data(), lanes);
      EXPECT_EQ(std::memcmp(y.data(), expected.data(), sizeof(double) * y.size()), 0)
          << m << " columns, " << (lanes == Lanes::Wide ? "AVX" : "SSE2");
    }
  }
}

TEST(BackwardSolve, RowProductsAreFourRunningSumsInEitherLanes) {
  checkRowProducts<double>();
  checkRowProducts<float>();
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
