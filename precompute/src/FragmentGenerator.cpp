#include "brittle/precompute/FragmentGenerator.h"

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/clip.h>
#include <CGAL/Polygon_mesh_processing/connected_components.h>
#include <CGAL/Polygon_mesh_processing/triangulate_faces.h>
#include <CGAL/Side_of_triangle_mesh.h>
#include <CGAL/Surface_mesh.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <numeric>
#include <optional>
#include <random>

#include "brittle/descriptors/MassProperties.h"
#include "brittle/precompute/MeshValidation.h"
#include "Support.h"

namespace brittle {
namespace {

// Exact constructions: the points a clip creates are exact (lazy rationals), so the next clip of
// the same fragment decides on exact geometry. With Exact_predicates_inexact_constructions_kernel
// the rounded points of one clip made the next clip's corefinement loop without end on Voronoi
// cells of the sphere (measured: over 100 minutes on one cell).
using Kernel = CGAL::Exact_predicates_exact_constructions_kernel;
using Point = Kernel::Point_3;
using Mesh = CGAL::Surface_mesh<Point>;
namespace PMP = CGAL::Polygon_mesh_processing;

// A point rounded to doubles from its exact value. Converting the lazy number's interval instead
// would depend on how far earlier predicates had refined it, which differs from call to call.
Eigen::Vector3d toEigen(const Point& p) {
  return {CGAL::to_double(CGAL::exact(p.x())), CGAL::to_double(CGAL::exact(p.y())),
          CGAL::to_double(CGAL::exact(p.z()))};
}

Error invalid(const std::string& message) { return makeError(ErrorCode::InvalidArgument, message); }
Error emptyFragment() { return invalid("empty fragment"); }

// The solid as a CGAL mesh, checking what the clip relies on.
Result<Mesh> toCgal(const TriangleMesh& m) {
  if (m.vertices.rows() == 0 || m.faces.rows() == 0) return invalid("the solid to clip is empty");
  if (!m.vertices.allFinite()) return invalid("the solid to clip has non-finite coordinates");
  if (m.faces.minCoeff() < 0 || m.faces.maxCoeff() >= m.vertices.rows()) {
    return invalid("the solid to clip has face indices out of range");
  }
  Mesh out;
  std::vector<Mesh::Vertex_index> v;
  v.reserve(static_cast<size_t>(m.vertices.rows()));
  for (Eigen::Index i = 0; i < m.vertices.rows(); ++i) {
    v.push_back(out.add_vertex(Point(m.vertices(i, 0), m.vertices(i, 1), m.vertices(i, 2))));
  }
  for (Eigen::Index f = 0; f < m.faces.rows(); ++f) {
    const auto a = v[static_cast<size_t>(m.faces(f, 0))], b = v[static_cast<size_t>(m.faces(f, 1))],
               c = v[static_cast<size_t>(m.faces(f, 2))];
    if (a == b || b == c || c == a || out.add_face(a, b, c) == Mesh::null_face()) {
      return invalid("the solid to clip is not a manifold, consistently oriented mesh (face " + std::to_string(f) +
                     ")");
    }
  }
  if (!CGAL::is_closed(out)) return invalid("the solid to clip is not closed");
  return out;
}

// 6 × the signed volume the face encloses with the origin.
double sixVolume(const Mesh& mesh, Mesh::Face_index f) {
  Eigen::Vector3d p[3];
  int c = 0;
  for (auto v : mesh.vertices_around_face(mesh.halfedge(f))) p[c++] = toEigen(mesh.point(v));
  return p[0].dot(p[1].cross(p[2]));
}

// Vertices in lexicographic (x, y, z) order, each face rotated to start at its smallest index
// (orientation kept), faces in lexicographic order: the arrays then depend on the solid alone, not
// on the order in which CGAL happened to create its elements.
TriangleMesh canonicalOrder(const TriangleMesh& m) {
  const auto n = static_cast<int>(m.vertices.rows());
  std::vector<int> order(static_cast<size_t>(n));
  std::iota(order.begin(), order.end(), 0);
  auto row = [&](int i) { return std::array<double, 3>{m.vertices(i, 0), m.vertices(i, 1), m.vertices(i, 2)}; };
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return row(a) < row(b); });
  std::vector<int> newIndex(static_cast<size_t>(n));
  TriangleMesh out;
  out.vertices.resize(n, 3);
  for (int i = 0; i < n; ++i) {
    newIndex[static_cast<size_t>(order[static_cast<size_t>(i)])] = i;
    out.vertices.row(i) = m.vertices.row(order[static_cast<size_t>(i)]);
  }
  std::vector<std::array<int, 3>> faces;
  faces.reserve(static_cast<size_t>(m.faces.rows()));
  for (Eigen::Index f = 0; f < m.faces.rows(); ++f) {
    std::array<int, 3> t{newIndex[static_cast<size_t>(m.faces(f, 0))], newIndex[static_cast<size_t>(m.faces(f, 1))],
                         newIndex[static_cast<size_t>(m.faces(f, 2))]};
    std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());
    faces.push_back(t);
  }
  std::sort(faces.begin(), faces.end());
  out.faces.resize(static_cast<Eigen::Index>(faces.size()), 3);
  for (size_t f = 0; f < faces.size(); ++f) {
    out.faces.row(static_cast<Eigen::Index>(f)) << faces[f][0], faces[f][1], faces[f][2];
  }
  return out;
}

