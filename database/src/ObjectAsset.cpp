#include "brittle/database/ObjectAsset.h"

#include <algorithm>
#include <vector>

namespace brittle {

Eigen::Index femNodeCount(const TetMesh& mesh, ElementOrder order) {
  if (order == ElementOrder::P1) return mesh.nodes.rows();
  // One mid-edge node per distinct edge: count the node pairs (low, high) once each.
  std::vector<uint64_t> keys;
  keys.reserve(6 * static_cast<size_t>(mesh.tets.rows()));
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
    for (int i = 0; i < 4; ++i) {
      for (int j = i + 1; j < 4; ++j) {
        const auto a = static_cast<uint32_t>(mesh.tets(t, i)), b = static_cast<uint32_t>(mesh.tets(t, j));
        keys.push_back((static_cast<uint64_t>(std::min(a, b)) << 32) | std::max(a, b));
      }
    }
  }
  std::sort(keys.begin(), keys.end());
  return mesh.nodes.rows() + static_cast<Eigen::Index>(std::unique(keys.begin(), keys.end()) - keys.begin());
}

bool isPermutation(const Eigen::VectorXi& order, Eigen::Index n) {
  if (order.size() != n) return false;
  std::vector<char> seen(static_cast<size_t>(n), 0);
  for (Eigen::Index k = 0; k < n; ++k) {
    const int v = order[k];
    if (v < 0 || v >= n || seen[static_cast<size_t>(v)]) return false;
    seen[static_cast<size_t>(v)] = 1;
  }
  return true;
}

}  // namespace brittle
