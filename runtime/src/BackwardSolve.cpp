#include "BackwardSolve.h"

#include "Cancellation.h"

#include "brittle/core/Simd.h"

#include <oneapi/tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cassert>
#include <queue>
#include <type_traits>
#include <utility>

namespace brittle::detail {
namespace {

// Column j's non-zeros: [begin, end) of the value and row arrays.
[[gnu::always_inline]] inline std::pair<Eigen::Index, Eigen::Index> columnRange(const Eigen::SparseMatrix<double>& lower, Eigen::Index j) {
  const Eigen::Index begin = lower.outerIndexPtr()[j];
  const Eigen::Index end = lower.isCompressed() ? lower.outerIndexPtr()[j + 1] : begin + lower.innerNonZeroPtr()[j];
  return {begin, end};
}

// Σ_t col_c,t b_t over t < m for C columns at once (C = 1, 2), each in four running sums
// (t mod 4) added pairwise: the sums over a supernode's rows of its columns, sharing the loads of b.
// The four sums are 4/W registers of W lanes (two SSE2 registers, W = 2, or one AVX register,
// W = 4; lane l of register r holds t mod 4 = rW + l), a product then a sum per lane as in plain
// C++, so the bits are those of the scalar loop in either form; GCC's own vectorisation of that
// loop shuffled lanes and ran ~15 % slower. A column's sum is the same arithmetic whichever C it is
// computed with.
template <int W, int C, class V>
[[gnu::always_inline]] inline void dotColumns(const std::array<const V*, C>& cols, const double* b, Eigen::Index m,
                                              std::array<double, C>& sums) {
  using Pack = VectorOf<double, W>;
  constexpr int R = 4 / W;  // registers per four rows
  // Four of column c's values from row t, as doubles (exact from float) in R registers.
  auto load = [&](int c, Eigen::Index t, Pack* out) {
    if constexpr (std::is_same_v<V, double>) {
      for (int r = 0; r < R; ++r) loadLanes<W>(cols[c] + t + r * W, out[r]);
    } else {
      VectorOf<float, 4> f;
      loadLanes<4>(cols[c] + t, f);
      if constexpr (W == 4) {
        out[0] = __builtin_convertvector(f, Pack);
      } else {
        out[0] = __builtin_convertvector(__builtin_shufflevector(f, f, 0, 1), Pack);
        out[1] = __builtin_convertvector(__builtin_shufflevector(f, f, 2, 3), Pack);
      }
    }
  };
  double acc[C][4] = {};
  Eigen::Index t = 0;
  Pack s0[R] = {}, s1[R] = {};
  for (; t + 4 <= m; t += 4) {
    Pack bt[R], col[R];
    for (int r = 0; r < R; ++r) loadLanes<W>(b + t + r * W, bt[r]);
    load(0, t, col);
    for (int r = 0; r < R; ++r) s0[r] += col[r] * bt[r];
    if constexpr (C == 2) {
      load(1, t, col);
      for (int r = 0; r < R; ++r) s1[r] += col[r] * bt[r];
    }
  }
  for (int r = 0; r < R; ++r) {
    __builtin_memcpy(acc[0] + r * W, &s0[r], sizeof s0[r]);
    if constexpr (C == 2) __builtin_memcpy(acc[C - 1] + r * W, &s1[r], sizeof s1[r]);
  }
  for (int l = 0; t + l < m; ++l) {
    for (int c = 0; c < C; ++c) acc[c][l] += static_cast<double>(cols[c][t + l]) * b[t + l];
  }
  for (int c = 0; c < C; ++c) sums[c] = (acc[c][0] + acc[c][1]) + (acc[c][2] + acc[c][3]);
}

// Column j's non-zero count.
[[gnu::always_inline]] inline Eigen::Index columnLength(const Eigen::SparseMatrix<double>& lower, int32_t j) {
  const auto [begin, end] = columnRange(lower, j);
  return end - begin;
}

// Columns [run.first, run.end), descending, of the supernode that ends at run.last. Column j holds
// rows j+1..last (in the supernode) then R, the rows of column `last`, whose x are gathered. Column
// j's values are at values + offset[j] (the plan's copy, in the order this loop reads them). W is
// the lanes of dotColumns.
template <int W, class V>
[[gnu::always_inline]] inline void solveRunsInLanes(const Eigen::SparseMatrix<double>& lower, const V* values,
                                                    const int64_t* offset, const int32_t* planRows,
                                                    const std::vector<BackwardSolvePlan::Run>& runs, double* x,
                                                    double* b) {
  for (size_t i = 0; i < runs.size(); ++i) {
    const BackwardSolvePlan::Run& run = runs[i];
    if (i + 1 < runs.size()) {  // the next run's values and rows follow this one's: ask for them now
      const BackwardSolvePlan::Run& next = runs[i + 1];
      prefetchBytes(values + offset[next.end - 1], values + offset[next.first] + columnLength(lower, next.first));
      prefetchBytes(planRows + next.rowsAt, planRows + next.rowsAt + next.rowCount);
    }
    const Eigen::Index m = run.rowCount;
    const int32_t* rows = planRows + run.rowsAt;
    for (Eigen::Index t = 0; t < m; ++t) b[t] = x[rows[t]];
    // Column j: its sum over R (its last m values), plus its sum over rows j+1..last (the
    // supernode's triangle: 14 % of the plate's L, 16–20 % of the other default objects'), both
    // in dotColumns' four running sums. The triangle's x are contiguous; summed in one running
    // sum, its add latency had set the pace of the largest supernodes.
    auto tail = [&](int32_t j) { return values + offset[j] + columnLength(lower, j) - m; };
    auto finish = [&](int32_t j, double overR) {
      std::array<double, 1> inside{};
      dotColumns<W, 1, V>({values + offset[j]}, x + j + 1, columnLength(lower, j) - m, inside);
      x[j] -= overR + inside[0];
    };
    int32_t j = run.end - 1;
    for (; j - 1 >= run.first; j -= 2) {
      std::array<double, 2> sums{};
      dotColumns<W, 2, V>({tail(j), tail(j - 1)}, b, m, sums);
      finish(j, sums[0]);
      finish(j - 1, sums[1]);
    }
    if (j == run.first) {
      std::array<double, 1> sum{};
      dotColumns<W, 1, V>({tail(j)}, b, m, sum);
      finish(j, sum[0]);
    }
  }
}

template <class V>
void solveRunsNarrow(const Eigen::SparseMatrix<double>& lower, const V* values, const int64_t* offset,
                     const int32_t* rows, const std::vector<BackwardSolvePlan::Run>& runs, double* x, double* b) {
  solveRunsInLanes<2>(lower, values, offset, rows, runs, x, b);
}

// The same, with the dot products in AVX registers (the same bits). It calls nothing while they
// are live, so GCC clears their upper halves on return (brittle/core/Simd.h).
template <class V>
BRITTLE_TARGET_AVX void solveRunsWide(const Eigen::SparseMatrix<double>& lower, const V* values, const int64_t* offset,
                                      const int32_t* rows, const std::vector<BackwardSolvePlan::Run>& runs, double* x,
                                      double* b) {
  solveRunsInLanes<4>(lower, values, offset, rows, runs, x, b);
}

template <class V>
void solveRuns(const Eigen::SparseMatrix<double>& lower, const V* values, const int64_t* offset, const int32_t* rows,
               const std::vector<BackwardSolvePlan::Run>& runs, double* x, std::vector<double>& gathered, Lanes lanes) {
  if (lanes == Lanes::Wide) {
    solveRunsWide(lower, values, offset, rows, runs, x, gathered.data());
  } else {
    solveRunsNarrow(lower, values, offset, rows, runs, x, gathered.data());
  }
}

// y_i ← (y_i − h_i·c) s_i over rows [begin, end) of the row-major h (m columns): each dot product
// dotColumns' (four running sums, the same bits in either lanes).
template <int W, class V>
[[gnu::always_inline]] inline void subtractRowProductsInLanes(const V* h, Eigen::Index m, Eigen::Index begin,
                                                              Eigen::Index end, const double* c, const double* s,
                                                              double* y) {
  for (Eigen::Index i = begin; i < end; ++i) {
    std::array<double, 1> sum{};
    dotColumns<W, 1, V>({h + i * m}, c, m, sum);
    y[i] = (y[i] - sum[0]) * s[i];
  }
}

template <class V>
void subtractRowProductsNarrow(const V* h, Eigen::Index m, Eigen::Index begin, Eigen::Index end, const double* c,
                               const double* s, double* y) {
  subtractRowProductsInLanes<2>(h, m, begin, end, c, s, y);
}

template <class V>
BRITTLE_TARGET_AVX void subtractRowProductsWide(const V* h, Eigen::Index m, Eigen::Index begin, Eigen::Index end,
                                                const double* c, const double* s, double* y) {
  subtractRowProductsInLanes<4>(h, m, begin, end, c, s, y);
}

// A supernode's last column per column: j and j + 1 share one when j's first row is j + 1 and j
// has one row more than j + 1 (its pattern is then j + 1's and j + 1).
std::vector<int32_t> supernodeLast(const Eigen::SparseMatrix<double>& lower) {
  const auto n = static_cast<int32_t>(lower.cols());
  std::vector<int32_t> last(static_cast<size_t>(n));
  for (int32_t j = n - 1; j >= 0; --j) {
    last[static_cast<size_t>(j)] = j;
    if (j + 1 >= n) continue;
    const auto [begin, end] = columnRange(lower, j);
    const auto [nextBegin, nextEnd] = columnRange(lower, j + 1);
    if (end > begin && lower.innerIndexPtr()[begin] == j + 1 && end - begin == nextEnd - nextBegin + 1) {
      last[static_cast<size_t>(j)] = last[static_cast<size_t>(j) + 1];
    }
  }
  return last;
}

// Descending columns as runs: neighbours in the list that are neighbours in one supernode.
std::vector<BackwardSolvePlan::Run> toRuns(const std::vector<int32_t>& descending, const std::vector<int32_t>& last) {
  std::vector<BackwardSolvePlan::Run> runs;
  for (int32_t j : descending) {
    const int32_t l = last[static_cast<size_t>(j)];
    if (!runs.empty() && runs.back().first == j + 1 && runs.back().last == l) {
      runs.back().first = j;
    } else {
      runs.push_back({j, j + 1, l});
    }
  }
  return runs;
}

}  // namespace

BackwardSolvePlan BackwardSolvePlan::make(const Eigen::SparseMatrix<double>& lower, int parts, bool floatValues) {
  BackwardSolvePlan plan;
  plan.mFloatValues = floatValues;
  const auto n = static_cast<int32_t>(lower.cols());
  std::vector<int32_t> parent(static_cast<size_t>(n), -1);
  std::vector<double> subtreeWork(static_cast<size_t>(n), 0.0);
  double total = 0.0;
  for (int32_t j = 0; j < n; ++j) {  // children come before their parents, so sums are complete in order
    if (j % 4096 == 0) cancellationPoint();  // made on a World's background threads (Cancellation.h)
    const auto [begin, end] = columnRange(lower, j);
    if (end > begin) parent[static_cast<size_t>(j)] = lower.innerIndexPtr()[begin];
    subtreeWork[static_cast<size_t>(j)] += static_cast<double>(end - begin) + 1.0;
    total += static_cast<double>(end - begin) + 1.0;
    if (parent[static_cast<size_t>(j)] >= 0) {
      subtreeWork[static_cast<size_t>(parent[static_cast<size_t>(j)])] += subtreeWork[static_cast<size_t>(j)];
    }
  }
  // Children lists (compressed, ascending).
  std::vector<int32_t> childStart(static_cast<size_t>(n) + 1, 0), children(static_cast<size_t>(n));
  for (int32_t j = 0; j < n; ++j) {
    if (parent[static_cast<size_t>(j)] >= 0) ++childStart[static_cast<size_t>(parent[static_cast<size_t>(j)]) + 1];
  }
  for (int32_t j = 0; j < n; ++j) childStart[static_cast<size_t>(j) + 1] += childStart[static_cast<size_t>(j)];
  {
    std::vector<int32_t> fill(childStart.begin(), childStart.end() - 1);
    for (int32_t j = 0; j < n; ++j) {
      if (const int32_t p = parent[static_cast<size_t>(j)]; p >= 0) children[static_cast<size_t>(fill[static_cast<size_t>(p)]++)] = j;
    }
  }
  parts = std::max(parts, 1);
  const std::vector<int32_t> superLast = supernodeLast(lower);
  plan.mSuperLast = superLast;
  for (int32_t j = 0; j < n; ++j) {
    const auto [begin, end] = columnRange(lower, j);
    plan.mMaxGather = std::max(plan.mMaxGather, static_cast<size_t>(end - begin));
  }
  if (parts == 1 || n == 0) {
    std::vector<int32_t> all(static_cast<size_t>(n));
    for (int32_t j = 0; j < n; ++j) all[static_cast<size_t>(n - 1 - j)] = j;
    plan.mTopRuns = toRuns(all, superLast);
    plan.copyValues(lower);
    return plan;
  }
  // Take the heaviest subtree apart (its root to the top, its children back as candidates) while
  // it holds more than `limit`; then deal the subtrees left out, largest first, to the lightest
  // part (ties: the lower node, the lower part). The time is that of the top plus the heaviest
  // part: the limit that makes it least is taken, among a few fractions of a part's share.
  auto lighter = [&](int32_t a, int32_t b) {
    const double wa = subtreeWork[static_cast<size_t>(a)], wb = subtreeWork[static_cast<size_t>(b)];
    return wa != wb ? wa < wb : a > b;
  };
  struct Split {
    std::vector<int32_t> top, finals;
    std::vector<int> partOf;  // per final
    double criticalWork = 0.0, parallelWork = 0.0;
  };
  auto split = [&](double limit) {
    Split sp;
    std::priority_queue<int32_t, std::vector<int32_t>, decltype(lighter)> heap(lighter);
    for (int32_t j = 0; j < n; ++j) {
      if (parent[static_cast<size_t>(j)] < 0) heap.push(j);
    }
    double topWork = total;
    while (!heap.empty()) {
      const int32_t j = heap.top();
      heap.pop();
      const int32_t first = childStart[static_cast<size_t>(j)], last = childStart[static_cast<size_t>(j) + 1];
      if (subtreeWork[static_cast<size_t>(j)] > limit && last > first) {
        sp.top.push_back(j);
        for (int32_t c = first; c < last; ++c) heap.push(children[static_cast<size_t>(c)]);
      } else {
        sp.finals.push_back(j);
        topWork -= subtreeWork[static_cast<size_t>(j)];
      }
    }
    std::sort(sp.finals.begin(), sp.finals.end(), [&](int32_t a, int32_t b) { return lighter(b, a); });
    std::vector<double> load(static_cast<size_t>(parts), 0.0);
    for (int32_t root : sp.finals) {
      const auto part = std::min_element(load.begin(), load.end()) - load.begin();
      load[static_cast<size_t>(part)] += subtreeWork[static_cast<size_t>(root)];
      sp.partOf.push_back(static_cast<int>(part));
    }
    sp.parallelWork = total - topWork;
    sp.criticalWork = topWork + *std::max_element(load.begin(), load.end());
    return sp;
  };
  Split best = split(total / parts);
  for (double fraction : {0.75, 0.5, 0.33, 0.25, 0.125}) {
    if (Split sp = split(fraction * total / parts); sp.criticalWork < best.criticalWork) best = std::move(sp);
  }
  std::sort(best.top.begin(), best.top.end(), std::greater<>());
  plan.mTopRuns = toRuns(best.top, superLast);
  std::vector<std::vector<int32_t>> partNodes(static_cast<size_t>(parts));
  std::vector<int32_t> stack;
  for (size_t f = 0; f < best.finals.size(); ++f) {
    std::vector<int32_t>& nodes = partNodes[static_cast<size_t>(best.partOf[f])];
    stack.assign(1, best.finals[f]);
    while (!stack.empty()) {
      const int32_t j = stack.back();
      stack.pop_back();
      nodes.push_back(j);
      for (int32_t c = childStart[static_cast<size_t>(j)]; c < childStart[static_cast<size_t>(j) + 1]; ++c) {
        stack.push_back(children[static_cast<size_t>(c)]);
      }
    }
  }
  for (auto& nodes : partNodes) {
    std::sort(nodes.begin(), nodes.end(), std::greater<>());
    plan.mPartRuns.push_back(toRuns(nodes, superLast));
  }
  plan.copyValues(lower);
  plan.mParallelShare = best.parallelWork / total;
  plan.mCriticalShare = best.criticalWork / total;
  return plan;
}

void BackwardSolvePlan::sizeScratch(Scratch& scratch) const {
  const size_t buffers = std::max<size_t>(mPartRuns.size(), 1);
  if (scratch.size() < buffers) scratch.resize(buffers);
  for (auto& buffer : scratch) {
    if (buffer.size() < mMaxGather) buffer.resize(mMaxGather);
  }
}

void BackwardSolvePlan::copyValues(const Eigen::SparseMatrix<double>& lower) {
  mColumns = lower.cols();
  mNonZeros = lower.nonZeros();
  mOffset.assign(static_cast<size_t>(lower.cols()), 0);
  mValues.clear();
  mFloats.clear();
  mForwardFloats.clear();
  mRows.clear();
  if (mFloatValues) {
    mFloats.reserve(static_cast<size_t>(lower.nonZeros()));
    // The forward solve's copy keeps Eigen's positions (columnRange's), so that it walks the
    // values forwards as it walks Eigen's: the solve-order copy holds a run's columns descending,
    // and a forward solve reading it went backwards through it and was slower than Eigen's doubles.
    const Eigen::Index size = lower.cols() > 0 ? columnRange(lower, lower.cols() - 1).second : 0;
    mForwardFloats.resize(static_cast<size_t>(size));
    for (Eigen::Index p = 0; p < size; ++p) {
      if (p % (1 << 20) == 0) cancellationPoint();
      mForwardFloats[static_cast<size_t>(p)] = static_cast<float>(lower.valuePtr()[p]);
    }
  } else {
    mValues.reserve(static_cast<size_t>(lower.nonZeros()));
  }
  // Each run's R too, beside: the gather read them from Eigen's row indices, column `last` of each
  // run in turn, which the prefetcher followed as badly as it followed the values (the plate's
  // backward solve: ~20 % of its CPU time less, the gather's share of its samples 27 → 10 %).
  auto copy = [&](std::vector<Run>& runs) {
    for (Run& run : runs) {
      const auto [lastBegin, lastEnd] = columnRange(lower, run.last);
      run.rowCount = static_cast<int32_t>(lastEnd - lastBegin);
      run.rowsAt = static_cast<int64_t>(mRows.size());
      mRows.insert(mRows.end(), lower.innerIndexPtr() + lastBegin, lower.innerIndexPtr() + lastEnd);
      for (int32_t j = run.end - 1; j >= run.first; --j) {
        if (j % 1024 == 0) cancellationPoint();
        const auto [begin, end] = columnRange(lower, j);
        if (mFloatValues) {
          mOffset[static_cast<size_t>(j)] = static_cast<int64_t>(mFloats.size());
          for (Eigen::Index p = begin; p < end; ++p) mFloats.push_back(static_cast<float>(lower.valuePtr()[p]));
        } else {
          mOffset[static_cast<size_t>(j)] = static_cast<int64_t>(mValues.size());
          mValues.insert(mValues.end(), lower.valuePtr() + begin, lower.valuePtr() + end);
        }
      }
    }
  };
  copy(mTopRuns);
  for (auto& runs : mPartRuns) copy(runs);
}

void BackwardSolvePlan::solveInPlace(const Eigen::SparseMatrix<double>& lower, Eigen::VectorXd& x, Scratch& scratch,
                                     Lanes lanes) const {
  assert(lower.cols() == mColumns && lower.nonZeros() == mNonZeros && x.size() == mColumns);
  sizeScratch(scratch);
  auto solve = [&](const auto* values) {
    solveRuns(lower, values, mOffset.data(), mRows.data(), mTopRuns, x.data(), scratch[0], lanes);
    tbb::parallel_for(0, static_cast<int>(mPartRuns.size()), [&](int part) {
      solveRuns(lower, values, mOffset.data(), mRows.data(), mPartRuns[static_cast<size_t>(part)], x.data(),
                scratch[static_cast<size_t>(part)], lanes);
    });
  };
  if (mFloatValues) {
    solve(mFloats.data());
  } else {
    solve(mValues.data());
  }
}

namespace {

// The forward solve over `values` at Eigen's positions, double or float (each widened exactly).
template <class V>
void forwardWithValues(const Eigen::SparseMatrix<double>& lower, const std::vector<int32_t>& superLast,
                       const V* values, Eigen::VectorXd& x, double* b) {
  const auto n = static_cast<int32_t>(lower.cols());
  for (int32_t j = 0; j < n;) {
    const int32_t last = superLast[static_cast<size_t>(j)];
    int32_t first = j;
    while (first <= last && x[first] == 0.0) ++first;
    if (first > last) {  // nothing to pass on from this part of the supernode
      j = last + 1;
      continue;
    }
    // Columns first..last share the rows R below `last`: x over R is gathered once, takes each
    // column's update in column order (as Eigen's loop gives it), and is put back.
    const auto [lastBegin, lastEnd] = columnRange(lower, last);
    const Eigen::Index m = lastEnd - lastBegin;
    const int* rows = lower.innerIndexPtr() + lastBegin;
    for (Eigen::Index t = 0; t < m; ++t) b[t] = x[rows[t]];
    for (int32_t c = first; c <= last; ++c) {
      const double xc = x[c];
      if (xc == 0.0) continue;
      const auto [begin, end] = columnRange(lower, c);
      const Eigen::Index inside = end - begin - m;
      for (Eigen::Index p = 0; p < inside; ++p) x[c + 1 + p] -= xc * static_cast<double>(values[begin + p]);
      const V* tail = values + begin + inside;
      for (Eigen::Index t = 0; t < m; ++t) b[t] -= xc * static_cast<double>(tail[t]);
    }
    for (Eigen::Index t = 0; t < m; ++t) x[rows[t]] = b[t];
    j = last + 1;
  }
}

}  // namespace

void BackwardSolvePlan::forwardInPlace(const Eigen::SparseMatrix<double>& lower, Eigen::VectorXd& x,
                                       Scratch& scratch) const {
  assert(lower.cols() == mColumns && lower.nonZeros() == mNonZeros && x.size() == mColumns);
  sizeScratch(scratch);
  double* b = scratch[0].data();
  if (mFloatValues) {
    forwardWithValues(lower, mSuperLast, mForwardFloats.data(), x, b);
  } else {
    forwardWithValues(lower, mSuperLast, lower.valuePtr(), x, b);
  }
}

void BackwardSolvePlan::solveInPlace(const Eigen::SparseMatrix<double>& lower, Eigen::VectorXd& x) const {
  Scratch scratch;
  solveInPlace(lower, x, scratch);
}

template <class V>
void subtractRowProducts(const V* h, Eigen::Index m, Eigen::Index begin, Eigen::Index end, const double* c,
                         const double* s, double* y, Lanes lanes) {
  if (lanes == Lanes::Wide) {
    subtractRowProductsWide(h, m, begin, end, c, s, y);
  } else {
    subtractRowProductsNarrow(h, m, begin, end, c, s, y);
  }
}

template void subtractRowProducts<float>(const float*, Eigen::Index, Eigen::Index, Eigen::Index, const double*,
                                         const double*, double*, Lanes);
template void subtractRowProducts<double>(const double*, Eigen::Index, Eigen::Index, Eigen::Index, const double*,
                                          const double*, double*, Lanes);

}  // namespace brittle::detail
