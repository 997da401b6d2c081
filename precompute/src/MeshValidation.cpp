#include "brittle/precompute/MeshValidation.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>

#include <algorithm>
#include <array>
#include <numeric>
#include <unordered_map>
#include <vector>

#include "brittle/descriptors/MassProperties.h"

namespace brittle {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using SurfaceMesh = CGAL::Surface_mesh<Kernel::Point_3>;

struct UnionFind {
  std::vector<int32_t> parent;
  explicit UnionFind(size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  int32_t find(int32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void unite(int32_t a, int32_t b) {
    a = find(a);
    b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);  // smallest id wins: deterministic
  }
};

uint64_t edgeKey(int32_t a, int32_t b) {
  return (static_cast<uint64_t>(static_cast<uint32_t>(a)) << 32) | static_cast<uint32_t>(b);
}

std::string where(const char* what, size_t count, const char* unit, const std::string& first) {
  return std::string(what) + ": " + std::to_string(count) + " " + unit + ", first at " + first;
}

}  // namespace

Status validateSurfaceMesh(const TriangleMesh& mesh) {
  const auto nv = mesh.vertices.rows();
  const auto nf = mesh.faces.rows();
  if (nv == 0 || nf == 0) return makeError(ErrorCode::EmptyMesh, "empty mesh: no vertices or faces");
  for (Eigen::Index v = 0; v < nv; ++v) {
    if (!mesh.vertices.row(v).allFinite()) {
      return makeError(ErrorCode::NonFiniteValue, "non-finite coordinate at vertex " + std::to_string(v));
    }
  }
  for (Eigen::Index f = 0; f < nf; ++f) {
    for (int k = 0; k < 3; ++k) {
      if (mesh.faces(f, k) < 0 || mesh.faces(f, k) >= nv) {
        return makeError(ErrorCode::ParseError, "face " + std::to_string(f) + " refers to vertex " +
                                                    std::to_string(mesh.faces(f, k)) + " of " +
                                                    std::to_string(nv));
      }
    }
  }

  // Degenerate faces: repeated corners, or an area that is zero at the precision of the model.
  const double diag = (mesh.vertices.colwise().maxCoeff() - mesh.vertices.colwise().minCoeff()).norm();
  const double minArea = 1e-14 * diag * diag;
  size_t degenerate = 0;
  Eigen::Index firstDegenerate = -1;
  for (Eigen::Index f = 0; f < nf; ++f) {
    const auto a = mesh.faces(f, 0), b = mesh.faces(f, 1), c = mesh.faces(f, 2);
    const Eigen::Vector3d pa = mesh.vertices.row(a), pb = mesh.vertices.row(b), pc = mesh.vertices.row(c);
    if (a == b || b == c || a == c || 0.5 * (pb - pa).cross(pc - pa).norm() <= minArea) {
      if (degenerate++ == 0) firstDegenerate = f;
    }
  }
  if (degenerate > 0) {
    return makeError(ErrorCode::DegenerateFace,
                     where("degenerate faces", degenerate, "zero-area faces", "face " + std::to_string(firstDegenerate)));
  }

  // Edge use: undirected counts find open and non-manifold edges; directed counts find
  // inconsistent orientation (a manifold, consistently oriented edge is used once each way).
  std::unordered_map<uint64_t, int> undirected, directed;
  undirected.reserve(static_cast<size_t>(3 * nf));
  directed.reserve(static_cast<size_t>(3 * nf));
  for (Eigen::Index f = 0; f < nf; ++f) {
    for (int k = 0; k < 3; ++k) {
      const int32_t a = mesh.faces(f, k), b = mesh.faces(f, (k + 1) % 3);
      ++undirected[edgeKey(std::min(a, b), std::max(a, b))];
      ++directed[edgeKey(a, b)];
    }
  }
  size_t boundary = 0, overused = 0, flipped = 0;
  int32_t firstBoundary = INT32_MAX, firstOverused = INT32_MAX, firstFlipped = INT32_MAX;
  for (const auto& [key, count] : undirected) {
    const auto lo = static_cast<int32_t>(key >> 32);
    if (count == 1) ++boundary, firstBoundary = std::min(firstBoundary, lo);
    if (count > 2) ++overused, firstOverused = std::min(firstOverused, lo);
  }
  if (boundary > 0) {
    return makeError(ErrorCode::OpenMesh,
                     where("open mesh", boundary, "boundary edges", "vertex " + std::to_string(firstBoundary)));
  }
  if (overused > 0) {
    return makeError(ErrorCode::NonManifold,
                     where("non-manifold mesh", overused, "edges with more than two faces",
                           "vertex " + std::to_string(firstOverused)));
  }
  for (const auto& [key, count] : directed) {
    if (count > 1) ++flipped, firstFlipped = std::min(firstFlipped, static_cast<int32_t>(key >> 32));
  }
  if (flipped > 0) {
    return makeError(ErrorCode::InconsistentOrientation,
                     where("inconsistently oriented mesh", flipped, "edges traversed twice in the same direction",
                           "vertex " + std::to_string(firstFlipped)));
  }

  // Non-manifold vertices: the faces around a vertex must form a single fan. Faces around v are
  // joined when they share an edge through v; more groups than one means a pinched vertex.
  std::vector<std::vector<int32_t>> facesOfVertex(static_cast<size_t>(nv));
  for (Eigen::Index f = 0; f < nf; ++f) {
    for (int k = 0; k < 3; ++k) facesOfVertex[mesh.faces(f, k)].push_back(static_cast<int32_t>(f));
  }
  size_t pinched = 0;
  Eigen::Index firstPinched = -1;
  for (Eigen::Index v = 0; v < nv; ++v) {
    const auto& fan = facesOfVertex[v];
    if (fan.empty()) continue;
    // Around a manifold vertex each neighbour vertex is shared by exactly two faces of the fan,
    // which chains the faces into one cycle; count the cycle's components.
    std::unordered_map<int32_t, int32_t> firstFaceOfNeighbour;
    UnionFind groups(fan.size());
    for (size_t i = 0; i < fan.size(); ++i) {
      for (int k = 0; k < 3; ++k) {
        const int32_t w = mesh.faces(fan[i], k);
        if (w == v) continue;
        auto [it, inserted] = firstFaceOfNeighbour.emplace(w, static_cast<int32_t>(i));
        if (!inserted) groups.unite(it->second, static_cast<int32_t>(i));
      }
    }
    size_t roots = 0;
    for (size_t i = 0; i < fan.size(); ++i) roots += groups.find(static_cast<int32_t>(i)) == static_cast<int32_t>(i);
    if (roots > 1 && pinched++ == 0) firstPinched = v;
  }
  if (pinched > 0) {
    return makeError(ErrorCode::NonManifold, where("non-manifold mesh", pinched, "pinched vertices",
                                                   "vertex " + std::to_string(firstPinched)));
  }

  // One body: all faces connected.
  UnionFind components(static_cast<size_t>(nv));
  for (Eigen::Index f = 0; f < nf; ++f) {
    components.unite(mesh.faces(f, 0), mesh.faces(f, 1));
    components.unite(mesh.faces(f, 0), mesh.faces(f, 2));
  }
  std::vector<int32_t> roots;
  for (Eigen::Index v = 0; v < nv; ++v) {
    if (!facesOfVertex[v].empty()) roots.push_back(components.find(static_cast<int32_t>(v)));
  }
  std::sort(roots.begin(), roots.end());
  roots.erase(std::unique(roots.begin(), roots.end()), roots.end());
  if (roots.size() > 1) {
    return makeError(ErrorCode::NonManifold,
                     "mesh has " + std::to_string(roots.size()) +
                         " separate components (one object must be one body), second starts at vertex " +
                         std::to_string(roots[1]));
  }

  // Self-intersections, with CGAL's exact predicates.
  std::vector<Kernel::Point_3> points;
  points.reserve(static_cast<size_t>(nv));
  for (Eigen::Index v = 0; v < nv; ++v) points.emplace_back(mesh.vertices(v, 0), mesh.vertices(v, 1), mesh.vertices(v, 2));
  std::vector<std::array<std::size_t, 3>> polygons;
  polygons.reserve(static_cast<size_t>(nf));
  for (Eigen::Index f = 0; f < nf; ++f) {
    polygons.push_back({static_cast<std::size_t>(mesh.faces(f, 0)), static_cast<std::size_t>(mesh.faces(f, 1)),
                        static_cast<std::size_t>(mesh.faces(f, 2))});
  }
  SurfaceMesh surface;
  CGAL::Polygon_mesh_processing::polygon_soup_to_polygon_mesh(points, polygons, surface);
  if (CGAL::Polygon_mesh_processing::does_self_intersect(surface)) {
    std::vector<std::pair<SurfaceMesh::Face_index, SurfaceMesh::Face_index>> pairs;
    CGAL::Polygon_mesh_processing::self_intersections(surface, std::back_inserter(pairs));
    size_t firstA = SIZE_MAX, firstB = SIZE_MAX;
    for (const auto& [fa, fb] : pairs) {
      const auto a = std::min<size_t>(fa.idx(), fb.idx()), b = std::max<size_t>(fa.idx(), fb.idx());
      if (a < firstA || (a == firstA && b < firstB)) firstA = a, firstB = b;
    }
    return makeError(ErrorCode::SelfIntersection,
                     where("self-intersecting mesh", pairs.size(), "intersecting face pairs",
                           "faces " + std::to_string(firstA) + " and " + std::to_string(firstB)));
  }

  const double volume = computeSurfaceMassProperties(mesh, 1.0).volumeM3;
  if (!(volume > 0.0)) {
    return makeError(ErrorCode::InwardFacing, "inward-facing mesh: enclosed volume is " +
                                                  std::to_string(volume) + " m^3 (faces must be "
                                                  "counter-clockwise seen from outside)");
  }
  return Ok{};
}

}  // namespace brittle
