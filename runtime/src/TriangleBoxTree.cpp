#include "TriangleBoxTree.h"

#include <algorithm>
#include <cassert>
#include <limits>
#include <numeric>

namespace brittle::detail {

TriangleBoxTree TriangleBoxTree::build(const Points& nodes, const Triangles& faces) {
  TriangleBoxTree tree;
  const auto count = static_cast<int32_t>(faces.rows());
  if (count == 0) return tree;
  const double margin = 1e-9 * std::max(1.0, nodes.cwiseAbs().maxCoeff());
  std::vector<Eigen::Vector3d> lo(static_cast<size_t>(count)), hi(lo.size()), centre(lo.size());
  for (int32_t f = 0; f < count; ++f) {
    const Eigen::Vector3d a = nodes.row(faces(f, 0)), b = nodes.row(faces(f, 1)), c = nodes.row(faces(f, 2));
    lo[static_cast<size_t>(f)] = a.cwiseMin(b).cwiseMin(c);
    hi[static_cast<size_t>(f)] = a.cwiseMax(b).cwiseMax(c);
    centre[static_cast<size_t>(f)] = (a + b + c) / 3.0;
  }
  tree.mRows.resize(static_cast<size_t>(count));
  std::iota(tree.mRows.begin(), tree.mRows.end(), 0);
  tree.mNodes.reserve(static_cast<size_t>(2 * (count / 4 + 1)));
  tree.mNodes.emplace_back();
  // Nodes to split: (node, first row, row count). Children are made in pairs, so an inner node's
  // second child is its first plus one.
  struct Span {
    int32_t node, first, count;
  };
  std::vector<Span> todo{{0, 0, count}};
  while (!todo.empty()) {
    const Span s = todo.back();
    todo.pop_back();
    const auto begin = tree.mRows.begin() + s.first, end = begin + s.count;
    Eigen::Vector3d boxLo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), boxHi = -boxLo;
    Eigen::Vector3d cLo = boxLo, cHi = boxHi;
    for (auto it = begin; it != end; ++it) {
      const auto f = static_cast<size_t>(*it);
      boxLo = boxLo.cwiseMin(lo[f]), boxHi = boxHi.cwiseMax(hi[f]);
      cLo = cLo.cwiseMin(centre[f]), cHi = cHi.cwiseMax(centre[f]);
    }
    Node& node = tree.mNodes[static_cast<size_t>(s.node)];
    node.lo = boxLo.array() - margin;
    node.hi = boxHi.array() + margin;
    if (s.count <= 4) {
      node.first = s.first;
      node.count = s.count;
      continue;
    }
    Eigen::Index axis;
    (cHi - cLo).maxCoeff(&axis);
    const int32_t half = s.count / 2;
    std::nth_element(begin, begin + half, end, [&](int32_t x, int32_t y) {
      const double cx = centre[static_cast<size_t>(x)][axis], cy = centre[static_cast<size_t>(y)][axis];
      return cx < cy || (cx == cy && x < y);
    });
    const auto child = static_cast<int32_t>(tree.mNodes.size());
    node.first = child;
    node.count = 0;
    tree.mNodes.emplace_back();  // invalidates `node`
    tree.mNodes.emplace_back();
    todo.push_back({child, s.first, half});
    todo.push_back({child + 1, s.first + half, s.count - half});
  }
  return tree;
}

void TriangleBoxTree::within(const Eigen::Vector3d& p, double radiusM, std::vector<int32_t>& rows) const {
  rows.clear();
  if (mNodes.empty()) return;
  const double r2 = radiusM * radiusM;
  int32_t stack[kStackDepth];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& n = mNodes[static_cast<size_t>(stack[--top])];
    if (boxDistance2(n, p) > r2) continue;
    if (n.count > 0) {
      rows.insert(rows.end(), mRows.begin() + n.first, mRows.begin() + n.first + n.count);
      continue;
    }
    assert(top + 2 <= kStackDepth);
    stack[top++] = n.first;
    stack[top++] = n.first + 1;
  }
  std::sort(rows.begin(), rows.end());
}

}  // namespace brittle::detail
