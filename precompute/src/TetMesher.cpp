// The only translation unit that instantiates CGAL Mesh_3 (see TetMesher.h).
#include "brittle/precompute/TetMesher.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Mesh_complex_3_in_triangulation_3.h>
#include <CGAL/Mesh_criteria_3.h>
#include <CGAL/Mesh_triangulation_3.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polyhedral_mesh_domain_with_features_3.h>
#include <CGAL/Random.h>
#include <CGAL/make_mesh_3.h>

#include <array>
#include <cmath>
#include <limits>
#include <unordered_map>
#include <vector>

#include "brittle/descriptors/MassProperties.h"
#include "brittle/precompute/TetMeshQuality.h"

namespace brittle {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Polyhedron = CGAL::Mesh_polyhedron_3<Kernel>::type;
using Domain = CGAL::Polyhedral_mesh_domain_with_features_3<Kernel>;
using Tr = CGAL::Mesh_triangulation_3<Domain, CGAL::Default, CGAL::Sequential_tag>::type;
using C3t3 = CGAL::Mesh_complex_3_in_triangulation_3<Tr, Domain::Corner_index, Domain::Curve_index>;
using Criteria = CGAL::Mesh_criteria_3<Tr>;

Polyhedron toPolyhedron(const TriangleMesh& surface) {
  std::vector<Kernel::Point_3> points;
  for (Eigen::Index v = 0; v < surface.vertices.rows(); ++v) {
    points.emplace_back(surface.vertices(v, 0), surface.vertices(v, 1), surface.vertices(v, 2));
  }
  std::vector<std::array<std::size_t, 3>> faces;
  for (Eigen::Index f = 0; f < surface.faces.rows(); ++f) {
    faces.push_back({static_cast<std::size_t>(surface.faces(f, 0)), static_cast<std::size_t>(surface.faces(f, 1)),
                     static_cast<std::size_t>(surface.faces(f, 2))});
  }
  Polyhedron poly;
  CGAL::Polygon_mesh_processing::polygon_soup_to_polygon_mesh(points, faces, poly);
  return poly;
}

// One Mesh_3 run at cell size h. Nodes are numbered in the order the complex's cells first
// reach them, which is deterministic for a fixed input and seed (no pointer ordering).
TetMesh meshOnce(const Polyhedron& poly, const TetMeshSettings& s, double h) {
  // CGAL's generator takes 32 bits: fold the high half in so every 64-bit seed counts.
  CGAL::get_default_random() = CGAL::Random(static_cast<unsigned int>(s.seed ^ (s.seed >> 32)));
  Domain domain(poly);
  if (s.detectSharpFeatures) domain.detect_features(s.featureAngleDeg);
  namespace params = CGAL::parameters;
  Criteria criteria(params::edge_size = h, params::facet_angle = s.facetAngleDeg, params::facet_size = h,
                    params::facet_distance = s.facetDistanceFraction * h,
                    params::cell_radius_edge_ratio = s.cellRadiusEdgeRatio, params::cell_size = h);
  // Mesh_3 gives perturbation and exudation a wall-clock budget equal to the refinement time
  // unless told otherwise, which makes the mesh depend on machine load. time_limit = 0 means
  // "no clock"; the perturber then stops once every dihedral angle reaches sliverBoundDeg, so the
  // result depends on the input, the settings and the seed only.
  C3t3 c3t3 = s.optimize
                  ? CGAL::make_mesh_3<C3t3>(
                        domain, criteria,
                        params::perturb(params::time_limit = 0.0, params::sliver_bound = s.sliverBoundDeg),
                        params::exude(params::time_limit = 0.0, params::sliver_bound = s.sliverBoundDeg))
                  : CGAL::make_mesh_3<C3t3>(domain, criteria, params::no_perturb(), params::no_exude());

  std::unordered_map<Tr::Vertex_handle, int32_t> index;
  std::vector<Eigen::Vector3d> nodes;
  std::vector<std::array<int32_t, 4>> tets;
  for (auto cell = c3t3.cells_in_complex_begin(); cell != c3t3.cells_in_complex_end(); ++cell) {
    std::array<int32_t, 4> tet;
    for (int k = 0; k < 4; ++k) {
      const auto vh = cell->vertex(k);
      auto [it, inserted] = index.emplace(vh, static_cast<int32_t>(nodes.size()));
      if (inserted) {
        const auto& p = vh->point();
        nodes.emplace_back(CGAL::to_double(p.x()), CGAL::to_double(p.y()), CGAL::to_double(p.z()));
      }
      tet[k] = it->second;
    }
    if (signedTetVolume(nodes[tet[0]], nodes[tet[1]], nodes[tet[2]], nodes[tet[3]]) < 0.0) std::swap(tet[2], tet[3]);
    tets.push_back(tet);
  }
  TetMesh mesh;
  mesh.nodes.resize(static_cast<Eigen::Index>(nodes.size()), 3);
  for (size_t i = 0; i < nodes.size(); ++i) mesh.nodes.row(static_cast<Eigen::Index>(i)) = nodes[i].transpose();
  mesh.tets.resize(static_cast<Eigen::Index>(tets.size()), 4);
  for (size_t t = 0; t < tets.size(); ++t) {
    mesh.tets.row(static_cast<Eigen::Index>(t)) << tets[t][0], tets[t][1], tets[t][2], tets[t][3];
  }
  return mesh;
}

}  // namespace

