// FeatureCurves.h — the feature edges of a closed surface worth protecting when tet-meshing it.
//
// A crease is an edge whose two faces' normals differ by at least angleDeg (Mesh_3's own
// criterion in detect_features). On CAD parts the creases are the part's edges: long curves. On
// scans and sculpted models most creases are noise: short scattered groups, and curves that turn
// back on themselves. Protecting those makes Mesh_3 put protection balls in places too tight for
// them, which is where zero-volume tets and split-off pieces come from. So the creases are grouped
// (edges connected through shared vertices), and a group is kept only when it is at least
// minLengthM long and no two of its edges meet at an angle below needleTurnDeg.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "brittle/core/MeshTypes.h"

namespace brittle {

struct FeatureCurveSettings {
  double angleDeg = 60.0;       ///< normals differing by at least this make a crease
  double minLengthM = 0.0;      ///< a group shorter than this (summed edge length, m) is dropped
  /// Two crease edges of a group meeting at a smaller angle drop the group. 15° keeps fandisk's
  /// sharpest real corner (19.4°) and drops the 0.1° spikes of mpi_triang (libcgal-demo).
  double needleTurnDeg = 15.0;
};

struct FeatureCurves {
  /// The kept creases as polylines (points in the surface's frame, m), split where a vertex has
  /// other than two crease edges or where the curve turns by more than 90° (as Mesh_3 splits its
  /// own); a closed loop repeats its first point at the end.
  std::vector<std::vector<Eigen::Vector3d>> polylines;
  int64_t creaseEdges = 0, keptEdges = 0;
  int64_t groups = 0, keptGroups = 0;
  int64_t shortGroups = 0, needleGroups = 0;  ///< dropped for each reason (needle counted first)
  bool droppedAny() const { return keptEdges < creaseEdges; }
};

/// Finds the creases of a closed, edge-manifold surface (one that passes validateSurfaceMesh) and
/// keeps the real feature curves among them. Deterministic: polylines are ordered by the vertex
/// id they start from.
FeatureCurves detectFeatureCurves(const TriangleMesh& surface, const FeatureCurveSettings& settings);

}  // namespace brittle
