#include "brittle/precompute/FillOrdering.h"

#include <metis.h>

#include <algorithm>
#include <vector>

#include "brittle/runtime/StaticCorrection.h"

namespace brittle {

Result<Eigen::VectorXi> fillReducingOrdering(const SparseMatrixd& k) {
  const Eigen::Index n = k.rows();
  if (n == 0 || k.cols() != n) return makeError(ErrorCode::InvalidArgument, "fill-reducing ordering: K must be square and not empty");
  // The graph of K's off-diagonal non-zeros, made symmetric (METIS wants both directions).
  std::vector<std::vector<idx_t>> adjacent(static_cast<size_t>(n));
  for (Eigen::Index c = 0; c < k.outerSize(); ++c) {
    for (SparseMatrixd::InnerIterator it(k, c); it; ++it) {
      if (it.row() == c) continue;
      adjacent[static_cast<size_t>(c)].push_back(static_cast<idx_t>(it.row()));
      adjacent[static_cast<size_t>(it.row())].push_back(static_cast<idx_t>(c));
    }
  }
  std::vector<idx_t> offsets(1, 0), neighbours;
  for (std::vector<idx_t>& a : adjacent) {
    std::sort(a.begin(), a.end());
    a.erase(std::unique(a.begin(), a.end()), a.end());
    neighbours.insert(neighbours.end(), a.begin(), a.end());
    offsets.push_back(static_cast<idx_t>(neighbours.size()));
  }
  idx_t vertices = static_cast<idx_t>(n);
  std::vector<idx_t> perm(static_cast<size_t>(n)), iperm(static_cast<size_t>(n));
  idx_t options[METIS_NOPTIONS];
  METIS_SetDefaultOptions(options);
  options[METIS_OPTION_SEED] = 1;  // METIS's own generator: the same order in every process
  options[METIS_OPTION_NUMBERING] = 0;
  if (neighbours.empty()) neighbours.push_back(0);  // a diagonal K: METIS still wants a buffer
  if (METIS_NodeND(&vertices, offsets.data(), neighbours.data(), nullptr, options, perm.data(), iperm.data()) != METIS_OK) {
    return makeError(ErrorCode::FactorizationFailed, "fill-reducing ordering: METIS_NodeND failed");
  }
  // METIS's perm[k] is the row that goes to position k: the elimination order.
  Eigen::VectorXi order(n);
  for (Eigen::Index i = 0; i < n; ++i) order[i] = static_cast<int>(perm[static_cast<size_t>(i)]);
  if (factorNonZeros(k, order) >= factorNonZeros(k, Eigen::VectorXi())) return Eigen::VectorXi();  // AMD is as good
  return order;
}

}  // namespace brittle