Result<TetMeshResult> tetrahedralize(const TriangleMesh& surface, const TetMeshSettings& s, ProgressSink* progress) {
  if (s.targetTets <= 0 && !(s.cellSizeM > 0.0)) {
    return makeError(ErrorCode::InvalidArgument, "tet meshing needs a target tet count or a cell size > 0");
  }
  const double volume = computeSurfaceMassProperties(surface, 1.0).volumeM3;
  if (!(volume > 0.0)) return makeError(ErrorCode::MeshingFailed, "surface encloses no volume");

  Polyhedron poly;
  try {
    poly = toPolyhedron(surface);
  } catch (const std::exception& e) {
    return makeError(ErrorCode::MeshingFailed, std::string("cannot build CGAL polyhedron: ") + e.what());
  }

  // Mesh_3 tets at cell size h average about 0.175 h³ (circumradius ~0.7 h, near-regular).
  // The size search runs refinement only (cheap); optimisation, which changes the count by a
  // few per cent, runs once at the chosen size.
  double h = s.targetTets > 0 ? std::cbrt(volume / (0.175 * static_cast<double>(s.targetTets))) : s.cellSizeM;
  const int attemptsAllowed = s.targetTets > 0 ? std::max(1, s.maxAttempts) : 0;
  TetMeshSettings search = s;
  search.optimize = false;
  TetMeshResult best;
  best.cellSizeM = h;
  double bestMiss = std::numeric_limits<double>::infinity();
  try {
    for (int attempt = 0; attempt < attemptsAllowed; ++attempt) {
      if (isInterrupted(progress)) return makeError(ErrorCode::Cancelled, "tet meshing cancelled");
      reportProgress(progress, "tet meshing: sizing", static_cast<double>(attempt) / attemptsAllowed);
      const double count = static_cast<double>(meshOnce(poly, search, h).tets.rows());
      best.attempts = attempt + 1;
      if (count == 0) break;
      const double miss = std::abs(count / static_cast<double>(s.targetTets) - 1.0);
      if (miss < bestMiss) bestMiss = miss, best.cellSizeM = h;
      if (miss <= s.countTolerance) break;
      h *= std::cbrt(count / static_cast<double>(s.targetTets));
    }
    if (isInterrupted(progress)) return makeError(ErrorCode::Cancelled, "tet meshing cancelled");
    reportProgress(progress, s.optimize ? "tet meshing: refine + optimise" : "tet meshing: refine", 0.0);
    best.mesh = meshOnce(poly, s, best.cellSizeM);
    ++best.attempts;
  } catch (const std::exception& e) {
    return makeError(ErrorCode::MeshingFailed, std::string("CGAL Mesh_3 failed: ") + e.what());
  }
  if (best.mesh.tets.rows() == 0) {
    return makeError(ErrorCode::MeshingFailed,
                     "CGAL Mesh_3 produced no tetrahedra at cell size " + std::to_string(best.cellSizeM) + " m");
  }
  reportProgress(progress, "tet meshing", 1.0);

  best.mesh = compactNodes(best.mesh);
  if (const int64_t pieces = countFaceConnectedComponents(best.mesh); pieces != 1) {
    return makeError(ErrorCode::MeshingFailed,
                     "Mesh_3 output is not one solid: " + std::to_string(pieces) +
                         " face-connected pieces at cell size " + std::to_string(best.cellSizeM) +
                         " m (a part thinner than the cell size? try more tets)");
  }
  best.surfaceFaces = boundaryFaces(best.mesh);
  best.quality = computeMeshQuality(best.mesh);
  if (!(best.quality.minTetVolumeM3 > 0.0)) {
    return makeError(ErrorCode::MeshingFailed, "Mesh_3 output has a tetrahedron of non-positive volume");
  }
  return best;
}

}  // namespace brittle
