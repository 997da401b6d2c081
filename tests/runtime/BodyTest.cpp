// A body's later version at other frequencies (runtime/src/Body.h, withFrequencies): what depends
// on the frequencies is its own, ω and ζ as makeBody computes them, the rest is the base's, and
// its typed errors.
#include <gtest/gtest.h>

#include <cmath>
#include <utility>
#include <vector>

#include "Body.h"
#include "Cancellation.h"
#include "brittle/precompute/TetMesher.h"
#include "brittle/runtime/FemAssembly.h"
#include "brittle/database/Material.h"
#include "brittle/testing/Fixtures.h"

namespace brittle {
namespace {

// A small block's body with two modes of made-up shapes (nothing here reads them as physics)
// and, as a matched body has, the eigenvalues its static correction is for.
std::shared_ptr<const detail::Body> twoModeBody(const Eigen::VectorXd& correctionEigenvalues) {
  TetMeshSettings meshing;
  meshing.targetTets = 200;
  ObjectAsset asset;
  asset.name = "block";
  asset.tetMesh = tetrahedralize(testing::makeBoxSurface(0.1, 0.05, 0.02), meshing).value().mesh;
  const Eigen::Index n = asset.tetMesh.nodes.rows();
  asset.modal.modes = Eigen::MatrixXd::Zero(3 * n, 2);
  for (Eigen::Index i = 0; i < 3 * n; ++i) {
    asset.modal.modes(i, 0) = std::sin(0.1 * static_cast<double>(i));
    asset.modal.modes(i, 1) = std::cos(0.2 * static_cast<double>(i));
  }
  asset.modal.eigenvaluesRad2PerS2 = Eigen::Vector2d(4.0e6, 9.0e6);
  asset.modal.frequenciesHz = asset.modal.eigenvaluesRad2PerS2.cwiseSqrt() / (2.0 * M_PI);
  asset.modal.residuals = Eigen::Vector2d::Zero();
  asset.stressModes = MatrixXdRow::Constant(6 * asset.tetMesh.tets.rows(), 2, 1.0);
  auto body = detail::makeBody(asset, testing::presetGlass(), 0, nullptr, correctionEigenvalues);
  EXPECT_TRUE(body) << body.error().message;
  return body ? body.value() : nullptr;
}

// abandon() marks a version and every later one (a removed fragment's chain: its checks, its own
// analysis), not the ones before it nor another chain; a job making an abandoned version runs with
// its flag (Cancellation.h) and stops at its next cancellation point, leaving the version unmade.
TEST(Body, AbandonMarksAVersionAndItsLaterOnesAndStopsTheirMaking) {
  using detail::Body;
  using detail::BodySource;
  using detail::CancelScope;
  using detail::Cancelled;
  using detail::cancellationPoint;
  using detail::tJobCancelFlag;
  auto failing = [] { return Result<std::shared_ptr<const Body>>(makeError(ErrorCode::InvalidArgument, "no body")); };
  auto later = [](const Result<std::shared_ptr<const Body>>& base) { return base; };
  auto chain = BodySource::deferred(failing, {{later, 1.0, true}, {later, 2.0, false}});
  auto other = BodySource::deferred(failing, {{later, 1.0, true}});
  ASSERT_TRUE(chain->late() && chain->late()->late());
  EXPECT_FALSE(chain->abandoned());
  chain->late()->abandon();
  EXPECT_FALSE(chain->abandoned());  // the version before it is still someone's
  EXPECT_TRUE(chain->late()->abandoned());
  EXPECT_TRUE(chain->late()->late()->abandoned());
  chain->abandon();
  EXPECT_TRUE(chain->abandoned());
  EXPECT_FALSE(other->abandoned());
  EXPECT_FALSE(other->late()->abandoned());

  int steps = 0;
  auto stopped = BodySource::deferred([&steps]() -> Result<std::shared_ptr<const Body>> {
    for (;;) {
      cancellationPoint();
      if (++steps == 3) return makeError(ErrorCode::InvalidArgument, "not stopped");
    }
  });
  stopped->abandon();
  {
    const CancelScope scope(tJobCancelFlag, stopped->abandonedFlag());
    EXPECT_THROW((void)stopped->get(), Cancelled);
  }
  EXPECT_EQ(steps, 0);
  EXPECT_FALSE(stopped->isMade());  // unmade, not made into an error
}

TEST(Body, ALaterVersionRingsAtItsOwnFrequenciesOnItsBasesMeshAndShapes) {
  const auto base = twoModeBody(Eigen::Vector2d(1.0e6, 2.0e6));
  ASSERT_TRUE(base);
  ModalBasis rates;
  rates.eigenvaluesRad2PerS2 = Eigen::Vector2d(2.5e6, 8.1e6);
  rates.frequenciesHz = rates.eigenvaluesRad2PerS2.cwiseSqrt() / (2.0 * M_PI);
  rates.residuals = Eigen::Vector2d(0.25, 0.5);
  auto made = detail::withFrequencies(*base, rates);
  ASSERT_TRUE(made) << made.error().message;
  const detail::Body& later = *made.value();
  EXPECT_EQ(later.asset.modal.eigenvaluesRad2PerS2, rates.eigenvaluesRad2PerS2);
  EXPECT_EQ(later.asset.modal.frequenciesHz, rates.frequenciesHz);
  EXPECT_EQ(later.asset.modal.residuals, rates.residuals);
  // ω and ζ from the new eigenvalues, as makeBody computes them.
  ASSERT_EQ(later.modes, base->modes);
  for (int j = 0; j < later.modes; ++j) {
    EXPECT_EQ(later.omega[j], std::sqrt(rates.eigenvaluesRad2PerS2[j]));
    EXPECT_EQ(later.zeta[j], rayleighDampingRatio(testing::presetGlass(), later.omega[j]));
  }
  EXPECT_NE(later.omega, base->omega);
  // Everything else is the base's.
  EXPECT_EQ(later.asset.modal.modes, base->asset.modal.modes);
  EXPECT_EQ(later.asset.stressModes, base->asset.stressModes);
  EXPECT_EQ(later.asset.tetMesh.nodes, base->asset.tetMesh.nodes);
  EXPECT_EQ(later.asset.tetMesh.tets, base->asset.tetMesh.tets);
  EXPECT_EQ(later.topology.boundaryTriangles, base->topology.boundaryTriangles);
  EXPECT_EQ(later.nodeNormals, base->nodeNormals);
  EXPECT_EQ(later.ring, base->ring);
  EXPECT_EQ(later.boundaryNodes, base->boundaryNodes);
  EXPECT_EQ(later.sizeM, base->sizeM);
  EXPECT_EQ(later.correctionEigenvalues, base->correctionEigenvalues);
  // Its stress bounds are weighted by its own 1/ω.
  EXPECT_NE(later.stressBounds().modeScales, base->stressBounds().modeScales);
  // A base whose correction was never asked for gives a version without one either.
  EXPECT_FALSE(base->staticCorrectionScheduled());
  EXPECT_FALSE(later.staticCorrectionScheduled());
}

// A scheduled correction is built once, for the base, and the version holds that one: the same
// stress per newton, bit for bit, with nothing left to build on its first impact.
TEST(Body, ALaterVersionHoldsItsBasesStaticCorrection) {
  const auto base = twoModeBody(Eigen::Vector2d(1.0e6, 2.0e6));
  ASSERT_TRUE(base);
  base->scheduleStaticCorrection();
  ASSERT_FALSE(base->staticCorrectionReady());
  ModalBasis rates;
  rates.eigenvaluesRad2PerS2 = Eigen::Vector2d(2.5e6, 8.1e6);
  rates.frequenciesHz = rates.eigenvaluesRad2PerS2.cwiseSqrt() / (2.0 * M_PI);
  rates.residuals = Eigen::Vector2d::Zero();
  auto made = detail::withFrequencies(*base, rates);
  ASSERT_TRUE(made) << made.error().message;
  EXPECT_TRUE(base->staticCorrectionReady());
  EXPECT_TRUE(made.value()->staticCorrectionReady());
  const auto& mine = made.value()->staticCorrection();
  const auto& theirs = base->staticCorrection();
  ASSERT_TRUE(theirs) << theirs.error().message;
  ASSERT_TRUE(mine) << mine.error().message;
  const std::vector<std::pair<int32_t, double>> load = {{base->boundaryNodes.front(), 1.0}};
  Eigen::VectorXd a, b;
  double ca = 0.0, cb = 0.0;
  ASSERT_TRUE(mine.value().stressPerNewton(load, Eigen::Vector3d::UnitZ(), a, ca));
  ASSERT_TRUE(theirs.value().stressPerNewton(load, Eigen::Vector3d::UnitZ(), b, cb));
  EXPECT_GT(a.cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(a, b);
  EXPECT_EQ(ca, cb);
}

TEST(Body, ALaterVersionNeedsFrequenciesOfItsBasesSizeAndACorrectionsEigenvalues) {
  const auto base = twoModeBody(Eigen::Vector2d(1.0e6, 2.0e6));
  ASSERT_TRUE(base);
  ModalBasis rates;
  rates.eigenvaluesRad2PerS2 = Eigen::Vector3d(2.5e6, 8.1e6, 9.0e6);
  rates.frequenciesHz = rates.eigenvaluesRad2PerS2.cwiseSqrt();
  rates.residuals = Eigen::Vector3d::Zero();
  EXPECT_EQ(detail::withFrequencies(*base, rates).error().code, ErrorCode::InvalidArgument);  // three for two modes
  rates.eigenvaluesRad2PerS2 = Eigen::Vector2d(0.0, 8.1e6);
  rates.frequenciesHz = Eigen::Vector2d::Zero();
  rates.residuals = Eigen::Vector2d::Zero();
  EXPECT_EQ(detail::withFrequencies(*base, rates).error().code, ErrorCode::InvalidArgument);  // a zero-frequency mode
  const auto own = twoModeBody(Eigen::VectorXd());  // its correction is for its own frequencies
  ASSERT_TRUE(own);
  rates.eigenvaluesRad2PerS2 = Eigen::Vector2d(2.5e6, 8.1e6);
  EXPECT_EQ(detail::withFrequencies(*own, rates).error().code, ErrorCode::InvalidArgument);
}

}  // namespace
}  // namespace brittle