// The faces of `mesh` (garbage collected, triangles) whose component passes `keep`, with only the
// vertices they use, in canonical order.
template <typename Keep>
TriangleMesh fromCgal(const Mesh& mesh, Keep keep) {
  std::vector<int> index(mesh.number_of_vertices(), -1);
  Eigen::Index faceCount = 0;
  for (auto f : mesh.faces()) {
    if (!keep(f)) continue;
    ++faceCount;
    for (auto v : mesh.vertices_around_face(mesh.halfedge(f))) index[static_cast<size_t>(v)] = 0;
  }
  TriangleMesh out;
  int used = 0;
  for (int& i : index) i = i < 0 ? -1 : used++;
  out.vertices.resize(used, 3);
  for (auto v : mesh.vertices()) {
    const int i = index[static_cast<size_t>(v)];
    if (i < 0) continue;
    out.vertices.row(i) = toEigen(mesh.point(v)).transpose();
  }
  out.faces.resize(faceCount, 3);
  Eigen::Index row = 0;
  for (auto f : mesh.faces()) {
    if (!keep(f)) continue;
    int c = 0;
    for (auto v : mesh.vertices_around_face(mesh.halfedge(f))) out.faces(row, c++) = index[static_cast<size_t>(v)];
    ++row;
  }
  return canonicalOrder(out);
}

// Where the clippers are built: the centre and diagonal of the input solid's bounding box, from its
// double coordinates. Every fragment lies inside the solid.
struct ClipFrame {
  Eigen::Vector3d centre;
  double diagonal = 0.0;
};

ClipFrame clipFrame(const TriangleMesh& solid) {
  const Eigen::Vector3d lo = solid.vertices.colwise().minCoeff(), hi = solid.vertices.colwise().maxCoeff();
  return {0.5 * (lo + hi), std::max((hi - lo).norm(), 1e-300)};
}

