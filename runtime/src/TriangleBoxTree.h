// TriangleBoxTree.h — a tree of axis-aligned boxes over a body's boundary triangles, for the
// contact stage's two searches (ContactGeometry.cpp): the face nearest to a reported point, and
// the faces within the load's radius ρ of the contact. Each once looked at every boundary face
// (the P1 vase's 7k: 0.4–0.7 ms of an impact). Private to the runtime; a Body builds it once.
//
// The searches return what the scans over every face returned, bit for bit: the tree only leaves
// out faces that cannot qualify, and the caller applies the scan's own test, in the scan's order,
// to those it keeps. Boxes are widened by a margin far above the rounding of a closest point
// (10⁻⁹ of the coordinates' magnitude), so a face is never left out by rounding.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <limits>
#include <vector>

#include "brittle/core/MeshTypes.h"

namespace brittle::detail {

class TriangleBoxTree {
 public:
  /// The tree over the triangles `faces` (#F by 3, rows of `nodes`, #N by 3, m): leaves of at most
  /// four faces, split at the median centroid along the widest axis (ties by row: the same tree
  /// in every process).
  static TriangleBoxTree build(const Points& nodes, const Triangles& faces);

  /// The row f with the least dist2(f) (m², the squared distance from `p` to face f), ties to the
  /// lowest row, as a scan over every row with a strict < would find; −1 when there is none.
  /// `best` returns that distance. dist2 must not be below the squared distance of `p` to f's
  /// corners' box (it is not, for a face's closest point).
  template <class Dist2>
  Eigen::Index nearest(const Eigen::Vector3d& p, Dist2&& dist2, double& best) const;

  /// Rows of every face whose box comes within `radiusM` of `p` (a superset of the faces within
  /// it), ascending, into `rows` (cleared; it keeps its storage).
  void within(const Eigen::Vector3d& p, double radiusM, std::vector<int32_t>& rows) const;

  bool empty() const { return mNodes.empty(); }

 private:
  struct Node {
    Eigen::Vector3d lo, hi;  // the box, widened by the margin
    int32_t first = 0;       // leaf: its first entry in mRows; inner: its first child (the second follows)
    int32_t count = 0;       // leaf: its faces; inner: 0
  };
  // Squared distance from p to node n's box (0 inside).
  double boxDistance2(const Node& n, const Eigen::Vector3d& p) const {
    return (n.lo - p).cwiseMax(p - n.hi).cwiseMax(0.0).squaredNorm();
  }
  static constexpr int kStackDepth = 128;  // a median split of 2³¹ faces is 31 levels deep
  std::vector<Node> mNodes;                // mNodes[0] is the root
  std::vector<int32_t> mRows;              // face rows, leaf by leaf
};

template <class Dist2>
Eigen::Index TriangleBoxTree::nearest(const Eigen::Vector3d& p, Dist2&& dist2, double& best) const {
  best = std::numeric_limits<double>::infinity();
  Eigen::Index found = -1;
  if (mNodes.empty()) return found;
  int32_t stack[kStackDepth];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& n = mNodes[static_cast<size_t>(stack[--top])];
    if (boxDistance2(n, p) > best) continue;  // equal may still hold a lower row at the same distance
    if (n.count > 0) {
      for (int32_t k = n.first; k < n.first + n.count; ++k) {
        const int32_t f = mRows[static_cast<size_t>(k)];
        const double d = dist2(f);
        if (d < best || (d == best && f < found)) best = d, found = f;
      }
      continue;
    }
    // The nearer child last, so it is searched first and tightens `best` for the other.
    const int32_t a = n.first, b = n.first + 1;
    const bool aNearer = boxDistance2(mNodes[static_cast<size_t>(a)], p) <= boxDistance2(mNodes[static_cast<size_t>(b)], p);
    stack[top++] = aNearer ? b : a;
    stack[top++] = aNearer ? a : b;
  }
  return found;
}

}  // namespace brittle::detail
