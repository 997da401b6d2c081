#include "brittle/descriptors/MeshRefinement.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>
#include <utility>
#include <vector>

namespace brittle {

TriangleMesh subdivideMidpoints(const TriangleMesh& in) {
  const Eigen::Index v0 = in.vertices.rows(), f0 = in.faces.rows();
  // Midpoint of each undirected edge, numbered in order of first use.
  std::unordered_map<uint64_t, int32_t> midpoint;
  midpoint.reserve(static_cast<size_t>(2 * f0));
  std::vector<std::pair<int32_t, int32_t>> edges;
  auto mid = [&](int32_t a, int32_t b) {
    const auto [lo, hi] = std::minmax(a, b);
    const uint64_t key = (static_cast<uint64_t>(static_cast<uint32_t>(lo)) << 32) | static_cast<uint32_t>(hi);
    const auto [it, inserted] = midpoint.try_emplace(key, static_cast<int32_t>(v0 + static_cast<Eigen::Index>(edges.size())));
    if (inserted) edges.emplace_back(lo, hi);
    return it->second;
  };
  TriangleMesh out;
  out.faces.resize(4 * f0, 3);
  for (Eigen::Index f = 0; f < f0; ++f) {
    const int32_t a = in.faces(f, 0), b = in.faces(f, 1), c = in.faces(f, 2);
    const int32_t ab = mid(a, b), bc = mid(b, c), ca = mid(c, a);
    out.faces.row(4 * f + 0) << a, ab, ca;
    out.faces.row(4 * f + 1) << b, bc, ab;
    out.faces.row(4 * f + 2) << c, ca, bc;
    out.faces.row(4 * f + 3) << ab, bc, ca;
  }
  out.vertices.resize(v0 + static_cast<Eigen::Index>(edges.size()), 3);
  out.vertices.topRows(v0) = in.vertices;
  for (size_t e = 0; e < edges.size(); ++e) {
    out.vertices.row(v0 + static_cast<Eigen::Index>(e)) =
        0.5 * (in.vertices.row(edges[e].first) + in.vertices.row(edges[e].second));
  }
  return out;
}

TriangleMesh subdivideToAtLeast(const TriangleMesh& mesh, int64_t minFaces) {
  TriangleMesh out = mesh;
  while (out.faces.rows() > 0 && out.faces.rows() < minFaces) out = subdivideMidpoints(out);
  return out;
}

TriangleMesh unitIcosphere(int level) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  TriangleMesh m;
  m.vertices.resize(12, 3);
  m.vertices << -1, t, 0, 1, t, 0, -1, -t, 0, 1, -t, 0, 0, -1, t, 0, 1, t, 0, -1, -t, 0, 1, -t, t, 0, -1, t, 0, 1, -t, 0, -1,
      -t, 0, 1;
  m.faces.resize(20, 3);
  m.faces << 0, 11, 5, 0, 5, 1, 0, 1, 7, 0, 7, 10, 0, 10, 11, 1, 5, 9, 5, 11, 4, 11, 10, 2, 10, 7, 6, 7, 1, 8, 3, 9, 4, 3, 4,
      2, 3, 2, 6, 3, 6, 8, 3, 8, 9, 4, 9, 5, 2, 4, 11, 6, 2, 10, 8, 6, 7, 9, 8, 1;
  auto project = [](Points& v, Eigen::Index from) {
    for (Eigen::Index i = from; i < v.rows(); ++i) v.row(i) = Eigen::Vector3d(v.row(i)).normalized().transpose();
  };
  project(m.vertices, 0);
  for (int l = 0; l < level; ++l) {
    const Eigen::Index old = m.vertices.rows();
    m = subdivideMidpoints(m);
    project(m.vertices, old);  // only the new midpoints are off the sphere
  }
  return m;
}

}  // namespace brittle