// The closed clipper of one plane: a tetrahedron whose base is a single triangle lying exactly in
// the plane (its corners are exact projections), ten diagonals across, and whose apex is ten
// diagonals down on the kept side, so it holds the whole kept part of anything in the frame.
//
// PMP::clip(mesh, plane) builds its clipper as the part of a bounding box below the plane, with the
// cap polygon triangulated. Two things follow from that and both are avoided here: the cap's
// diagonals cross the mesh and leave extra vertices on the cut (needles, and zero-area faces after
// rounding), and the box comes from the lazy points' interval approximations, whose width depends
// on which exact evaluations earlier predicates happened to trigger — an order that follows heap
// addresses — so those vertices moved by an ulp from run to run (1 call in ~400 on the sphere).
// With one triangle in the plane the cut vertices are the mesh's edges crossing the plane, nothing
// else: a function of the mesh and the plane alone.
Mesh planeClipper(const Kernel::Plane_3& plane, const Plane& p, const ClipFrame& frame) {
  const Eigen::Vector3d n = p.normal.normalized();
  const Eigen::Vector3d u = n.unitOrthogonal(), v = n.cross(u);  // (u, v, n) right-handed
  const double radius = 10.0 * frame.diagonal;
  Mesh clipper;
  std::array<Mesh::Vertex_index, 3> base;
  for (int k = 0; k < 3; ++k) {
    const double angle = 2.0 * std::numbers::pi * k / 3.0;
    const Eigen::Vector3d q = frame.centre + radius * (std::cos(angle) * u + std::sin(angle) * v);
    base[static_cast<size_t>(k)] = clipper.add_vertex(plane.projection(Point(q.x(), q.y(), q.z())));
  }
  const Eigen::Vector3d a = frame.centre - radius * n;
  const auto apex = clipper.add_vertex(Point(a.x(), a.y(), a.z()));
  clipper.add_face(base[0], base[1], base[2]);  // counter-clockwise about n: faces the cut-away side
  clipper.add_face(base[1], base[0], apex);
  clipper.add_face(base[2], base[1], apex);
  clipper.add_face(base[0], base[2], apex);
  return clipper;
}

// Clips `mesh` in place by the planes, then converts the kept pieces.
Result<TriangleMesh> clipMesh(Mesh& mesh, const ClipFrame& frame, const std::vector<Plane>& planes,
                              ClipComponents components) {
  for (const Plane& p : planes) {
    // CGAL keeps the negative side of a·x + b·y + c·z + d = 0, i.e. normal·x − offset ≤ 0.
    const Kernel::Plane_3 plane(p.normal.x(), p.normal.y(), p.normal.z(), -p.offset);
    // Exact classification of the vertices: the solid lies in the convex hull of its vertices, so
    // a plane that no vertex exceeds cannot cut it, and one that no vertex is inside of empties it.
    bool anyOutside = false, anyInside = false;
    for (auto v : mesh.vertices()) {
      const CGAL::Oriented_side side = plane.oriented_side(mesh.point(v));
      anyOutside = anyOutside || side == CGAL::ON_POSITIVE_SIDE;
      anyInside = anyInside || side == CGAL::ON_NEGATIVE_SIDE;
    }
    if (!anyOutside) continue;
    if (!anyInside) return emptyFragment();
    Mesh clipper = planeClipper(plane, p, frame);
    if (!PMP::clip(mesh, clipper, CGAL::parameters::clip_volume(true), CGAL::parameters::default_values())) {
      return makeError(ErrorCode::MeshingFailed, "CGAL clip gave a non-manifold result (self-intersecting input?)");
    }
    if (mesh.number_of_faces() == 0) return emptyFragment();
  }
  mesh.collect_garbage();
  if (!CGAL::is_triangle_mesh(mesh)) PMP::triangulate_faces(mesh);

  auto componentOf = mesh.add_property_map<Mesh::Face_index, std::size_t>("f:brittle_component", 0).first;
  const std::size_t pieces = PMP::connected_components(mesh, componentOf);
  std::vector<double> volume(pieces, 0.0);
  for (auto f : mesh.faces()) volume[componentOf[f]] += sixVolume(mesh, f) / 6.0;
  const double total = std::accumulate(volume.begin(), volume.end(), 0.0);
  if (!(total > 0.0)) return emptyFragment();
  if (pieces == 1 || components == ClipComponents::KeepAll) return fromCgal(mesh, [](Mesh::Face_index) { return true; });
  if (components == ClipComponents::RequireOne) {
    return makeError(ErrorCode::NonManifold, "the clipped solid falls apart into " + std::to_string(pieces) + " pieces");
  }
  const std::size_t largest = static_cast<std::size_t>(std::max_element(volume.begin(), volume.end()) - volume.begin());
  return fromCgal(mesh, [&](Mesh::Face_index f) { return componentOf[f] == largest; });
}

