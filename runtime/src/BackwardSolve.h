// BackwardSolve.h — the backward solve Lᵀx = y of a sparse LDLᵀ factor, shared by threads along
// the elimination tree. Private to the runtime (StaticCorrection.cpp).
//
// The static correction solves (K + μM)u = f on every impact. Its forward solve is as sparse as
// the load, so the backward solve over every non-zero of L is most of its cost (the P2 plate:
// 8.65M non-zeros by AMD, ~20 ms serial through Eigen). Column j of L holds rows that are all
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
// sum over R is a dense dot product with it (two columns at a time, four running sums each, in two
// SSE2 registers or one AVX register, with the same bits), the rest of the column (rows in the
// supernode, whose x are contiguous) a dot product of the same kind. Eigen's per-entry indexed loads made the solve ~2.5× slower
// than reading L; the plate's backward solve went from 18–25 ms to 12–14 ms on one core.
//
// The plan keeps its own copy of L's values, laid out in the order the solve reads them (the top's
// runs, then each part's; in a run, columns descending, each in row order), and asks for the next
// run's values while it solves one. Walking Eigen's column-major L backwards, which the hardware
// prefetcher follows badly, left the solve at a third of the machine's bandwidth: the plate's
// 7.8M non-zeros took 6.7–6.9 ms on two threads, against 4.4–4.5 ms from the copy (median of 60
// solves; the SSE2 sums alone gave 5.7–6.1). The copy costs 8 bytes a non-zero (62 MB for the plate),
// or 4 in float (the static correction's default, CorrectionStorage: its solve is of the
// correction itself, so float rounding is relative to it), where AVX registers pay: the plate's
// solve 7.5–8.2 → 6.3–6.8 ms on a machine that streams 9 GB/s a core. Each run's rows below its
// supernode are copied beside, in the same order, for the gather: read from Eigen's row indices,
// they had been a quarter of the solve's samples (docs/realtime.md).
//
// Each x_j is computed by one thread, in a fixed order that depends on L alone (its global
// supernode), so the result is the same bits on any number of threads. It is not the order of
// Eigen's serial solve (the tests compare within rounding).
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <cstdint>
#include <vector>

#include "brittle/core/Simd.h"

namespace brittle::detail {

class BackwardSolvePlan {
 public:
  /// A plan for `parts` threads over the strictly lower, column-major factor `lower` (rows
  /// ascending in each column, as Eigen's SimplicialLDLT stores L), with a copy of its values:
  /// in double, or rounded to float where `floatValues` (half the bytes to read; the sums stay in
  /// double, each value widened exactly).
  static BackwardSolvePlan make(const Eigen::SparseMatrix<double>& lower, int parts, bool floatValues = false);

  /// A run of columns [first, end) inside one supernode whose last column is `last` (end ≤ last + 1).
  /// Its `rowCount` rows below the supernode (R, the rows of column `last`) start at `rowsAt` in
  /// the plan's copy of them.
  struct Run {
    int32_t first, end, last;
    int32_t rowCount = 0;
    int64_t rowsAt = 0;
  };

  /// Per-part buffers of solveInPlace, sized on first use: one per caller at a time.
  using Scratch = std::vector<std::vector<double>>;

  /// x ← L⁻ᵀ x for the unit lower triangular L whose strict lower part is `lower`, the matrix the
  /// plan was made from (its pattern; the values are the plan's copy). The parts run
  /// in parallel (oneTBB) where the caller's arena has threads, else one after the other.
  /// `lanes` picks the dot products' registers (brittle/core/Simd.h): the same bits either way.
  void solveInPlace(const Eigen::SparseMatrix<double>& lower, Eigen::VectorXd& x, Scratch& scratch,
                    Lanes lanes = widestLanes()) const;
  void solveInPlace(const Eigen::SparseMatrix<double>& lower, Eigen::VectorXd& x) const;

  /// x ← L⁻¹ x, the forward solve, on one thread: the same arithmetic in the same order as
  /// Eigen's sparse triangular solve (a column whose x is exactly zero passes nothing on, so a
  /// sparse right-hand side costs only its reach in the elimination tree), with each supernode's
  /// rows below it gathered once, in the first buffer of `scratch` (sized as solveInPlace sizes it).
  /// A plan with float values reads L rounded to float, in Eigen's own order (ascending, the order
  /// this solve reads): Eigen's solve of that rounded L, bit for bit.
  void forwardInPlace(const Eigen::SparseMatrix<double>& lower, Eigen::VectorXd& x, Scratch& scratch) const;

  /// The share of L's non-zeros solved in parallel (0 for one part); what the plan is worth.
  double parallelShare() const { return mParallelShare; }
  /// The critical path's share of L's non-zeros: the top plus the heaviest part (1 for one part).
  double criticalShare() const { return mCriticalShare; }
  int parts() const { return static_cast<int>(mPartRuns.size()); }
  /// With float values, L's values rounded to float at Eigen's positions (valuePtr's), which the
  /// forward solve reads; else null. Whatever must match that solve (the correction's H) reads them.
  const float* forwardFloats() const { return mFloatValues ? mForwardFloats.data() : nullptr; }
  /// Bytes of the plan's copy of L's values.
  size_t valueBytes() const {
    return sizeof(double) * mValues.size() + sizeof(float) * (mFloats.size() + mForwardFloats.size());
  }

 private:
  std::vector<Run> mTopRuns;                // solved first, descending
  std::vector<std::vector<Run>> mPartRuns;  // per part, descending
  size_t mMaxGather = 0;                    // the most rows below a supernode
  std::vector<double> mValues;              // L's values in the order the solve reads them,
  std::vector<float> mFloats;               // or those rounded to float (one of the two is empty)
  std::vector<float> mForwardFloats;        // with mFloats: the same values in Eigen's order, for the forward solve
  bool mFloatValues = false;
  std::vector<int64_t> mOffset;             // column j's values start at mValues[mOffset[j]]
  std::vector<int32_t> mRows;               // each run's R, in the order the runs are solved
  std::vector<int32_t> mSuperLast;          // per column, the last column of its supernode
  Eigen::Index mColumns = 0, mNonZeros = 0;  // of the L the plan was made from
  double mParallelShare = 0.0;
  double mCriticalShare = 1.0;

  // mValues (or mFloats), mOffset, mRows and each run's rowCount and rowsAt, mColumns, mNonZeros
  void copyValues(const Eigen::SparseMatrix<double>& lower);
  void sizeScratch(Scratch& scratch) const;  // a buffer per part (at least one) of mMaxGather
};

/// y_i ← (y_i − h_i·c) s_i for the rows i in [begin, end) of the row-major h (m columns, double or
/// float, each value widened exactly): each dot product in four running sums (k mod 4) added
/// pairwise, the same bits in either lanes.
template <class V>
void subtractRowProducts(const V* h, Eigen::Index m, Eigen::Index begin, Eigen::Index end, const double* c,
                         const double* s, double* y, Lanes lanes = widestLanes());

}  // namespace brittle::detail
