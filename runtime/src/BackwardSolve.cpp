#include "BackwardSolve.h"

#if defined(__SSE2__)
#include <emmintrin.h>  // part of x86-64 itself
#endif
#include <oneapi/tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cassert>
#include <queue>
#include <utility>

namespace brittle::detail {
namespace {

// Column j's non-zeros: [begin, end) of the value and row arrays.
std::pair<Eigen::Index, Eigen::Index> columnRange(const Eigen::SparseMatrix<double>& lower, Eigen::Index j) {
  const Eigen::Index begin = lower.outerIndexPtr()[j];
  const Eigen::Index end = lower.isCompressed() ? lower.outerIndexPtr()[j + 1] : begin + lower.innerNonZeroPtr()[j];
  return {begin, end};
}

// Σ_t col_c,t b_t over t < m for C columns at once (C = 1, 2), each in four running sums
// (t mod 4) added pairwise: the sums over a supernode's rows of its columns, sharing the loads of b.
// The four sums are two SSE2 registers (lanes t mod 4 = 0, 1 and 2, 3), a product then a sum per
// lane as in plain C++, so the bits are those of the scalar loop on any x86-64; GCC's own
// vectorisation of that loop shuffled lanes and ran ~15 % slower. A column's sum is the same
// arithmetic whichever C it is computed with.
template <int C>
void dotColumns(const std::array<const double*, C>& cols, const double* b, Eigen::Index m, std::array<double, C>& sums) {
  double acc[C][4] = {};
  Eigen::Index t = 0;
#if defined(__SSE2__)
  __m128d low[C], high[C];
  for (int c = 0; c < C; ++c) low[c] = high[c] = _mm_setzero_pd();
  for (; t + 4 <= m; t += 4) {
    const __m128d b0 = _mm_loadu_pd(b + t), b1 = _mm_loadu_pd(b + t + 2);
    for (int c = 0; c < C; ++c) {
      low[c] = _mm_add_pd(low[c], _mm_mul_pd(_mm_loadu_pd(cols[c] + t), b0));
      high[c] = _mm_add_pd(high[c], _mm_mul_pd(_mm_loadu_pd(cols[c] + t + 2), b1));
    }
  }
  for (int c = 0; c < C; ++c) {
    _mm_storeu_pd(acc[c], low[c]);
    _mm_storeu_pd(acc[c] + 2, high[c]);
  }
#else
  for (; t + 4 <= m; t += 4) {
    for (int c = 0; c < C; ++c) {
      for (int l = 0; l < 4; ++l) acc[c][l] += cols[c][t + l] * b[t + l];
    }
  }
#endif
  for (int l = 0; t + l < m; ++l) {
    for (int c = 0; c < C; ++c) acc[c][l] += cols[c][t + l] * b[t + l];
  }
  for (int c = 0; c < C; ++c) sums[c] = (acc[c][0] + acc[c][1]) + (acc[c][2] + acc[c][3]);
}

// Columns [run.first, run.end), descending, of the supernode that ends at run.last. Column j holds
// rows j+1..last (in the supernode) then R, the rows of column `last`, whose x are gathered. Column
// j's values are at values + offset[j] (the plan's copy, in the order this loop reads them).
void solveRuns(const Eigen::SparseMatrix<double>& lower, const double* values, const int64_t* offset,
               const std::vector<BackwardSolvePlan::Run>& runs, double* x, std::vector<double>& gathered) {
  auto length = [&](int32_t j) {
    const auto [begin, end] = columnRange(lower, j);
    return end - begin;
  };
  for (size_t i = 0; i < runs.size(); ++i) {
    const BackwardSolvePlan::Run& run = runs[i];
    if (i + 1 < runs.size()) {  // the next run's values follow this one's: ask for them now
      const BackwardSolvePlan::Run& next = runs[i + 1];
      const double* end = values + offset[next.first] + length(next.first);
      for (const double* p = values + offset[next.end - 1]; p < end; p += 8) __builtin_prefetch(p);
    }
    const auto [lastBegin, lastEnd] = columnRange(lower, run.last);
    const Eigen::Index m = lastEnd - lastBegin;
    const int* rows = lower.innerIndexPtr() + lastBegin;
    double* b = gathered.data();
    for (Eigen::Index t = 0; t < m; ++t) b[t] = x[rows[t]];
    // Column j: its sum over R (its last m values), then over rows j+1..last, in row order.
    auto tail = [&](int32_t j) { return values + offset[j] + length(j) - m; };
    auto finish = [&](int32_t j, double overR) {
      const double* column = values + offset[j];
      const Eigen::Index inside = length(j) - m;
      double t = overR;
      for (Eigen::Index p = 0; p < inside; ++p) t += column[p] * x[j + 1 + p];
      x[j] -= t;
    };
    int32_t j = run.end - 1;
    for (; j - 1 >= run.first; j -= 2) {
      std::array<double, 2> sums{};
      dotColumns<2>({tail(j), tail(j - 1)}, b, m, sums);
      finish(j, sums[0]);
      finish(j - 1, sums[1]);
    }
    if (j == run.first) {
      std::array<double, 1> sum{};
      dotColumns<1>({tail(j)}, b, m, sum);
      finish(j, sum[0]);
    }
  }
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

BackwardSolvePlan BackwardSolvePlan::make(const Eigen::SparseMatrix<double>& lower, int parts) {
  BackwardSolvePlan plan;
  const auto n = static_cast<int32_t>(lower.cols());
  std::vector<int32_t> parent(static_cast<size_t>(n), -1);
  std::vector<double> subtreeWork(static_cast<size_t>(n), 0.0);
  double total = 0.0;
  for (int32_t j = 0; j < n; ++j) {  // children come before their parents, so sums are complete in order
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
  mValues.reserve(static_cast<size_t>(lower.nonZeros()));
  auto copy = [&](const std::vector<Run>& runs) {
    for (const Run& run : runs) {
      for (int32_t j = run.end - 1; j >= run.first; --j) {
        const auto [begin, end] = columnRange(lower, j);
        mOffset[static_cast<size_t>(j)] = static_cast<int64_t>(mValues.size());
        mValues.insert(mValues.end(), lower.valuePtr() + begin, lower.valuePtr() + end);
      }
    }
  };
  copy(mTopRuns);
  for (const auto& runs : mPartRuns) copy(runs);
}

void BackwardSolvePlan::solveInPlace(const Eigen::SparseMatrix<double>& lower, Eigen::VectorXd& x,
                                     Scratch& scratch) const {
  assert(lower.cols() == mColumns && lower.nonZeros() == mNonZeros && x.size() == mColumns);
  sizeScratch(scratch);
  solveRuns(lower, mValues.data(), mOffset.data(), mTopRuns, x.data(), scratch[0]);
  tbb::parallel_for(0, static_cast<int>(mPartRuns.size()), [&](int part) {
    solveRuns(lower, mValues.data(), mOffset.data(), mPartRuns[static_cast<size_t>(part)], x.data(),
              scratch[static_cast<size_t>(part)]);
  });
}

void BackwardSolvePlan::forwardInPlace(const Eigen::SparseMatrix<double>& lower, Eigen::VectorXd& x,
                                       Scratch& scratch) const {
  assert(lower.cols() == mColumns && lower.nonZeros() == mNonZeros && x.size() == mColumns);
  sizeScratch(scratch);
  std::vector<double>& gathered = scratch[0];
  const auto n = static_cast<int32_t>(lower.cols());
  const double* values = lower.valuePtr();
  double* b = gathered.data();
  for (int32_t j = 0; j < n;) {
    const int32_t last = mSuperLast[static_cast<size_t>(j)];
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
      for (Eigen::Index p = 0; p < inside; ++p) x[c + 1 + p] -= xc * values[begin + p];
      const double* tail = values + begin + inside;
      for (Eigen::Index t = 0; t < m; ++t) b[t] -= xc * tail[t];
    }
    for (Eigen::Index t = 0; t < m; ++t) x[rows[t]] = b[t];
    j = last + 1;
  }
}

void BackwardSolvePlan::solveInPlace(const Eigen::SparseMatrix<double>& lower, Eigen::VectorXd& x) const {
  Scratch scratch;
  solveInPlace(lower, x, scratch);
}

}  // namespace brittle::detail