Status checkPlanes(const std::vector<Plane>& planes) {
  for (size_t i = 0; i < planes.size(); ++i) {
    const Plane& p = planes[i];
    if (!p.normal.allFinite() || !std::isfinite(p.offset) || p.normal.squaredNorm() == 0.0) {
      return invalid("clip plane " + std::to_string(i) + " has a non-finite or zero normal or offset");
    }
  }
  return Ok{};
}

Result<std::vector<Plane>> bisectors(const std::vector<Eigen::Vector3d>& sites, int cell) {
  if (cell < 0 || cell >= static_cast<int>(sites.size())) {
    return invalid("Voronoi cell " + std::to_string(cell) + " of " + std::to_string(sites.size()) + " sites");
  }
  const Eigen::Vector3d& s = sites[static_cast<size_t>(cell)];
  std::vector<size_t> order;
  for (size_t j = 0; j < sites.size(); ++j) {
    if (!sites[j].allFinite()) return invalid("Voronoi site " + std::to_string(j) + " is not finite");
    if (static_cast<int>(j) == cell) continue;
    if (sites[j] == s) return invalid("Voronoi sites " + std::to_string(cell) + " and " + std::to_string(j) + " coincide");
    order.push_back(j);
  }
  // Nearest sites first: their bisectors cut most, and the far ones then miss and are skipped.
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return (sites[a] - s).squaredNorm() < (sites[b] - s).squaredNorm(); });
  std::vector<Plane> planes;
  for (size_t j : order) {
    // |x − s|² ≤ |x − s_j|²  ⇔  (s_j − s)·x ≤ (s_j − s)·(s + s_j)/2. The neighbour's plane is
    // the exact negation of this one (IEEE negation commutes with the rounding), so adjacent
    // cells share their face.
    const Eigen::Vector3d n = sites[j] - s;
    planes.push_back({n, n.dot(0.5 * (s + sites[j]))});
  }
  return planes;
}

using detail::unit;

// An index uniform in [0, n), n ≥ 1.
int uniformIndex(std::mt19937_64& rng, int n) { return std::min(n - 1, static_cast<int>(unit(rng) * n)); }

}  // namespace

Result<TriangleMesh> clipByPlanes(const TriangleMesh& solid, const std::vector<Plane>& planes,
                                  ClipComponents components) {
  if (Status st = checkPlanes(planes); !st) return st.error();
  try {
    auto mesh = toCgal(solid);
    if (!mesh) return mesh.error();
    return clipMesh(mesh.value(), clipFrame(solid), planes, components);
  } catch (const std::exception& e) {
    return makeError(ErrorCode::MeshingFailed, std::string("CGAL clip failed: ") + e.what());
  }
}

Result<TriangleMesh> voronoiCell(const TriangleMesh& solid, const std::vector<Eigen::Vector3d>& sites, int cell,
                                 ClipComponents components) {
  auto planes = bisectors(sites, cell);
  if (!planes) return planes.error();
  return clipByPlanes(solid, planes.value(), components);
}

Result<std::vector<TriangleMesh>> voronoiCells(const TriangleMesh& solid, const std::vector<Eigen::Vector3d>& sites) {
  std::vector<TriangleMesh> cells;
  for (int c = 0; c < static_cast<int>(sites.size()); ++c) {
    auto cell = voronoiCell(solid, sites, c, ClipComponents::KeepAll);
    if (!cell) return Error{cell.error().code, "Voronoi cell " + std::to_string(c) + ": " + cell.error().message};
    cells.push_back(std::move(cell).value());
  }
  return cells;
}

Status validateFragmentSettings(const FragmentSettings& s) {
  if (s.minCells < 2 || s.maxCells < s.minCells || s.maxCells > 256) {
    return invalid("FragmentSettings: minCells and maxCells need 2 ≤ minCells ≤ maxCells ≤ 256");
  }
  if (!(s.planeCutFraction >= 0.0 && s.planeCutFraction <= 1.0)) {
    return invalid("FragmentSettings: planeCutFraction must be in [0, 1]");
  }
  if (!(s.minVolumeFraction >= 0.0 && s.minVolumeFraction < 1.0)) {
    return invalid("FragmentSettings: minVolumeFraction must be in [0, 1)");
  }
  if (s.maxAttempts < 1) return invalid("FragmentSettings: maxAttempts must be ≥ 1");
  return Ok{};
}

