#include "brittle/precompute/FeatureCurves.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <numeric>
#include <tuple>

namespace brittle {

FeatureCurves detectFeatureCurves(const TriangleMesh& surface, const FeatureCurveSettings& settings) {
  const auto& v = surface.vertices;
  const auto& f = surface.faces;
  auto point = [&](int32_t i) -> Eigen::Vector3d { return v.row(i).transpose(); };
  std::vector<Eigen::Vector3d> normals(static_cast<size_t>(f.rows()));
  for (Eigen::Index k = 0; k < f.rows(); ++k) {
    normals[static_cast<size_t>(k)] = (point(f(k, 1)) - point(f(k, 0))).cross(point(f(k, 2)) - point(f(k, 0)));
  }
  // Each edge as (low, high, face); sorted, an interior edge's two faces sit side by side.
  std::vector<std::tuple<int32_t, int32_t, int64_t>> halfEdges;
  halfEdges.reserve(static_cast<size_t>(3 * f.rows()));
  for (Eigen::Index k = 0; k < f.rows(); ++k) {
    for (int c = 0; c < 3; ++c) {
      const int32_t a = f(k, c), b = f(k, (c + 1) % 3);
      halfEdges.emplace_back(std::min(a, b), std::max(a, b), k);
    }
  }
  std::sort(halfEdges.begin(), halfEdges.end());
  const double cosAngle = std::cos(settings.angleDeg * std::numbers::pi / 180.0);
  std::vector<std::array<int32_t, 2>> creases;
  for (size_t i = 0; i + 1 < halfEdges.size(); ++i) {
    const auto& [a, b, f1] = halfEdges[i];
    const auto& [a2, b2, f2] = halfEdges[i + 1];
    if (a != a2 || b != b2) continue;
    const Eigen::Vector3d& n1 = normals[static_cast<size_t>(f1)];
    const Eigen::Vector3d& n2 = normals[static_cast<size_t>(f2)];
    if (n1.dot(n2) <= cosAngle * n1.norm() * n2.norm()) creases.push_back({a, b});
    ++i;
  }

  FeatureCurves out;
  out.creaseEdges = static_cast<int64_t>(creases.size());
  if (creases.empty()) return out;
  const auto vertexCount = static_cast<size_t>(v.rows());
  std::vector<std::vector<int64_t>> incident(vertexCount);  // crease edges at each vertex, in edge order
  for (size_t e = 0; e < creases.size(); ++e) {
    for (int32_t end : creases[e]) incident[static_cast<size_t>(end)].push_back(static_cast<int64_t>(e));
  }
  auto other = [&](int64_t e, int32_t end) { return creases[e][0] == end ? creases[e][1] : creases[e][0]; };
  // Angle (degrees) at vertex p between its crease edges e1 and e2.
  auto angleAt = [&](int32_t p, int64_t e1, int64_t e2) {
    const Eigen::Vector3d d1 = point(other(e1, p)) - point(p), d2 = point(other(e2, p)) - point(p);
    return std::acos(std::clamp(d1.dot(d2) / (d1.norm() * d2.norm()), -1.0, 1.0)) * 180.0 / std::numbers::pi;
  };

  // Groups: creases connected through shared vertices (union-find on vertices, smallest id roots).
  std::vector<int32_t> parent(vertexCount);
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (const auto& [a, b] : creases) {
    const int32_t ra = find(a), rb = find(b);
    if (ra != rb) parent[std::max(ra, rb)] = std::min(ra, rb);
  }
  std::vector<double> length(vertexCount, 0.0);
  std::vector<char> isGroup(vertexCount, 0), needle(vertexCount, 0);
  for (const auto& [a, b] : creases) {
    const int32_t r = find(a);
    isGroup[r] = 1;
    length[r] += (point(b) - point(a)).norm();
  }
  for (size_t p = 0; p < vertexCount; ++p) {
    const auto& es = incident[p];
    for (size_t i = 0; i < es.size(); ++i) {
      for (size_t j = i + 1; j < es.size(); ++j) {
        if (angleAt(static_cast<int32_t>(p), es[i], es[j]) < settings.needleTurnDeg) needle[find(static_cast<int32_t>(p))] = 1;
      }
    }
  }
  std::vector<char> keepGroup(vertexCount, 0);
  for (size_t r = 0; r < vertexCount; ++r) {
    if (!isGroup[r]) continue;
    ++out.groups;
    if (needle[r]) {
      ++out.needleGroups;
    } else if (length[r] < settings.minLengthM) {
      ++out.shortGroups;
    } else {
      keepGroup[r] = 1;
      ++out.keptGroups;
    }
  }

  // Polylines over the kept edges, split at terminal vertices as Mesh_3 splits its own: a vertex
  // with other than two kept edges, or two meeting at an acute angle.
  std::vector<char> kept(creases.size(), 0), visited(creases.size(), 0);
  std::vector<std::vector<int64_t>> keptAt(vertexCount);
  for (size_t e = 0; e < creases.size(); ++e) {
    if (!keepGroup[find(creases[e][0])]) continue;
    kept[e] = 1;
    ++out.keptEdges;
    for (int32_t end : creases[e]) keptAt[static_cast<size_t>(end)].push_back(static_cast<int64_t>(e));
  }
  auto terminal = [&](int32_t p) {
    const auto& es = keptAt[static_cast<size_t>(p)];
    return es.size() != 2 || angleAt(p, es[0], es[1]) < 90.0;
  };
  // Walks from vertex `start` along edge `e` until a terminal vertex or back to `start`.
  auto walk = [&](int32_t start, int64_t e) {
    std::vector<Eigen::Vector3d> line{point(start)};
    int32_t at = start;
    while (true) {
      visited[e] = 1;
      at = other(e, at);
      line.push_back(point(at));
      if (at == start || terminal(at)) break;
      const auto& es = keptAt[static_cast<size_t>(at)];
      e = es[0] == e ? es[1] : es[0];
      if (visited[e]) break;
    }
    out.polylines.push_back(std::move(line));
  };
  for (size_t p = 0; p < vertexCount; ++p) {
    if (keptAt[p].empty() || !terminal(static_cast<int32_t>(p))) continue;
    for (int64_t e : keptAt[p]) {
      if (!visited[e]) walk(static_cast<int32_t>(p), e);
    }
  }
  for (size_t e = 0; e < creases.size(); ++e) {  // closed loops without a terminal vertex
    if (kept[e] && !visited[e]) walk(creases[e][0], static_cast<int64_t>(e));
  }
  return out;
}

}  // namespace brittle
