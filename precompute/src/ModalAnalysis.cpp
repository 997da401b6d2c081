#include "brittle/precompute/ModalAnalysis.h"

#include <arpack/arpack.hpp>

#include <Eigen/CholmodSupport>
#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <array>
#include <cmath>
#include <mutex>
#include <numbers>
#include <numeric>
#include <random>
#include <vector>

#include "brittle/core/Timing.h"

namespace brittle {
namespace {

// Largest accepted relative residual ‖Kφ − λMφ‖/‖Kφ‖ before a solve is redone at machine precision.
constexpr double kMaxResidual = 1e-8;

class CholmodFactor final : public ShiftInvertFactor {
 public:
  bool factor(const SparseMatrixd& a) {
    mSolver.compute(a);
    return mSolver.info() == Eigen::Success;
  }
  void solve(const double* rhs, double* x) const override {
    Eigen::Map<const Eigen::VectorXd> b(rhs, mSolver.rows());
    Eigen::Map<Eigen::VectorXd>(x, mSolver.rows()) = mSolver.solve(b);
  }

 private:
  Eigen::CholmodSupernodalLLT<SparseMatrixd, Eigen::Lower> mSolver;
};

class EigenLdltFactor final : public ShiftInvertFactor {
 public:
  bool factor(const SparseMatrixd& a) {
    mSolver.compute(a);
    // LDLᵀ succeeds on indefinite matrices too; the shifted matrix must be positive definite.
    return mSolver.info() == Eigen::Success && (mSolver.vectorD().array() > 0.0).all();
  }
  void solve(const double* rhs, double* x) const override {
    Eigen::Map<const Eigen::VectorXd> b(rhs, mSolver.rows());
    Eigen::Map<Eigen::VectorXd>(x, mSolver.rows()) = mSolver.solve(b);
  }

 private:
  Eigen::SimplicialLDLT<SparseMatrixd, Eigen::Lower, Eigen::AMDOrdering<int>> mSolver;
};

// A fixed, generic vector: a mode's sign is chosen so that its projection on it is positive.
// (The largest component is a poor reference: symmetric meshes make ± ties.)
Eigen::VectorXd signReference(Eigen::Index n) {
  Eigen::VectorXd w(n);
  for (Eigen::Index i = 0; i < n; ++i) w(i) = std::sin(0.7548776662466927 * static_cast<double>(i + 1));
  return w;
}

// Candidate eigenpairs (any order) → checked basis: sort, M-normalise, split off the rigid modes,
// keep r, fix signs, compute residuals. A mode is rigid when its eigenvalue is zero at the scale
// of the problem (|λ| ≤ 1e-3·zeroScale, zeroScale = |σ|); there must be exactly six, and together
// they must span the analytic rigid-body space. Two loose pieces give twelve zero modes, which an
// eigensolver returns as an arbitrary basis of that space, so counting by projection alone
// could be fooled; counting by eigenvalue cannot.
Result<ModalBasis> finishBasis(const FemSystem& sys, const Points& nodes, Eigen::VectorXd lambda,
                               Eigen::MatrixXd vectors, int r, double zeroScale, int* rigidCount) {
  std::vector<int> order(static_cast<size_t>(lambda.size()));
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return lambda(a) < lambda(b); });
  const Eigen::MatrixXd rigid = rigidBodyModes(nodes, sys.mass);
  const Eigen::MatrixXd mRigid = sys.mass * rigid;

  std::vector<int> elastic;
  int rigidFound = 0;
  double rigidSpan = 0.0;
  for (int idx : order) {
    Eigen::VectorXd phi = vectors.col(idx);
    phi /= std::sqrt(phi.dot(sys.mass * phi));
    vectors.col(idx) = phi;
    const double rigidFraction = (mRigid.transpose() * phi).squaredNorm();
    if (std::abs(lambda(idx)) <= 1e-3 * zeroScale) {
      ++rigidFound;
      rigidSpan += rigidFraction;
    } else if (static_cast<int>(elastic.size()) < r) {
      elastic.push_back(idx);
    }
  }
  *rigidCount = rigidFound;
  if (rigidFound != 6 || rigidSpan < 6.0 - 1e-6) {
    return makeError(ErrorCode::RigidModeMismatch,
                     "found " + std::to_string(rigidFound) + " zero-frequency modes among the " +
                         std::to_string(lambda.size()) + " lowest (spanning " + std::to_string(rigidSpan) +
                         " of the 6 rigid motions), expected exactly the 6 rigid-body modes (is the mesh one "
                         "connected, free body?)");
  }
  if (static_cast<int>(elastic.size()) < r) {
    return makeError(ErrorCode::EigenNotConverged, "only " + std::to_string(elastic.size()) + " of " +
                                                       std::to_string(r) + " elastic modes were found");
  }

