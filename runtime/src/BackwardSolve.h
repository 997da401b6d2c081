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
// Each x_j is computed by one thread, summing its column in storage order, so the result is the
// same bits on any number of threads and equal to the serial solve in descending column order.
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

  /// x ← L⁻ᵀ x for the unit lower triangular L whose strict lower part is `lower`. The parts run
  /// in parallel (oneTBB) where the caller's arena has threads, else one after the other.
  void solveInPlace(const Eigen::SparseMatrix<double>& lower, Eigen::VectorXd& x) const;

  /// The share of L's non-zeros solved in parallel (0 for one part); what the plan is worth.
  double parallelShare() const { return mParallelShare; }
  /// The critical path's share of L's non-zeros: the top plus the heaviest part (1 for one part).
  double criticalShare() const { return mCriticalShare; }
  int parts() const { return static_cast<int>(mPartNodes.size()); }

 private:
  std::vector<int32_t> mTopNodes;                // solved first, descending
  std::vector<std::vector<int32_t>> mPartNodes;  // per part, descending
  double mParallelShare = 0.0;
  double mCriticalShare = 1.0;
};

}  // namespace brittle::detail
