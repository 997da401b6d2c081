#include "BackwardSolve.h"

#include <oneapi/tbb/parallel_for.h>

#include <algorithm>
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

void solveColumns(const Eigen::SparseMatrix<double>& lower, const std::vector<int32_t>& columns, double* x) {
  const double* values = lower.valuePtr();
  const int* rows = lower.innerIndexPtr();
  for (int32_t j : columns) {
    const auto [begin, end] = columnRange(lower, j);
    double t = x[j];
    for (Eigen::Index p = begin; p < end; ++p) t -= values[p] * x[rows[p]];
    x[j] = t;
  }
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
  if (parts == 1 || n == 0) {
    plan.mTopNodes.resize(static_cast<size_t>(n));
    for (int32_t j = 0; j < n; ++j) plan.mTopNodes[static_cast<size_t>(n - 1 - j)] = j;
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
  plan.mTopNodes = std::move(best.top);
  std::sort(plan.mTopNodes.begin(), plan.mTopNodes.end(), std::greater<>());
  plan.mPartNodes.assign(static_cast<size_t>(parts), {});
  std::vector<int32_t> stack;
  for (size_t f = 0; f < best.finals.size(); ++f) {
    std::vector<int32_t>& nodes = plan.mPartNodes[static_cast<size_t>(best.partOf[f])];
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
  for (auto& nodes : plan.mPartNodes) std::sort(nodes.begin(), nodes.end(), std::greater<>());
  plan.mParallelShare = best.parallelWork / total;
  plan.mCriticalShare = best.criticalWork / total;
  return plan;
}

void BackwardSolvePlan::solveInPlace(const Eigen::SparseMatrix<double>& lower, Eigen::VectorXd& x) const {
  solveColumns(lower, mTopNodes, x.data());
  tbb::parallel_for(0, static_cast<int>(mPartNodes.size()),
                    [&](int part) { solveColumns(lower, mPartNodes[static_cast<size_t>(part)], x.data()); });
}

}  // namespace brittle::detail
