// VoxelDescriptor.h — shape descriptors sampled on a k³ grid over the canonical frame: occupancy
// by an exact parity fill along the grid's columns, and the clamped signed distance from exact
// point-triangle distances within the clamp, signed by the same parity fill.
//
// Grid. The canonical cube [-c, c]³ (c = halfExtent, dimensionless canonical units) is split into
// k³ cubic voxels of edge h = 2c/k; voxel (i, j, l) has its centre at -c + (i + ½, j + ½, l + ½) h
// and is stored at index (i·k + j)·k + l (x slowest, as a C array [k][k][k]). The default c = 1.5
// holds every unit-volume solid whose extent along each canonical axis is ≤ 3: a cube (side 1), a
// ball (diameter 1.24), a square rod up to about 5:1, a square plate down to about 1/9 thick (27:1).
// Parts outside the cube are cropped; the descriptor stays defined.
//
// Voxel descriptor: occupancy, 1 where the voxel centre is inside the solid, else 0 (a centre
// exactly on the surface falls on either side, by a fixed rule). Computed by parity: along each
// column of centres parallel to z, a centre is inside when an odd number of the surface's crossings
// with the column's line lie at or above it. A line through an edge or a vertex is counted by a
// tie rule on the projected triangles, so it crosses once where the surface passes through and
// never where it folds back; the result equals the winding number at every centre (tested).
//
// Improved voxel descriptor: the signed distance at each voxel centre, clamped to ±w voxels and
// divided by w·h, so values lie in [-1, 1] (negative inside). Why this instead of occupancy:
// occupancy is a step function of the pose, so a misalignment δ of the canonical frame (a remesh,
// a slightly wrong axis of a nearly symmetric shape) flips every voxel whose centre is within δ of
// the surface and the distance jumps by whole voxels. The signed distance is 1-Lipschitz in the
// pose, so the descriptor moves by at most δ/(w·h) per voxel and the distance grows smoothly with
// the misalignment; clamping keeps voxels far from the surface from dominating, and bounded
// values keep the L2 metric balanced between shapes of different sizes. Computed exactly: each
// centre within w·h of the surface gets its distance to the nearest triangle (closest point by
// Voronoi region, in double), every other one reads ±1 exactly, and the sign is the occupancy's
// (so the two descriptors agree on inside and outside; a centre on the surface reads 0). Until stop
// 80 it came from OpenVDB's narrow-band mesh-to-level-set, twice as slow, whose own inside test
// differed from the parity fill's at a few centres within a few percent of a voxel of the surface.
#pragma once

#include "brittle/descriptors/CanonicalFrame.h"
#include "brittle/descriptors/DescriptorTypes.h"
#include "brittle/core/MeshTypes.h"
#include "brittle/core/Result.h"

namespace brittle {

struct VoxelDescriptorSettings {
  int resolution = 16;      ///< k, voxels per axis, in [2, 256]; the descriptor has k³ values
  double halfExtent = 1.5;  ///< c, half the edge of the sampled cube (canonical units)
};

struct ImprovedVoxelDescriptorSettings {
  int resolution = 16;        ///< k, as above
  double halfExtent = 1.5;    ///< c, as above
  double clampVoxels = 2.0;   ///< w, clamp distance in voxels, in [0.5, k]
};

/// Check resolution, halfExtent (and clampVoxels). Error: InvalidArgument naming the field.
Status validateVoxelDescriptorSettings(const VoxelDescriptorSettings& settings);
Status validateImprovedVoxelDescriptorSettings(const ImprovedVoxelDescriptorSettings& settings);

/// Occupancy (0 or 1 per voxel) of the solid bounded by a closed, outward surface, seen in `frame`.
/// Inputs: surface (#V by 3 vertices in metres, #F by 3 faces); frame, usually a candidate of
/// computeCanonicalFrames on the same surface.
/// Output: k³ values in the grid order above.
/// Errors: EmptyMesh, NonFiniteValue, InvalidArgument (face index out of range, bad settings or
/// frame), OpenMesh.
Result<Descriptor> computeVoxelDescriptor(const TriangleMesh& surface, const CanonicalFrame& frame,
                                          const VoxelDescriptorSettings& settings = {});

/// Clamped signed distance in [-1, 1] per voxel (see file header). Inputs, output layout and errors
/// as computeVoxelDescriptor.
Result<Descriptor> computeImprovedVoxelDescriptor(const TriangleMesh& surface, const CanonicalFrame& frame,
                                                  const ImprovedVoxelDescriptorSettings& settings = {});

/// One row per candidate frame (#candidates by k³). Errors as above; InvalidArgument if no frame.
Result<DescriptorMatrix> computeVoxelDescriptors(const TriangleMesh& surface, const CanonicalFrames& frames,
                                                 const VoxelDescriptorSettings& settings = {});
Result<DescriptorMatrix> computeImprovedVoxelDescriptors(const TriangleMesh& surface, const CanonicalFrames& frames,
                                                         const ImprovedVoxelDescriptorSettings& settings = {});

/// Euclidean distance (for occupancy, the square root of the number of differing voxels).
inline float voxelL2Distance(const Descriptor& a, const Descriptor& b) { return descriptorL2Distance(a, b); }

/// Normalised Hamming distance of two occupancy descriptors: the fraction of voxels that differ,
/// in [0, 1] (the L1 distance divided by k³).
inline float voxelHammingDistance(const Descriptor& a, const Descriptor& b) {
  return a.size() == 0 ? 0.0f : (a - b).cwiseAbs().sum() / static_cast<float>(a.size());
}

}  // namespace brittle
