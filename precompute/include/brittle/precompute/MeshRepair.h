// MeshRepair.h — rebuilds a watertight, outward, 2-manifold surface through an OpenVDB level set
// (mesh → narrow-band signed distance → zero isosurface). Holes narrower than about a voxel are
// closed, inverted or inconsistent orientation is fixed (the sign comes from flood fill, not
// from the face winding), and self-intersections are resolved into their union.
#pragma once

#include "brittle/core/MeshTypes.h"
#include "brittle/core/Result.h"
#include "brittle/precompute/Progress.h"

namespace brittle {

struct RepairSettings {
  /// Voxel size (m); 0 means the longest bounding-box side / voxelsPerLongestSide.
  double voxelSizeM = 0.0;
  int voxelsPerLongestSide = 128;
  double adaptivity = 0.0;  ///< OpenVDB volumeToMesh adaptivity in [0, 1]; 0 keeps every voxel
};

struct RepairReport {
  double voxelSizeM = 0.0;
  double inputVolumeM3 = 0.0;   ///< |signed volume| of the input (approximate if it was open)
  double outputVolumeM3 = 0.0;
  double relativeVolumeChange = 0.0;  ///< (output − input) / input
  int64_t inputFaces = 0;
  int64_t outputFaces = 0;
};

/// Repairs mesh. Errors: EmptyMesh, NonFiniteValue, RepairFailed (empty level set, or the result
/// still fails validateSurfaceMesh — the message says why).
Result<TriangleMesh> repairSurfaceMesh(const TriangleMesh& mesh, const RepairSettings& settings,
                                       RepairReport* report = nullptr, ProgressSink* progress = nullptr);

}  // namespace brittle