  ModalBasis basis;
  const Eigen::Index n = vectors.rows();
  basis.modes.resize(n, r);
  basis.eigenvaluesRad2PerS2.resize(r);
  basis.frequenciesHz.resize(r);
  basis.residuals.resize(r);
  for (int j = 0; j < r; ++j) {
    Eigen::VectorXd phi = vectors.col(elastic[static_cast<size_t>(j)]);
    if (phi.dot(signReference(n)) < 0.0) phi = -phi;
    const double l = lambda(elastic[static_cast<size_t>(j)]);
    if (!(l > 0.0)) {
      return makeError(ErrorCode::EigenNotConverged, "elastic mode " + std::to_string(j) + " has eigenvalue " +
                                                         std::to_string(l) + " <= 0");
    }
    const Eigen::VectorXd kphi = sys.stiffness * phi;
    basis.residuals(j) = (kphi - l * (sys.mass * phi)).norm() / kphi.norm();
    basis.eigenvaluesRad2PerS2(j) = l;
    basis.frequenciesHz(j) = std::sqrt(l) / (2.0 * std::numbers::pi);
    basis.modes.col(j) = phi;
  }
  const Eigen::MatrixXd gram = basis.modes.transpose() * (sys.mass * basis.modes);
  basis.orthonormalityError = (gram - Eigen::MatrixXd::Identity(r, r)).cwiseAbs().maxCoeff();
  return basis;
}

Status checkModeCount(const FemSystem& sys, int r) {
  const auto n = sys.stiffness.rows();
  if (r < 1 || r + 6 >= n) {
    return makeError(ErrorCode::InvalidArgument, "cannot compute " + std::to_string(r) + " modes of a system with " +
                                                     std::to_string(n) + " degrees of freedom");
  }
  return Ok{};
}

}  // namespace

std::string factorizationName(Factorization f) { return f == Factorization::Cholmod ? "cholmod" : "eigen-ldlt"; }

double defaultShift(const Points& nodes, const Material& material) {
  const double length = (nodes.colwise().maxCoeff() - nodes.colwise().minCoeff()).norm();
  const double waveSpeed = std::sqrt(material.youngsModulusPa / material.densityKgPerM3);
  return -1e-3 * (waveSpeed / length) * (waveSpeed / length);
}

Result<std::unique_ptr<ShiftInvertFactor>> ShiftInvertFactor::create(const SparseMatrixd& k, const SparseMatrixd& m,
                                                                     double shift, Factorization kind) {
  if (!(shift < 0.0)) {
    return makeError(ErrorCode::FactorizationFailed, "shift must be negative for a free body, got " + std::to_string(shift));
  }
  const SparseMatrixd a = k - shift * m;
  if (kind == Factorization::Cholmod) {
    auto f = std::make_unique<CholmodFactor>();
    if (!f->factor(a)) {
      return makeError(ErrorCode::FactorizationFailed, "CHOLMOD: K - sigma*M is not positive definite (sigma = " +
                                                           std::to_string(shift) + ")");
    }
    return std::unique_ptr<ShiftInvertFactor>(std::move(f));
  }
  auto f = std::make_unique<EigenLdltFactor>();
  if (!f->factor(a)) {
    return makeError(ErrorCode::FactorizationFailed, "Eigen LDLT: K - sigma*M is not positive definite (sigma = " +
                                                         std::to_string(shift) + ")");
  }
  return std::unique_ptr<ShiftInvertFactor>(std::move(f));
}