Result<TriangleMesh> generateFragment(const TriangleMesh& solid, const FragmentSettings& settings, uint64_t seed,
                                      std::string* cutKind) {
  if (Status st = validateFragmentSettings(settings); !st) return st.error();
  try {
    auto built = toCgal(solid);
    if (!built) return built.error();
    const Mesh& mesh = built.value();
    const double volume = computeSurfaceMassProperties(solid, 1.0).volumeM3;
    if (!(volume > 0.0)) return invalid("the solid to fragment has no positive volume");
    const CGAL::Side_of_triangle_mesh<Mesh, Kernel> inside(mesh);
    const ClipFrame frame = clipFrame(solid);
    const Eigen::Vector3d lo = solid.vertices.colwise().minCoeff(), hi = solid.vertices.colwise().maxCoeff();

    std::mt19937_64 rng(seed);
    auto interiorPoint = [&]() -> std::optional<Eigen::Vector3d> {
      for (int tries = 0; tries < 10000; ++tries) {
        // One draw per statement: the evaluation order of function arguments is unspecified.
        const double ux = unit(rng);
        const double uy = unit(rng);
        const double uz = unit(rng);
        const Eigen::Vector3d p = lo + Eigen::Vector3d(ux, uy, uz).cwiseProduct(hi - lo);
        if (inside(Point(p.x(), p.y(), p.z())) == CGAL::ON_BOUNDED_SIDE) return p;
      }
      return std::nullopt;
    };
    const Error noInterior = invalid("no point inside the solid in 10000 tries (is it flat?)");

    std::string reason = "no draw";
    for (int attempt = 0; attempt < settings.maxAttempts; ++attempt) {
      const bool byPlanes = unit(rng) < settings.planeCutFraction;
      std::vector<Plane> planes;
      if (byPlanes) {
        const int count = 1 + uniformIndex(rng, 3);
        for (int c = 0; c < count; ++c) {
          const auto through = interiorPoint();
          if (!through) return noInterior;
          // A uniform direction (Archimedes: z and the azimuth uniform).
          const double z = 2.0 * unit(rng) - 1.0;
          const double phi = 2.0 * std::numbers::pi * unit(rng);
          const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
          const Eigen::Vector3d n(r * std::cos(phi), r * std::sin(phi), z);
          planes.push_back({n, n.dot(*through)});
        }
      } else {
        const int cells = settings.minCells + uniformIndex(rng, settings.maxCells - settings.minCells + 1);
        std::vector<Eigen::Vector3d> sites;
        for (int c = 0; c < cells; ++c) {
          const auto site = interiorPoint();
          if (!site) return noInterior;
          sites.push_back(*site);
        }
        auto cellPlanes = bisectors(sites, uniformIndex(rng, cells));
        if (!cellPlanes) {  // coinciding sites: draw again
          reason = cellPlanes.error().message;
          continue;
        }
        planes = std::move(cellPlanes).value();
      }
      Mesh work = mesh;
      auto piece = clipMesh(work, frame, planes, ClipComponents::RequireOne);
      if (!piece) {
        reason = piece.error().message;
        continue;
      }
      const double fraction = computeSurfaceMassProperties(piece.value(), 1.0).volumeM3 / volume;
      if (fraction < settings.minVolumeFraction) {
        reason = "a fragment of " + std::to_string(fraction) + " of the volume, below minVolumeFraction";
        continue;
      }
      if (Status valid = validateSurfaceMesh(piece.value()); !valid) {
        reason = valid.error().message;
        continue;
      }
      if (cutKind) *cutKind = byPlanes ? "planes" : "voronoi";
      return piece;
    }
    return makeError(ErrorCode::MeshingFailed, "no acceptable fragment in " + std::to_string(settings.maxAttempts) +
                                                   " draws; last: " + reason);
  } catch (const std::exception& e) {
    return makeError(ErrorCode::MeshingFailed, std::string("fragment generation failed: ") + e.what());
  }
}

}  // namespace brittle
