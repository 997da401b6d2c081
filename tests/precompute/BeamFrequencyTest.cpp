// Free-free beam 1 × 0.1 × 0.1 m of glass against beam theory, through the real pipeline
// (Mesh_3 → P1 or P2 FEM → ARPACK).
#include <gtest/gtest.h>

#include <cstdio>
#include <numbers>
#include <vector>

#include "brittle/runtime/FemAssembly.h"
#include "brittle/runtime/QuadraticTetMesh.h"
#include "brittle/precompute/MaterialLibrary.h"
#include "brittle/precompute/ModalAnalysis.h"
#include "brittle/precompute/TetMesher.h"
#include "brittle/testing/Fixtures.h"

namespace brittle {
namespace {

constexpr double kLength = 1.0, kSide = 0.1;

struct BeamFrequencies {
  int64_t tets = 0;
  double bending0 = 0.0, bending1 = 0.0, axial = 0.0;
};

// Share of a mode's kinetic energy along x (lumped by node): ~1 for the axial mode.
double axialShare(const Eigen::VectorXd& phi) {
  double x = 0.0, all = 0.0;
  for (Eigen::Index i = 0; i < phi.size(); ++i) {
    all += phi(i) * phi(i);
    if (i % 3 == 0) x += phi(i) * phi(i);
  }
  return x / all;
}

BeamFrequencies solveBeam(double cellSize, bool quadratic = false) {
  const Material glass = materialPreset("glass").value();
  TetMeshSettings ts;
  ts.targetTets = 0;
  ts.cellSizeM = cellSize;
  auto tets = tetrahedralize(testing::makeBoxSurface(kLength, kSide, kSide), ts);
  if (!tets.ok()) {
    ADD_FAILURE() << tets.error().message;
    return {};
  }
  const QuadraticTetMesh p2 = quadratic ? makeQuadraticTetMesh(tets.value().mesh).value() : QuadraticTetMesh{};
  const Points& nodes = quadratic ? p2.nodes : tets.value().mesh.nodes;
  auto sys = (quadratic ? assembleFem(p2, glass, {}) : assembleFem(tets.value().mesh, glass, {})).value();
  ModalSettings ms;
  ms.modeCount = 10;
  ms.shiftRad2PerS2 = defaultShift(nodes, glass);
  auto modes = computeModes(sys, nodes, ms);
  if (!modes.ok()) {
    ADD_FAILURE() << modes.error().message;
    return {};
  }
  const auto& b = modes.value().basis;
  BeamFrequencies f;
  f.tets = tets.value().mesh.tets.rows();
  f.bending0 = b.frequenciesHz(0);
  f.bending1 = b.frequenciesHz(1);
  int axial = 0;
  for (int j = 0; j < 10; ++j)
    if (axialShare(b.modes.col(j)) > axialShare(b.modes.col(axial))) axial = j;
  EXPECT_GT(axialShare(b.modes.col(axial)), 0.8);
  f.axial = b.frequenciesHz(axial);
  return f;
}

TEST(BeamFrequency, FreeFreeBeamMatchesTheoryAndConvergesUnderRefinement) {
  const Material glass = materialPreset("glass").value();
  const double e = glass.youngsModulusPa, rho = glass.densityKgPerM3;
  const double axialTheory = std::sqrt(e / rho) / (2.0 * kLength);
  const double area = kSide * kSide, inertia = std::pow(kSide, 4) / 12.0;
  const double bendingTheory =
      4.730040744862704 * 4.730040744862704 / (2.0 * std::numbers::pi * kLength * kLength) * std::sqrt(e * inertia / (rho * area));

  // P1 tets are too stiff, so frequencies converge from above: under refinement they must fall,
  // by shrinking steps. (Against Euler–Bernoulli itself the error need not fall monotonically:
  // at L/h = 10 shear and rotary inertia put the exact 3D value a few per cent below it, so the
  // FE value crosses the EB line on its way down.)
  std::vector<BeamFrequencies> runs;
  for (double h : {0.04, 0.028, 0.02, 0.014}) {
    const BeamFrequencies f = solveBeam(h);
    const double bending = 0.5 * (f.bending0 + f.bending1);
    std::printf("h %.3f m: %ld tets, bending %.1f/%.1f Hz (Euler-Bernoulli %.1f, %+.2f%%), axial %.2f Hz (theory %.2f, %+.3f%%)\n",
                h, static_cast<long>(f.tets), f.bending0, f.bending1, bendingTheory, 100 * (bending / bendingTheory - 1.0), f.axial,
                axialTheory, 100 * (f.axial / axialTheory - 1.0));
    // The square section makes the two bending modes a degenerate pair.
    EXPECT_NEAR(f.bending0 / f.bending1, 1.0, 0.02);
    runs.push_back(f);
  }
  auto bendingOf = [](const BeamFrequencies& f) { return 0.5 * (f.bending0 + f.bending1); };
  for (size_t i = 1; i < runs.size(); ++i) {
    EXPECT_LT(bendingOf(runs[i]), bendingOf(runs[i - 1])) << "bending must converge from above";
    EXPECT_LT(runs[i].axial, runs[i - 1].axial + 1e-9) << "axial must converge from above";
    if (i >= 2) {
      EXPECT_LT(bendingOf(runs[i - 1]) - bendingOf(runs[i]), bendingOf(runs[i - 2]) - bendingOf(runs[i - 1]))
          << "refinement steps must shrink";
    }
  }
  EXPECT_NEAR(runs.back().axial / axialTheory, 1.0, 0.02);
  EXPECT_NEAR(bendingOf(runs.back()) / bendingTheory, 1.0, 0.05);
}

// The first bending pair converges to 526.0 Hz (issue 17: CalculiX C3D10, converged; P1 at 16k
// tets reads 542.3 Hz, +3.1 %). brittle's own P2 (an upper bound on every mesh), from
//   brittle_validation_tests --gtest_also_run_disabled_tests --gtest_filter=BeamFrequency.DISABLED_*
// h 0.05 m, 573 tets: 526.28 Hz; 1 502 tets 526.18; 3 342 tets 526.149; 9 211 tets 526.137;
// 23 794 tets 526.134 Hz (axial 2644.874 Hz throughout). So the limit is 526.13 Hz or just below,
// 0.03 % above the 526.0 used here.
constexpr double kBeamBendingHz = 526.0;

TEST(BeamFrequency, P2BendingPairIsWithinOnePercentAtAFewHundredTets) {
  const BeamFrequencies f = solveBeam(0.05, true);
  const double bending = 0.5 * (f.bending0 + f.bending1);
  std::printf("P2, %ld tets: bending %.2f/%.2f Hz (%+.3f%% against %.1f Hz), axial %.2f Hz\n", static_cast<long>(f.tets), f.bending0,
              f.bending1, 100.0 * (bending / kBeamBendingHz - 1.0), kBeamBendingHz, f.axial);
  EXPECT_LE(f.tets, 2000);  // the issue: 2k C3D10 elements come within 0.01 %
  EXPECT_NEAR(bending / kBeamBendingHz, 1.0, 0.01);
}

// Not run by default: P2 under refinement, for the reference above.
TEST(BeamFrequency, DISABLED_P2Converged) {
  for (double h : {0.05, 0.035, 0.025, 0.0175, 0.0125}) {
    const BeamFrequencies f = solveBeam(h, true);
    std::printf("P2, h %.4f m, %ld tets: bending %.3f/%.3f Hz, axial %.3f Hz\n", h, static_cast<long>(f.tets), f.bending0, f.bending1, f.axial);
    std::fflush(stdout);
  }
}

}  // namespace
}  // namespace brittle
