// TetMesher.h — tetrahedral meshing of a validated closed surface with CGAL Mesh_3.
//
// The domain keeps sharp features (Polyhedral_mesh_domain_with_features_3), so boxes keep their
// edges and corners exactly. Only real feature curves are protected (FeatureCurves.h): long
// creases, not the scattered facet creases of a scan. Mesh quality comes from Mesh_3's sliver
// perturbation and exudation (on by default, aiming at sliverBoundDeg): without them slivers go
// down to ~0.3°.
//
// The final mesh is checked: one face-connected solid, every tet above degenerateTetVolumeM3
// (FemAssembly.h), so a degenerate element never reaches the FEM. When a run fails the check,
// the mesher adjusts and runs again, at most meshingRuns runs in all, and records each adjustment
// with its reason:
//   * a degenerate tet with feature curves protected: feature protection off;
//   * split-off pieces (a part thinner than the cell size), the first time: the size halved in
//     a ball around each piece but the largest;
//   * otherwise: twice the tets (a fresh size search for twice the target, local sizes dropped;
//     with a cell size instead of a target, the size / 2^(1/3)).
// A flat part can be meshed with tets wider than thick (TetMeshSettings::thinStretch): Mesh_3
// meshes the solid stretched across its thinnest principal axis, and the nodes are taken back.
// This is the only translation unit that instantiates Mesh_3 (it costs ~4 GiB to compile); its
// interface is flat arrays only.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "brittle/database/ObjectAsset.h"
#include "brittle/core/MeshTypes.h"
#include "brittle/core/Result.h"
#include "brittle/precompute/Progress.h"

namespace brittle {

struct TetMeshSettings {
  /// Target number of tetrahedra. When > 0 the cell size is searched with refinement-only Mesh_3
  /// runs, each correcting the size by (count/target)^(1/3), until the count is within
  /// ±countTolerance; the optimised mesh is then built once at that size (optimisation moves
  /// the count by a few per cent, so the final count can sit slightly outside the tolerance).
  int64_t targetTets = 5000;
  double countTolerance = 0.25;
  int maxAttempts = 4;
  /// Cell size (m), used when targetTets == 0: upper bound on tetrahedron circumradius, facet
  /// size and feature edge length.
  double cellSizeM = 0.0;
  double facetAngleDeg = 25.0;          ///< lower bound on surface triangle angles
  double facetDistanceFraction = 0.05;  ///< surface approximation error, as a fraction of cell size
  double cellRadiusEdgeRatio = 3.0;     ///< upper bound on circumradius / shortest edge
  bool detectSharpFeatures = true;
  double featureAngleDeg = 60.0;        ///< dihedral angle that marks an edge as sharp
  /// Crease groups shorter than this many cell sizes are not protected (FeatureCurves.h).
  double minFeatureLengthCells = 8.0;
  double needleTurnDeg = 15.0;          ///< crease groups turning back sharper than this are not protected
  /// Final Mesh_3 runs allowed (the first and its adjusted retries; sizing runs not counted).
  /// 1: no retry, a failed check is an error.
  int meshingRuns = 4;
  bool optimize = true;                 ///< sliver perturbation + exudation
  /// Dihedral angle (degrees) the optimisers aim for. Measured on 3k-tet meshes of real models:
  /// 5° costs ~1 s, 10° ~20 s, 0 ("as good as possible") ~50 s. Protected sharp features can
  /// keep a few slivers below the bound (see docs/results/bake-cost.md).
  double sliverBoundDeg = 5.0;
  uint64_t seed = 1;                    ///< seeds CGAL's random generator (determinism)
  /// Wall-clock limit of one Mesh_3 run, in seconds (0: none). Mesh_3's facet refinement can
  /// run on without end: a 300-tet piece of the wedge, in a 10⁴-entry database bake, was still
  /// in Refine_facets_3 after ten minutes. A run stopped by the limit is a MeshingFailed. The
  /// limit changes no mesh that is made within it, so results stay deterministic unless a run
  /// takes about as long as the limit on one machine and not on another: keep it far above the
  /// normal run time. Object bakes have none by default (a large object can take minutes);
  /// database entries, which on a failure are meshed finer and then drawn again from their next
  /// seed, have one (DatabaseBakeSettings::defaultFragmentTetMeshSettings).
  double runTimeLimitS = 0.0;
  /// Elements this many times wider than thick across the solid's thinnest principal axis, in
  /// [1, 16]: the surface is stretched by it along that axis, meshed, and the nodes taken back
  /// (targetTets and cellSizeM are those of the stretched solid). 1 keeps Mesh_3's near-regular
  /// tets. For flat parts in quadratic tets, whose bending needs one element through the thickness
  /// but not one as wide as it is thick. sliverBoundDeg applies to the stretched tets. A part whose
  /// two smallest second moments of volume lie within a factor 2 has no one thin axis, and a
  /// stretch > 1 on it is an InvalidArgument.
  double thinStretch = 1.0;
};

/// One change the mesher made to the settings it was given, and why.
struct MeshingAdjustment {
  std::string what;  ///< e.g. "sharp features off"
  std::string why;
};

struct TetMeshResult {
  TetMesh mesh;               ///< positively oriented tets, no unused nodes
  Triangles surfaceFaces;     ///< boundary faces of mesh, outward
  MeshQuality quality;
  double cellSizeM = 0.0;     ///< the cell size that produced mesh
  int attempts = 0;           ///< Mesh_3 runs made (sizing runs + the final ones)
  int meshingRuns = 0;        ///< final runs made (1 when the first passed the checks)
  bool sharpFeatures = false; ///< whether the mesh protects feature curves
  std::vector<MeshingAdjustment> adjustments;  ///< in order
};

/// Tetrahedralises the solid bounded by surface (which must pass validateSurfaceMesh).
/// Errors: InvalidArgument (no target and no cell size, meshingRuns < 1, a stretch outside [1, 16]
/// or on a part with no one thin axis), MeshingFailed (Mesh_3
/// produced no cells, or a mesh that is not one solid after meshingRuns runs), DegenerateElement
/// (a degenerate tet after meshingRuns runs), Cancelled. Their messages list the adjustments made.
Result<TetMeshResult> tetrahedralize(const TriangleMesh& surface, const TetMeshSettings& settings,
                                     ProgressSink* progress = nullptr);

}  // namespace brittle
