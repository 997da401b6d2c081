#include "brittle/precompute/ModalIntegrators.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <utility>

#include "brittle/runtime/ModalResponse.h"

namespace brittle {
namespace {

// The spectral radius of each scheme's free-vibration map, against its closed form: what makes a
// scheme stable (≤ 1) or not, at steps up to 100 times the mode's period.
TEST(ModalResponse, EachIntegratorAmplifiesAsItsTheoryStates) {
  const double w = 2 * std::numbers::pi * 1000.0;
  for (double wh : {0.01, 0.5, 1.9, 2.1, 10.0, 600.0}) {
    SCOPED_TRACE(::testing::Message() << "wh " << wh);
    auto radius = [&](ModalIntegrator integrator, double zeta) {
      const Eigen::Matrix2d a = stepMatrix(integrator, w, zeta, wh / w).leftCols<2>();
      return a.eigenvalues().cwiseAbs().maxCoeff();
    };
    EXPECT_NEAR(radius(ModalIntegrator::ExplicitEuler, 0.0), std::sqrt(1 + wh * wh), 1e-9 * std::sqrt(1 + wh * wh));
    EXPECT_NEAR(radius(ModalIntegrator::ImplicitEuler, 0.0), 1 / std::sqrt(1 + wh * wh), 1e-12);
    // Symplectic Euler: on the unit circle up to ωh = 2, then one real root beyond −1.
    const double symplectic = radius(ModalIntegrator::SymplecticEuler, 0.0);
    if (wh <= 2.0) EXPECT_NEAR(symplectic, 1.0, 1e-9);
    else EXPECT_GT(symplectic, 1.0 + 1e-3);
    for (double zeta : {0.0, 0.01, 0.2}) EXPECT_NEAR(radius(ModalIntegrator::Exact, zeta), std::exp(-zeta * wh), 1e-9);
  }
}

// Under a half-sine pulse, each scheme converges to the exact solution at its order: error × 4 at
// twice the step for the first-order Eulers; the exact map is exact for the piecewise-linear force,
// so its error is that of the force's interpolation, second order.
TEST(ModalResponse, IntegratorsConvergeAtTheirOrder) {
  const double w = 2 * std::numbers::pi * 1000.0, zeta = 0.01, pulse = 0.6e-3, window = 3e-3;
  auto peakError = [&](ModalIntegrator integrator, int steps) {
    std::vector<double> t, f, tr, fr;
    auto force = [&](double x) { return x < pulse ? std::sin(std::numbers::pi * x / pulse) : 0.0; };
    for (int k = 0; k <= steps; ++k) t.push_back(window * k / steps), f.push_back(force(t.back()));
    const int fine = steps * 64;
    for (int k = 0; k <= fine; ++k) tr.push_back(window * k / fine), fr.push_back(force(tr.back()));
    Eigen::MatrixXd q, ref;
    EXPECT_TRUE(integrateModalResponse(Eigen::VectorXd::Constant(1, w), Eigen::VectorXd::Constant(1, zeta),
                                       Eigen::VectorXd::Ones(1), t, f, q, integrator));
    EXPECT_TRUE(integrateModalResponse(Eigen::VectorXd::Constant(1, w), Eigen::VectorXd::Constant(1, zeta),
                                       Eigen::VectorXd::Ones(1), tr, fr, ref));
    double err = 0.0;
    for (int k = 0; k <= steps; ++k) err = std::max(err, std::abs(q(k, 0) - ref(64 * k, 0)));
    return err / ref.cwiseAbs().maxCoeff();
  };
  for (auto [integrator, order] : {std::pair{ModalIntegrator::ExplicitEuler, 1}, std::pair{ModalIntegrator::SymplecticEuler, 1},
                                   std::pair{ModalIntegrator::ImplicitEuler, 1}, std::pair{ModalIntegrator::Exact, 2}}) {
    SCOPED_TRACE(modalIntegratorName(integrator));
    const double coarse = peakError(integrator, 2000), finer = peakError(integrator, 4000);
    EXPECT_NEAR(std::log2(coarse / finer), order, 0.3) << coarse << " " << finer;
  }
  EXPECT_LT(peakError(ModalIntegrator::Exact, 60), 0.02);  // 20 steps per period: 2 % at most
}

}  // namespace
}  // namespace brittle
