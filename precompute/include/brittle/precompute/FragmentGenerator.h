// FragmentGenerator.h — fragments cut from a solid with exact geometric predicates: Voronoi cells
// of random sites and random plane cuts, both computed as intersections of the solid with
// half-spaces by CGAL::Polygon_mesh_processing::clip (corefinement on a Surface_mesh with
// Exact_predicates_exact_constructions_kernel: every decision is exact and every cut point stays
// exact through later clips; the result is rounded to doubles once, from the exact values).
// Inexact constructions were tried first: rounded cut points fed to the next clip made CGAL's
// corefinement loop without end on a Voronoi cell of the sphere.
//
// This is the only translation unit that instantiates CGAL's corefinement (heavy templates); its
// interface is flat arrays (MeshTypes.h). Output arrays are in a canonical order (vertices
// lexicographic, faces rotated to their smallest index and sorted), so a fragment's arrays depend
// on its geometry alone.
//
// Cost per generateFragment call with the default FragmentSettings: the "fragment-cut" row of
// `brittle bench search` (docs/results/data/descriptor_cost.csv) and docs/results/fragment-database.md.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "brittle/core/MeshTypes.h"
#include "brittle/core/Result.h"

namespace brittle {

/// The closed half-space normal·x ≤ offset (x in m; offset in m times |normal|, which need not be
/// 1). The coefficients are used as given, exactly: no normalisation.
struct Plane {
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  double offset = 0.0;
};

/// What a clip does when the intersection falls apart into several pieces (a non-convex solid
/// cut by planes). Pieces are face-connected components; the choice is the caller's because a
/// fragment must be one body while a partition must keep everything.
enum class ClipComponents {
  RequireOne,   ///< several pieces are an error (NonManifold, with the count)
  KeepLargest,  ///< keep the piece of largest volume (ties: the first in CGAL's face order)
  KeepAll,      ///< return every piece in one mesh (then it is not one body)
};

/// Intersection of a solid with the half-spaces, clipping by one plane after the other. A plane
/// that every vertex satisfies (exact test) is skipped; the others go through
/// PMP::clip(clip_volume = true).
/// Input: solid is closed, outward, manifold and free of self-intersections (e.g. it passes
/// validateSurfaceMesh); planes in the solid's frame.
/// Output: closed, outward triangle mesh without unused vertices, in canonical order (above).
/// Rounding of new points can, in near-degenerate configurations, leave a zero-area face or a tiny
/// self-intersection: validate the result where it matters (generateFragment does).
/// Errors: InvalidArgument (a non-finite or zero plane normal; a solid with out-of-range indices,
/// non-finite coordinates, or that is not a closed manifold triangle mesh; an empty intersection:
/// "empty fragment"), NonManifold (several pieces under RequireOne), MeshingFailed (CGAL's clip
/// failed or threw).
Result<TriangleMesh> clipByPlanes(const TriangleMesh& solid, const std::vector<Plane>& planes,
                                  ClipComponents components = ClipComponents::RequireOne);

/// The Voronoi cell of sites[cell] within the solid: the solid clipped by the bisector planes
/// between that site and every other one (nearest sites first, which makes most far bisectors
/// miss and be skipped). sites: #S points (m), in the solid's frame, pairwise distinct.
/// Errors: those of clipByPlanes; InvalidArgument for a cell index out of range or two equal sites.
Result<TriangleMesh> voronoiCell(const TriangleMesh& solid, const std::vector<Eigen::Vector3d>& sites, int cell,
                                 ClipComponents components = ClipComponents::RequireOne);

/// Every Voronoi cell of the sites within the solid, in site order: a partition of the solid
/// whose volumes add up to the solid's. Each cell keeps all its pieces (ClipComponents::KeepAll),
/// since a cell of a non-convex solid can fall apart. Errors: those of voronoiCell, with the cell
/// index; a site whose cell misses the solid gives InvalidArgument "empty fragment".
Result<std::vector<TriangleMesh>> voronoiCells(const TriangleMesh& solid, const std::vector<Eigen::Vector3d>& sites);

struct FragmentSettings {
  int minCells = 3;                 ///< Voronoi sites per draw: uniform in [minCells, maxCells]
  int maxCells = 10;
  double planeCutFraction = 0.3;    ///< share of draws made by 1–3 random planes, in [0, 1]
  double minVolumeFraction = 0.01;  ///< fragments below this fraction of the solid's volume are redrawn
  int maxAttempts = 20;             ///< draws before giving up
};

/// Checks the ranges: 2 ≤ minCells ≤ maxCells ≤ 256, planeCutFraction in [0, 1],
/// minVolumeFraction in [0, 1), maxAttempts ≥ 1. Error: InvalidArgument naming the field.
Status validateFragmentSettings(const FragmentSettings& settings);

/// One fragment of `solid`, reproducible from `seed`: the same seed gives bit-identical arrays on
/// every platform that has IEEE doubles (std::mt19937_64 bits mapped to [0, 1) by (x >> 11)·2⁻⁵³,
/// no std distributions). Each draw is, with probability planeCutFraction, 1–3 planes through
/// uniform interior points with uniform random normals (the fragment is the side normal·x ≤ offset
/// of all of them), otherwise M sites uniform inside the solid (rejection sampling in the bounding
/// box with CGAL::Side_of_triangle_mesh), M uniform in [minCells, maxCells], and the cell of one
/// uniformly chosen site. A draw whose fragment is empty, in several pieces, below
/// minVolumeFraction or fails validateSurfaceMesh is discarded, and the same generator draws again.
/// Input: solid as for clipByPlanes, with positive volume. *cutKind (if given) receives "voronoi"
/// or "planes".
/// Output: one closed, outward body that passes validateSurfaceMesh, in the solid's frame (m).
/// Errors: InvalidArgument (bad settings; a solid that is not a closed manifold triangle mesh or
/// has no positive volume; no interior point found in 10⁴ tries), MeshingFailed (no acceptable
/// fragment in maxAttempts draws; the message gives the last reason).
Result<TriangleMesh> generateFragment(const TriangleMesh& solid, const FragmentSettings& settings, uint64_t seed,
                                      std::string* cutKind = nullptr);

}  // namespace brittle
