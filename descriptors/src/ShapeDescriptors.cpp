#include "brittle/descriptors/ShapeDescriptors.h"

namespace brittle {

const char* descriptorKindName(DescriptorKind kind) {
  switch (kind) {
    case DescriptorKind::Moment: return "moment";
    case DescriptorKind::Voxel: return "voxel";
    case DescriptorKind::VoxelImproved: return "voxel-improved";
  }
  return "unknown";
}

Result<DescriptorKind> parseDescriptorKind(std::string_view name) {
  for (DescriptorKind kind : kAllDescriptorKinds) {
    if (name == descriptorKindName(kind)) return kind;
  }
  return makeError(ErrorCode::InvalidArgument,
                   "unknown descriptor kind '" + std::string(name) + "' (expected moment, voxel or voxel-improved)");
}

int descriptorSize(DescriptorKind kind, const ShapeDescriptorSettings& settings) {
  switch (kind) {
    case DescriptorKind::Moment: return momentDescriptorSize(settings.moment.maxOrder);
    case DescriptorKind::Voxel: return settings.voxel.resolution * settings.voxel.resolution * settings.voxel.resolution;
    case DescriptorKind::VoxelImproved: {
      const int k = settings.voxelImproved.resolution;
      return k * k * k;
    }
  }
  return 0;
}

Result<DescriptorMatrix> computeShapeDescriptors(const TriangleMesh& surface, const CanonicalFrames& frames,
                                                 DescriptorKind kind, const ShapeDescriptorSettings& settings) {
  switch (kind) {
    case DescriptorKind::Moment:
      // The frames already hold the order-4 central moments; a higher order needs a second pass.
      if (settings.moment.maxOrder <= frames.centralMoments.maxOrder) {
        return momentDescriptorsFromFrames(frames, settings.moment);
      }
      return computeMomentDescriptors(surface, frames, settings.moment);
    case DescriptorKind::Voxel: return computeVoxelDescriptors(surface, frames, settings.voxel);
    case DescriptorKind::VoxelImproved: return computeImprovedVoxelDescriptors(surface, frames, settings.voxelImproved);
  }
  return makeError(ErrorCode::InvalidArgument, "unknown descriptor kind");
}

Status validateShapeDescriptorSettings(const ShapeDescriptorSettings& settings) {
  if (auto s = validateCanonicalFrameSettings(settings.frame); !s) return s;
  if (auto s = validateMomentDescriptorSettings(settings.moment); !s) return s;
  if (auto s = validateVoxelDescriptorSettings(settings.voxel); !s) return s;
  return validateImprovedVoxelDescriptorSettings(settings.voxelImproved);
}

}  // namespace brittle
