// ShapeDescriptors.h — the three descriptor kinds behind one switch, so a database, a benchmark or
// a researcher's script can loop over them: moment (MomentDescriptor.h), voxel occupancy and the
// improved voxel descriptor, a clamped signed distance (VoxelDescriptor.h).
//
// Every kind is computed in the canonical frames of CanonicalFrame.h and compared with the plain
// Euclidean distance (each kind's weights and normalisation are inside its values), so one L2
// nearest-neighbour index serves them all.
#pragma once

#include <array>
#include <string>
#include <string_view>

#include "brittle/descriptors/CanonicalFrame.h"
#include "brittle/descriptors/DescriptorTypes.h"
#include "brittle/core/MeshTypes.h"
#include "brittle/descriptors/MomentDescriptor.h"
#include "brittle/core/Result.h"
#include "brittle/descriptors/VoxelDescriptor.h"

namespace brittle {

enum class DescriptorKind { Moment = 0, Voxel = 1, VoxelImproved = 2 };
inline constexpr int kDescriptorKindCount = 3;
inline constexpr std::array<DescriptorKind, kDescriptorKindCount> kAllDescriptorKinds = {
    DescriptorKind::Moment, DescriptorKind::Voxel, DescriptorKind::VoxelImproved};

/// "moment", "voxel" or "voxel-improved" (the CLI and pack spelling).
const char* descriptorKindName(DescriptorKind kind);
/// Inverse of descriptorKindName. Error: InvalidArgument listing the valid names.
Result<DescriptorKind> parseDescriptorKind(std::string_view name);

/// The settings of every kind, and of the canonical frame they share.
struct ShapeDescriptorSettings {
  CanonicalFrameSettings frame;
  MomentDescriptorSettings moment;
  VoxelDescriptorSettings voxel;
  ImprovedVoxelDescriptorSettings voxelImproved;
};

/// Number of values of one descriptor of `kind` under `settings`.
int descriptorSize(DescriptorKind kind, const ShapeDescriptorSettings& settings);

/// One descriptor of `kind` per candidate frame (#candidates by descriptorSize), for the solid
/// bounded by `surface` (closed, outward, metres) whose frames are `frames`.
/// Errors: those of computeMomentDescriptors / computeVoxelDescriptors (EmptyMesh, NonFiniteValue,
/// InvalidArgument, OpenMesh).
Result<DescriptorMatrix> computeShapeDescriptors(const TriangleMesh& surface, const CanonicalFrames& frames,
                                                 DescriptorKind kind, const ShapeDescriptorSettings& settings);

/// Checks every kind's settings. Error: InvalidArgument naming the field.
Status validateShapeDescriptorSettings(const ShapeDescriptorSettings& settings);

}  // namespace brittle
