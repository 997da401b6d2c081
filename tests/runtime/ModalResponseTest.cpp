#include "brittle/runtime/ModalResponse.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace brittle {
namespace {

TEST(ModalResponse, ClosedFormStepEqualsTheMatrixExponential) {
  for (double zeta : {0.0, 0.001, 0.05, 0.3, 0.9}) {
    for (double wh : {0.02, 0.3, 1.0, 5.0, 40.0}) {
      SCOPED_TRACE(testing::Message() << "zeta " << zeta << " wh " << wh);
      const double w = 2.0 * std::numbers::pi * 1000.0, h = wh / w;
      const auto a = exactStepMatrix(w, zeta, h), b = exactStepMatrixByExponential(w, zeta, h);
      // Columns have different units; compare each relative to its own size.
      for (int c = 0; c < 4; ++c) EXPECT_LT((a.col(c) - b.col(c)).norm(), 1e-9 * b.col(c).norm() + 1e-300) << c;
    }
  }
}

// Constant force F on a damped oscillator from rest: q = F/ω² [1 − e^(−ζωt)(cos ω_d t + ζ/√(1−ζ²) sin ω_d t)].
double stepResponse(double w, double z, double f, double t) {
  const double wd = w * std::sqrt(1 - z * z);
  return f / (w * w) * (1 - std::exp(-z * w * t) * (std::cos(wd * t) + z / std::sqrt(1 - z * z) * std::sin(wd * t)));
}

TEST(ModalResponse, ConstantForceMatchesTheAnalyticStepResponseAtAnyStep) {
  const double w = 2 * std::numbers::pi * 500.0, z = 0.02, f = 3.0;
  for (int steps : {3, 10, 100}) {  // 3 steps over 20 periods: far beyond any explicit scheme's limit
    std::vector<double> t, force;
    for (int k = 0; k <= steps; ++k) {
      t.push_back(20.0 * 2 * std::numbers::pi / w * k / steps);
      force.push_back(f);
    }
    force[0] = f;  // the force is on from t = 0
    Eigen::MatrixXd q;
    ASSERT_TRUE(integrateModalResponse(Eigen::VectorXd::Constant(1, w), Eigen::VectorXd::Constant(1, z),
                                       Eigen::VectorXd::Constant(1, 1.0), t, force, q));
    for (int k = 0; k <= steps; ++k) EXPECT_NEAR(q(k, 0), stepResponse(w, z, f, t[static_cast<size_t>(k)]), 1e-12 * f / (w * w));
  }
}

TEST(ModalResponse, LinearRampIsExactAndOverdampedModesWork) {
  // Ramp p = s t from rest, undamped: q = s/ω² (t − sin(ωt)/ω).
  const double w = 1000.0, s = 5.0;
  std::vector<double> t = {0.0, 0.004, 0.011, 0.02}, force;
  for (double x : t) force.push_back(s * x);
  Eigen::MatrixXd q;
  ASSERT_TRUE(integrateModalResponse(Eigen::VectorXd::Constant(1, w), Eigen::VectorXd::Zero(1), Eigen::VectorXd::Ones(1), t,
                                     force, q));
  for (size_t k = 0; k < t.size(); ++k) {
    EXPECT_NEAR(q(static_cast<Eigen::Index>(k), 0), s / (w * w) * (t[k] - std::sin(w * t[k]) / w), 1e-15);
  }
  // ζ = 3 (overdamped): under a constant force it creeps to F/ω² without overshoot.
  std::vector<double> tl, fl;
  for (int k = 0; k <= 200; ++k) {
    tl.push_back(k * 1e-3);
    fl.push_back(1.0);
  }
  ASSERT_TRUE(integrateModalResponse(Eigen::VectorXd::Constant(1, w), Eigen::VectorXd::Constant(1, 3.0), Eigen::VectorXd::Ones(1),
                                     tl, fl, q));
  for (Eigen::Index k = 1; k < q.rows(); ++k) {
    EXPECT_GE(q(k, 0), q(k - 1, 0) - 1e-18);
    EXPECT_LE(q(k, 0), 1.0 / (w * w) * (1 + 1e-12));
  }
  EXPECT_NEAR(q(q.rows() - 1, 0), 1.0 / (w * w), 1e-9 / (w * w));
}

TEST(ModalResponse, FreeVibrationNeverGrowsWithHugeSteps) {
  // Impulse-like start, then free ring-down with steps of 7.3 periods: the energy never grows.
  const double w = 2 * std::numbers::pi * 2000.0;
  std::vector<double> t = {0.0, 1e-5, 2e-5}, force = {0.0, 100.0, 0.0};  // a 20 µs triangle
  for (int k = 1; k <= 50; ++k) {
    t.push_back(2e-5 + k * 7.3 * 2 * std::numbers::pi / w);
    force.push_back(0.0);
  }
  Eigen::MatrixXd q;
  ASSERT_TRUE(integrateModalResponse(Eigen::VectorXd::Constant(1, w), Eigen::VectorXd::Constant(1, 0.01), Eigen::VectorXd::Ones(1),
                                     t, force, q));
  double peak = 0.0;
  for (Eigen::Index k = 0; k < q.rows(); ++k) {
    ASSERT_TRUE(std::isfinite(q(k, 0)));
    peak = std::max(peak, std::abs(q(k, 0)));
  }
  // A pulse much shorter than the period leaves an amplitude of at most impulse/ω (unit modal mass).
  const double impulse = 100.0 * 1e-5;
  EXPECT_LE(peak, impulse / w);
  EXPECT_GT(peak, 0.0);
}

TEST(ModalResponse, TimeGridAndBadInputs) {
  const auto grid = impactTimeGrid(1e-4, 4, 1e-3, 2);
  ASSERT_EQ(grid.size(), 7u);
  EXPECT_EQ(grid.front(), 0.0);
  EXPECT_DOUBLE_EQ(grid[4], 1e-4);
  EXPECT_DOUBLE_EQ(grid.back(), 1.1e-3);
  Eigen::MatrixXd q;
  const Eigen::VectorXd one = Eigen::VectorXd::Ones(1);
  EXPECT_EQ(integrateModalResponse(-one, one, one, {0, 1}, {0, 0}, q).error().code, ErrorCode::InvalidArgument);
  EXPECT_FALSE(integrateModalResponse(one, one, one, {0, 0}, {0, 0}, q));  // time not increasing
  EXPECT_FALSE(integrateModalResponse(one, one, one, {0, 1}, {0, std::nan("")}, q));
  EXPECT_FALSE(integrateModalResponse(one, Eigen::VectorXd::Ones(2), one, {0, 1}, {0, 0}, q));
}

}  // namespace
}  // namespace brittle