Result<ModalResult> computeModes(const FemSystem& sys, const Points& nodes, const ModalSettings& s,
                                 ProgressSink* progress) {
  const auto start = SteadyClock::now();
  if (Status ok = checkModeCount(sys, s.modeCount); !ok) return ok.error();
  if (!(s.shiftRad2PerS2 < 0.0)) {
    return makeError(ErrorCode::InvalidArgument, "the ARPACK shift must be negative (set it from defaultShift())");
  }
  ModalResult result;
  result.stats.shiftRad2PerS2 = s.shiftRad2PerS2;
  result.stats.solver = "arpack+" + factorizationName(s.factorization);

  reportProgress(progress, "modal: factorising", 0.0);
  auto factor = ShiftInvertFactor::create(sys.stiffness, sys.mass, s.shiftRad2PerS2, s.factorization);
  if (!factor) return factor.error();
  result.stats.factorizationS = secondsSince(start);

  const a_int n = static_cast<a_int>(sys.stiffness.rows());
  const a_int nev = s.modeCount + 6;  // the six rigid modes come first
  a_int ncv = s.lanczosVectors > 0 ? s.lanczosVectors : std::max(2 * nev + 1, nev + 20);
  a_int maxIterations = s.maxIterations;
  std::string tried;

  // Deterministic starting vector in [−1, 1) from the seed (the bit pattern, not a
  // distribution, so it is the same on every standard library).
  std::mt19937_64 rng(s.seed);
  Eigen::VectorXd start0(n);
  for (a_int i = 0; i < n; ++i) start0(i) = static_cast<double>(rng() >> 11) * 0x1.0p-52 - 1.0;

  // ARPACK keeps its reverse-communication state in Fortran SAVE variables, so two solves must
  // never interleave: parallel bakes (the fragment database) serialise here and run their
  // meshing, assembly and factorisation concurrently.
  // Recursive: the machine-precision fallback calls computeModes again on the same thread.
  static std::recursive_mutex arpackMutex;
  const std::lock_guard<std::recursive_mutex> arpackLock(arpackMutex);
  const auto iterStart = SteadyClock::now();
  Eigen::VectorXd tmp(n);
  for (int attempt = 0; attempt <= s.retries; ++attempt) {
    ncv = std::min(ncv, n);
    const a_int lworkl = ncv * (ncv + 8);
    std::vector<double> resid(start0.data(), start0.data() + n), v(static_cast<size_t>(n) * ncv),
        workd(3 * static_cast<size_t>(n)), workl(static_cast<size_t>(lworkl));
    std::array<a_int, 11> iparam{};
    std::array<a_int, 14> ipntr{};
    iparam[0] = 1;  // exact shifts
    iparam[2] = maxIterations;
    iparam[6] = 3;  // shift-invert mode
    a_int ido = 0, info = 1;  // info = 1: use resid as the starting vector
    while (true) {
      arpack::saupd(ido, arpack::bmat::generalized, n, arpack::which::largest_magnitude, nev, s.tolerance,
                    resid.data(), ncv, v.data(), n, iparam.data(), ipntr.data(), workd.data(), workl.data(), lworkl,
                    info);
      if (ido == 99) break;
      double* x = &workd[static_cast<size_t>(ipntr[0] - 1)];
      double* y = &workd[static_cast<size_t>(ipntr[1] - 1)];
      Eigen::Map<Eigen::VectorXd> xv(x, n), yv(y, n);
      if (ido == -1) {
        tmp = sys.mass * xv;
        (*factor.value()).solve(tmp.data(), y);
        ++result.stats.operatorApplications;
      } else if (ido == 1) {
        (*factor.value()).solve(&workd[static_cast<size_t>(ipntr[2] - 1)], y);
        ++result.stats.operatorApplications;
      } else if (ido == 2) {
        yv = sys.mass * xv;
      } else {
        break;
      }
      if (isInterrupted(progress)) return makeError(ErrorCode::Cancelled, "modal analysis cancelled");
      if (result.stats.operatorApplications % 16 == 0) {
        reportProgress(progress, "modal: ARPACK iterations",
                       std::min(0.99, static_cast<double>(result.stats.operatorApplications) / (4.0 * ncv)));
      }
    }
    result.stats.restarts += iparam[2];
    tried += (tried.empty() ? "" : "; ") + std::string("ncv=") + std::to_string(ncv) +
             " maxit=" + std::to_string(maxIterations) + " (info=" + std::to_string(info) +
             ", converged " + std::to_string(iparam[4]) + "/" + std::to_string(nev) + ")";
    if (info < 0) {
      return makeError(ErrorCode::EigenNotConverged, "ARPACK dsaupd failed with info=" + std::to_string(info) +
                                                         "; tried " + tried);
    }
    if (info == 0 && iparam[4] >= nev) {
      std::vector<a_int> select(static_cast<size_t>(ncv));
      Eigen::VectorXd d(nev);
      Eigen::MatrixXd z(n, nev);
      a_int infoEupd = 0;
      arpack::seupd(1, arpack::howmny::ritz_vectors, select.data(), d.data(), z.data(), n, s.shiftRad2PerS2,
                    arpack::bmat::generalized, n, arpack::which::largest_magnitude, nev, s.tolerance, resid.data(),
                    ncv, v.data(), n, iparam.data(), ipntr.data(), workd.data(), workl.data(), lworkl, infoEupd);
      if (infoEupd != 0) {
        return makeError(ErrorCode::EigenNotConverged, "ARPACK dseupd failed with info=" + std::to_string(infoEupd) +
                                                           "; tried " + tried);
      }
      result.stats.iterationS = secondsSince(iterStart);
      result.stats.lanczosVectors = ncv;
      auto basis = finishBasis(sys, nodes, d, z, s.modeCount, -s.shiftRad2PerS2, &result.stats.rigidModes);
      if (s.tolerance > 0.0 && (!basis || basis.value().residuals.maxCoeff() > kMaxResidual)) {
        // The Ritz tolerance was too loose for this problem (residuals too large, or rigid and
        // elastic modes not yet separated): solve again at machine precision.
        ModalSettings strict = s;
        strict.tolerance = 0.0;
        auto refined = computeModes(sys, nodes, strict, progress);
        if (refined) refined.value().stats.solver += " (refined at machine precision)";
        return refined;
      }
      if (!basis) return basis.error();
      result.basis = std::move(basis).value();
      result.stats.totalS = secondsSince(start);
      reportProgress(progress, "modal: ARPACK iterations", 1.0);
      return result;
    }
    ncv = std::min<a_int>(2 * ncv, n);
    maxIterations *= 2;
  }
  return makeError(ErrorCode::EigenNotConverged, "ARPACK did not converge for " + std::to_string(nev) +
                                                     " eigenpairs (6 rigid + " + std::to_string(s.modeCount) +
                                                     " elastic), shift " + std::to_string(s.shiftRad2PerS2) +
                                                     "; tried " + tried);
}

Result<ModalResult> computeModesDense(const FemSystem& sys, const Points& nodes, const ModalSettings& s) {
  const auto start = SteadyClock::now();
  if (Status ok = checkModeCount(sys, s.modeCount); !ok) return ok.error();
  const Eigen::MatrixXd k(sys.stiffness), m(sys.mass);
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> solver(k, m);
  if (solver.info() != Eigen::Success) return makeError(ErrorCode::EigenNotConverged, "dense eigensolver failed");
  const int count = s.modeCount + 6;
  ModalResult result;
  result.stats.solver = "dense";
  // Without a shift, "zero" is judged against the largest eigenvalue (rounding level ~1e-16 of it).
  const double zeroScale = s.shiftRad2PerS2 < 0.0 ? -s.shiftRad2PerS2 : 1e-9 * solver.eigenvalues().cwiseAbs().maxCoeff();
  auto basis = finishBasis(sys, nodes, solver.eigenvalues().head(count), solver.eigenvectors().leftCols(count),
                           s.modeCount, zeroScale, &result.stats.rigidModes);
  if (!basis) return basis.error();
  result.basis = std::move(basis).value();
  result.stats.totalS = result.stats.iterationS = secondsSince(start);
  return result;
}

}  // namespace brittle
