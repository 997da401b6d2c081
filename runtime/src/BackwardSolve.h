// BackwardSolve.h — the backward solve Lᵀx = y of a sparse LDLᵀ factor, shared by threads along
// the elimination tree. Private to the runtime (StaticCorrection.cpp).
//
// The static correction solves (K + μM)u = f on every impact. Its forward solve is as sparse as
// the load, so the backward solve over every non-zero of L is most of its cost (the P2 plate:
// 8.65M non-zeros, ~20 ms, bound by memory bandwidth). Column j of L holds rows that are all
// ancestors of j in the elimination tree (parent(j) = the first row below the diagonal), so
// x_j = y_j − Σ_i L_ij x_i needs only its ancestors' values: subtrees that do not contain one
// another can be solved at once, once the nodes above them are. The plan takes the heaviest
// subtrees apart from the root down until none holds more than a limit, deals them out to the
// parts (largest first, to the lightest part), and leaves the nodes taken apart (the top of the
// tree) to be solved first, alone. Of a few limits it keeps the one whose top plus heaviest part
// (the critical path, in non-zeros) is least.
//
// The columns are solved a supernode at a time. A (fundamental) supernode is a chain of columns
// f..g−1 where each column's pattern is the next column's plus that column (the P2 plate's 47.7k
// columns form 6.8k, 7 wide on average), so that all of them end in the same rows R (those of
// column g−1). Per supernode, x over R is gathered once into a contiguous buffer, and each column's
// sum over R is a dense dot product with it (two columns at a time, four running sums each), the
// rest of the column (rows in the supernode) a short sum of its own. Eigen's per-entry indexed
// loads made the solve ~2.5× slower than reading L; the plate's backward solve went from 18–25 ms to
// 12–14 ms on one core. The next supernode's values are prefetched: the solve walks L backwards,
// which the hardware prefetcher follows badly.
//
// Each x_j is computed by one thread, in a fixed order that depends on L alone (its global
// supernode), so the result is the same bits on any number of threads. It is not the order of
// Eigen's serial solve (the tests compare within rounding).
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <cstdint>
#include <vector>

namespace brittle::detail {

class BackwardSolvePlan {
 public:
  /// A plan for `parts` threads over the strictly lower, column-major factor `lower` (rows
  /// ascending in each column, as Eigen's SimplicialLDLT stores L).
  static BackwardSolvePlan make(const Eigen::SparseMatrix<double>& lower, int parts);

  /// A run of columns [first, end) inside one supernode whose last column is `last` (end ≤ last + 1).
  struct Run {
    int32_t first, end, last;
  };

  /// Per-part buffers of solveInPlace, sized on first use: one per caller at a time.
  using Scratch = std::vector<std::vector<double>>;

  /// x ← L⁻ᵀ x for the unit lower triangular L whose strict lower part is `lower`. The parts run
  /// in parallel (oneTBB) where the caller's arena has threads, else one after the other.
  void solveInPlace(const Eigen::SparseMatrix<double>& lower, Eigen::VectorXd& x, Scratch& scratch) const;
  void solveInPlace(const Eigen::SparseMatrix<double>& lower, Eigen::VectorXd& x) const;

  /// The share of L's non-zeros solved in parallel (0 for one part); what the plan is worth.
  double parallelShare() const { return mParallelShare; }
  /// The critical path's share of L's non-zeros: the top plus the heaviest part (1 for one part).
  double criticalShare() const { return mCriticalShare; }
  int parts() const { return static_cast<int>(mPartRuns.size()); }

 private:
  std::vector<Run> mTopRuns;                // solved first, descending
  std::vector<std::vector<Run>> mPartRuns;  // per part, descending
  size_t mMaxGather = 0;                    // the most rows below a supernode
  double mParallelShare = 0.0;
  double mCriticalShare = 1.0;
};

}  // namespace brittle::detail
