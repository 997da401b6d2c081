// ModalAnalysis.h — the lowest r non-rigid vibration modes of a free body, K φ = λ M φ.
//
// ARPACK (dsaupd/dseupd) in shift-invert mode 3 with a negative shift σ: the operator is
// (K − σM)⁻¹M, which is well defined for a free body (K is singular, K − σM is positive definite)
// and maps the lowest eigenvalues to the largest. The six rigid modes come out with the elastic
// ones (eigenvalue zero at the scale of |σ|), are checked to span the analytic rigid-body space,
// then excluded.
// (K − σM) is factorised once, by CHOLMOD's supernodal Cholesky (default; measured 3–6× faster
// than Eigen's SimplicialLDLT on these matrices, see docs/results/bake-cost.md) or by Eigen.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "brittle/database/Material.h"
#include "brittle/database/ObjectAsset.h"
#include "brittle/core/Result.h"
#include "brittle/runtime/FemAssembly.h"
#include "brittle/precompute/Progress.h"

namespace brittle {

enum class Factorization { Cholmod, EigenLdlt };

/// "cholmod" or "eigen-ldlt".
std::string factorizationName(Factorization f);

struct ModalSettings {
  int modeCount = 40;                ///< r, number of elastic modes returned (README: why 40)
  double shiftRad2PerS2 = 0.0;       ///< σ < 0, required by computeModes (see defaultShift())
  Factorization factorization = Factorization::Cholmod;
  int maxIterations = 500;           ///< ARPACK restarts (iparam[2])
  int lanczosVectors = 0;            ///< ncv; 0 means max(2·nev + 1, nev + 20)
  /// ARPACK relative tolerance on the Ritz values; 0 means machine precision. 1e-12 gives
  /// residuals ~1e-9 in about half the solves of machine precision (see docs/results/bake-cost.md); a basis whose
  /// residual still exceeds 1e-8 is solved again at machine precision.
  double tolerance = 1e-12;
  int retries = 2;                   ///< on non-convergence, retry with 2× ncv and 2× iterations
  uint64_t seed = 1;                 ///< seeds the starting vector
};

/// σ = −10⁻³ (c/L)², c = √(E/ρ), L = bounding-box diagonal: well below the first elastic
/// eigenvalue of any compact body, so rigid and elastic modes separate cleanly.
double defaultShift(const Points& nodes, const Material& material);

struct ModalSolveStats {
  double factorizationS = 0.0;  ///< one factorisation of K − σM
  double iterationS = 0.0;      ///< ARPACK iterations and eigenvector extraction
  double totalS = 0.0;          ///< whole call, including checks
  int operatorApplications = 0; ///< solves with K − σM
  int restarts = 0;
  int lanczosVectors = 0;
  double shiftRad2PerS2 = 0.0;
  int rigidModes = 0;
  std::string solver;           ///< "arpack+cholmod", "dense", ...
};

struct ModalResult {
  ModalBasis basis;
  ModalSolveStats stats;
};

/// Factorisation of K − σM; solve() applies (K − σM)⁻¹. Shared by ARPACK and the benchmarks.
class ShiftInvertFactor {
 public:
  virtual ~ShiftInvertFactor() = default;
  /// Error: FactorizationFailed (K − σM not positive definite: σ ≥ 0 or a broken mesh).
  static Result<std::unique_ptr<ShiftInvertFactor>> create(const SparseMatrixd& k, const SparseMatrixd& m,
                                                          double shift, Factorization kind);
  virtual void solve(const double* rhs, double* x) const = 0;
};

/// Lowest settings.modeCount elastic modes by ARPACK. Modes are mass-normalised, sorted by
/// ascending frequency, sign-fixed (positive projection on the fixed vector w_i = sin(0.7549 (i+1)))
/// and checked.
/// Errors: InvalidArgument (r < 1 or r + 6 ≥ 3N), FactorizationFailed, EigenNotConverged (says
/// how many converged and which ncv/iteration limits were tried), RigidModeMismatch (not exactly
/// six rigid modes: a disconnected or constrained mesh), Cancelled.
Result<ModalResult> computeModes(const FemSystem& system, const Points& nodes, const ModalSettings& settings,
                                 ProgressSink* progress = nullptr);

/// Same contract with a dense generalised eigensolver (Eigen). O(n³): for checks and small meshes.
Result<ModalResult> computeModesDense(const FemSystem& system, const Points& nodes, const ModalSettings& settings);

}  // namespace brittle
