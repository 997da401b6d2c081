#include "brittle/precompute/ModalAnalysis.h"

#include <gtest/gtest.h>

#include "brittle/precompute/MaterialLibrary.h"
#include "brittle/testing/Fixtures.h"

namespace brittle {
namespace {

struct Case {
  TetMesh mesh;
  FemSystem sys;
  ModalSettings settings;
};

Case smallBar(int modes, bool lumped = false) {
  Case c;
  c.mesh = testing::makeBoxTetMesh(0.4, 0.1, 0.06, 8, 2, 2);
  const Material glass = materialPreset("glass").value();
  c.sys = assembleFem(c.mesh, glass, FemSettings{lumped}).value();
  c.settings.modeCount = modes;
  c.settings.shiftRad2PerS2 = defaultShift(c.mesh.nodes, glass);
  return c;
}

void expectCheckedBasis(const ModalResult& r, int modes) {
  const auto& b = r.basis;
  ASSERT_EQ(b.frequenciesHz.size(), modes);
  EXPECT_EQ(r.stats.rigidModes, 6);
  EXPECT_LE(b.residuals.maxCoeff(), 1e-8);
  EXPECT_LE(b.orthonormalityError, 1e-8);
  for (Eigen::Index i = 0; i < modes; ++i) {
    EXPECT_GT(b.frequenciesHz(i), 1.0) << "a rigid mode was returned";
    if (i > 0) {
      EXPECT_GE(b.frequenciesHz(i), b.frequenciesHz(i - 1));
    }
  }
}

TEST(ModalAnalysis, ArpackMatchesDenseSolver) {
  Case c = smallBar(12);
  auto arpack = computeModes(c.sys, c.mesh.nodes, c.settings);
  auto dense = computeModesDense(c.sys, c.mesh.nodes, c.settings);
  ASSERT_TRUE(arpack.ok()) << arpack.error().message;
  ASSERT_TRUE(dense.ok()) << dense.error().message;
  expectCheckedBasis(arpack.value(), 12);
  expectCheckedBasis(dense.value(), 12);
  const Eigen::VectorXd& la = arpack.value().basis.eigenvaluesRad2PerS2;
  const Eigen::VectorXd& ld = dense.value().basis.eigenvaluesRad2PerS2;
  EXPECT_LE(((la - ld).cwiseAbs().array() / ld.array()).maxCoeff(), 1e-8);
  // Same subspace: for simple eigenvalues the modes agree up to the fixed sign.
  const auto& sys = c.sys;
  for (int j = 0; j < 12; ++j) {
    const bool simple = (j == 0 || la(j) - la(j - 1) > 1e-6 * la(j)) && (j == 11 || la(j + 1) - la(j) > 1e-6 * la(j));
    if (!simple) continue;
    const double overlap = arpack.value().basis.modes.col(j).dot(sys.mass * dense.value().basis.modes.col(j));
    EXPECT_NEAR(overlap, 1.0, 1e-8) << "mode " << j;
  }
}

TEST(ModalAnalysis, CholmodAndEigenFactorizationsAgree) {
  Case c = smallBar(8);
  auto chol = computeModes(c.sys, c.mesh.nodes, c.settings);
  c.settings.factorization = Factorization::EigenLdlt;
  auto ldlt = computeModes(c.sys, c.mesh.nodes, c.settings);
  ASSERT_TRUE(chol.ok() && ldlt.ok());
  expectCheckedBasis(ldlt.value(), 8);
  EXPECT_TRUE(chol.value().basis.eigenvaluesRad2PerS2.isApprox(ldlt.value().basis.eigenvaluesRad2PerS2, 1e-10));
}

TEST(ModalAnalysis, LumpedMassIsCheckedToo) {
  Case c = smallBar(6, true);
  auto r = computeModes(c.sys, c.mesh.nodes, c.settings);
  ASSERT_TRUE(r.ok()) << r.error().message;
  expectCheckedBasis(r.value(), 6);
}

TEST(ModalAnalysis, DeterministicForAFixedSeed) {
  Case c = smallBar(6);
  auto a = computeModes(c.sys, c.mesh.nodes, c.settings);
  auto b = computeModes(c.sys, c.mesh.nodes, c.settings);
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_EQ(a.value().basis.modes, b.value().basis.modes);
  EXPECT_EQ(a.value().basis.eigenvaluesRad2PerS2, b.value().basis.eigenvaluesRad2PerS2);
}

TEST(ModalAnalysis, LooseToleranceIsRefinedToMachinePrecision) {
  Case c = smallBar(8);
  c.settings.tolerance = 0.9;  // far too loose: Ritz vectors are not yet eigenvectors
  c.settings.lanczosVectors = 15;  // nev + 1: the smallest Krylov space, so little comes for free
  auto r = computeModes(c.sys, c.mesh.nodes, c.settings);
  ASSERT_TRUE(r.ok()) << r.error().message;
  expectCheckedBasis(r.value(), 8);
  EXPECT_NE(r.value().stats.solver.find("refined"), std::string::npos) << r.value().stats.solver;
}

TEST(ModalAnalysis, TwoSeparateBodiesHaveTwelveRigidModes) {
  auto a = testing::makeBoxTetMesh(0.2, 0.1, 0.1, 2, 1, 1);
  TetMesh two;
  two.nodes.resize(2 * a.nodes.rows(), 3);
  two.nodes << a.nodes, (a.nodes.rowwise() + Eigen::RowVector3d(1, 0, 0));
  two.tets.resize(2 * a.tets.rows(), 4);
  two.tets << a.tets, (a.tets.array() + static_cast<int32_t>(a.nodes.rows())).matrix();
  const Material glass = materialPreset("glass").value();
  auto sys = assembleFem(two, glass, {}).value();
  ModalSettings s;
  s.modeCount = 8;
  s.shiftRad2PerS2 = defaultShift(two.nodes, glass);
  auto r = computeModes(sys, two.nodes, s);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().code, ErrorCode::RigidModeMismatch);
}

TEST(ModalAnalysis, TypedErrors) {
  Case c = smallBar(6);
  ModalSettings s = c.settings;
  s.modeCount = 0;
  EXPECT_EQ(computeModes(c.sys, c.mesh.nodes, s).error().code, ErrorCode::InvalidArgument);
  s.modeCount = static_cast<int>(c.sys.stiffness.rows());
  EXPECT_EQ(computeModes(c.sys, c.mesh.nodes, s).error().code, ErrorCode::InvalidArgument);
  s = c.settings;
  s.shiftRad2PerS2 = 0.0;
  EXPECT_EQ(computeModes(c.sys, c.mesh.nodes, s).error().code, ErrorCode::InvalidArgument);
  EXPECT_EQ(ShiftInvertFactor::create(c.sys.stiffness, c.sys.mass, 1.0, Factorization::Cholmod).error().code,
            ErrorCode::FactorizationFailed);
  // An indefinite matrix (−K − σM has negative eigenvalues) must fail in both factorisations.
  const SparseMatrixd negK = -c.sys.stiffness;
  for (Factorization f : {Factorization::Cholmod, Factorization::EigenLdlt}) {
    auto bad = ShiftInvertFactor::create(negK, c.sys.mass, c.settings.shiftRad2PerS2, f);
    ASSERT_FALSE(bad.ok()) << factorizationName(f);
    EXPECT_EQ(bad.error().code, ErrorCode::FactorizationFailed) << factorizationName(f);
  }
  // Starved of iterations and Lanczos vectors, ARPACK cannot converge: a typed error that says
  // what was tried, never a silent bad basis.
  s = c.settings;
  s.modeCount = 20;
  s.maxIterations = 1;
  s.lanczosVectors = 27;
  s.tolerance = 0.0;
  s.retries = 0;
  auto starved = computeModes(c.sys, c.mesh.nodes, s);
  ASSERT_FALSE(starved.ok());
  EXPECT_EQ(starved.error().code, ErrorCode::EigenNotConverged);
  EXPECT_NE(starved.error().message.find("tried ncv=27 maxit=1"), std::string::npos) << starved.error().message;
}

}  // namespace
}  // namespace brittle
