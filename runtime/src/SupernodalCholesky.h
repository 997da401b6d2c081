// SupernodalCholesky.h — a sparse Cholesky factor P A Pᵀ = L Lᵀ by supernodes, with Eigen's dense
// kernels on each supernode's panel. Private to the runtime: the shift-invert factor of K − σM of
// the exact path's modal analysis and the own-mesh checks (FragmentModes.cpp), and every factor of
// factorInOrder (StaticCorrection.h: objects' and entries' static corrections); the static
// correction reads it in SimplicialLDLT's form (simplicialForm).
//
// Eigen's SimplicialLDLT computes L one row at a time, an entry at a time: on a quadratic-tet
// piece's K (25k DOF, 4.7M non-zeros in L) its factorisation took 657 ms of a 1.13 s check, at
// about 1.4 GFlop/s. A supernode is a chain of columns f..l in which each column's pattern is the
// next column's plus that column, so they share the rows below them: stored as one dense,
// column-major panel (the columns' rows f..l, then the shared rows), it is factorised by a dense
// Cholesky of its top block and a triangular solve of the rest, and the update it sends to the
// columns above it is one dense product (a rank-k update), scattered into their panels.
// Measured against SimplicialLDLT on glass boxes (factorisation, one thread): P1 at 3.4k DOF 25 ms
// against 91, P2 at 8.8k 170 ms against 833, at 23k 1.35 s against 12.2 s; 16 solves 1.5–2× faster.
//
// The elimination order is given (a pack's stored one), or Eigen's AMD: of the DOF's own graph, as
// SimplicialLDLT's, so that L has its pattern, or of the nodes' graph where the DOF come in blocks
// (a node's three: a ninth of the entries to order, within a few per cent of the fill). The
// factorisation runs on one thread in a fixed order, and Eigen's kernels block by the cache sizes
// the build fixes (EIGEN_NO_CPUID, cmake/BrittleTargets.cmake): the same bits in any process and on
// any machine that runs the same build. They are not SimplicialLDLT's bits (another order of the
// same sums). The const solves share one scratch buffer: one caller at a time.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <cstdint>
#include <memory>
#include <vector>

namespace brittle::detail {

class SupernodalCholesky {
 public:
  /// Orders and factorises the symmetric matrix `a` (n by n; only its lower triangle is read, as a
  /// full matrix or alone). With `block` > 1 dividing n, the DOF come in blocks of that many (a
  /// node's x, y, z) that are ordered together. False where `a` is not square, its lower triangle
  /// not finite, or it is not positive definite (a pivot ≤ 0); the factor is then empty.
  bool compute(const Eigen::SparseMatrix<double>& a, Eigen::Index block = 1);
  /// ... in the order given: `order` (n values) lists A's rows in the order they are eliminated
  /// (Eigen's inverse permutation, as a pack stores it). False as above, or where `order` is not a
  /// permutation of 0..n−1.
  bool computeInOrder(const Eigen::SparseMatrix<double>& a, const Eigen::VectorXi& order);

  Eigen::Index rows() const { return mN; }
  /// Non-zeros of L, the panels' upper triangles left out.
  int64_t nonZeros() const { return mNonZeros; }
  Eigen::Index supernodeCount() const { return static_cast<Eigen::Index>(mFirst.size()) - 1; }

  /// x (n values) ← P x: a vector in A's order to L's.
  void permute(const double* x, double* out) const;
  /// x (n values) ← Pᵀ x: from L's order back to A's.
  void permuteBack(const double* x, double* out) const;
  /// x ← L⁻¹ x (in L's order).
  void solveL(double* x) const;
  /// x ← L⁻ᵀ x (in L's order).
  void solveLt(double* x) const;
  /// out ← Lᵀ x (in L's order).
  void multiplyLt(const double* x, double* out) const;
  /// x ← A⁻¹ x (in A's order).
  void solve(Eigen::VectorXd& x) const;
  /// The factor in SimplicialLDLT's form, P A Pᵀ = U D Uᵀ: U's strict lower part (column-major,
  /// rows ascending in each column) = L D^-½ and D = diag(L)².
  void toUnitLower(Eigen::SparseMatrix<double>& unitLower, Eigen::VectorXd& pivots) const;
  /// A's row at L's row i.
  int32_t orderAt(Eigen::Index i) const { return mPerm[static_cast<size_t>(i)]; }

 private:
  Eigen::Index mN = 0;
  int64_t mNonZeros = 0;
  std::vector<int32_t> mPerm;      // L's row i is A's row mPerm[i]
  std::vector<int32_t> mFirst;     // supernode s holds the columns [mFirst[s], mFirst[s + 1])
  std::vector<int64_t> mRowsAt;    // its rows (its own columns, then those below) at mRows[mRowsAt[s]...]
  std::vector<int32_t> mRows;
  std::vector<int64_t> mValuesAt;  // its panel, column-major, at mValues[mValuesAt[s]...]
  std::vector<double> mValues;
  mutable std::vector<double> mScratch;
};

/// The factor as Eigen's SimplicialLDLT state (the static correction's ShiftedFactor): U = L D^-½
/// and D = diag(L)² in the same order, so that solve(), matrixL(), vectorD() and the permutations
/// read it as they read Eigen's own. `factor` must hold a factorisation.
std::shared_ptr<const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>>> simplicialForm(const SupernodalCholesky& factor);

}  // namespace brittle::detail
