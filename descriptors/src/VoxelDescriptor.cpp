#include "brittle/descriptors/VoxelDescriptor.h"

#include <openvdb/openvdb.h>
#include <openvdb/tools/MeshToVolume.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <exception>
#include <mutex>
#include <string>
#include <vector>

#include "SurfaceChecks.h"

namespace brittle {
namespace {

struct GridSpec {
  int resolution;
  double halfExtent;
  float bandVoxels;  // narrow-band half width; values beyond it are ±bandVoxels·h
};

Status checkGrid(int resolution, double halfExtent) {
  if (resolution < 2 || resolution > 256) {
    return makeError(ErrorCode::InvalidArgument, "voxel resolution " + std::to_string(resolution) + " is outside [2, 256]");
  }
  if (!std::isfinite(halfExtent) || !(halfExtent > 0.0)) {
    return makeError(ErrorCode::InvalidArgument, "voxel halfExtent must be finite and positive");
  }
  return Ok{};
}

Status checkFrame(const CanonicalFrame& f) {
  if (!f.rotation.allFinite() || !f.translationM.allFinite() || !std::isfinite(f.scalePerM) || !(f.scalePerM > 0.0)) {
    return makeError(ErrorCode::InvalidArgument, "canonical frame has a non-finite value or a non-positive scale");
  }
  return Ok{};
}

// Signed distance (canonical units) at the k³ voxel centres, in grid order. Precondition: the
// surface passed checkClosedSurface. OpenVDB exceptions stop here.
Result<std::vector<float>> sampleSignedDistance(const TriangleMesh& surface, const CanonicalFrame& frame,
                                                const GridSpec& spec) {
  static std::once_flag initialised;
  std::call_once(initialised, [] { openvdb::initialize(); });
  try {
    const double h = 2.0 * spec.halfExtent / spec.resolution;
    // Index (0,0,0) sits on the centre of the first voxel.
    auto xform = openvdb::math::Transform::createLinearTransform(h);
    xform->postTranslate(openvdb::Vec3d(-spec.halfExtent + 0.5 * h));
    const Points canonical = frame.pointsToCanonical(surface.vertices);
    std::vector<openvdb::Vec3s> points(static_cast<size_t>(canonical.rows()));
    for (Eigen::Index v = 0; v < canonical.rows(); ++v) {
      points[static_cast<size_t>(v)] = openvdb::Vec3s(static_cast<float>(canonical(v, 0)),
                                                      static_cast<float>(canonical(v, 1)),
                                                      static_cast<float>(canonical(v, 2)));
    }
    std::vector<openvdb::Vec3I> triangles(static_cast<size_t>(surface.faces.rows()));
    for (Eigen::Index f = 0; f < surface.faces.rows(); ++f) {
      triangles[static_cast<size_t>(f)] = openvdb::Vec3I(static_cast<uint32_t>(surface.faces(f, 0)),
                                                         static_cast<uint32_t>(surface.faces(f, 1)),
                                                         static_cast<uint32_t>(surface.faces(f, 2)));
    }
    const auto grid = openvdb::tools::meshToLevelSet<openvdb::FloatGrid>(*xform, points, triangles, spec.bandVoxels);
    const auto accessor = grid->getConstAccessor();
    const int k = spec.resolution;
    std::vector<float> out(static_cast<size_t>(k) * k * k);
    size_t n = 0;
    for (int i = 0; i < k; ++i) {
      for (int j = 0; j < k; ++j) {
        for (int l = 0; l < k; ++l) out[n++] = accessor.getValue(openvdb::Coord(i, j, l));
      }
    }
    return out;
  } catch (const std::exception& e) {
    return makeError(ErrorCode::InvalidArgument, std::string("OpenVDB mesh-to-volume failed: ") + e.what());
  } catch (...) {
    return makeError(ErrorCode::InvalidArgument, "OpenVDB mesh-to-volume failed with an unknown exception");
  }
}

template <typename Settings, typename Single>
Result<DescriptorMatrix> forEachFrame(const TriangleMesh& surface, const CanonicalFrames& frames,
                                      const Settings& settings, Single single) {
  if (frames.candidates.empty()) return makeError(ErrorCode::InvalidArgument, "no canonical frame given");
  const Eigen::Index k3 = static_cast<Eigen::Index>(settings.resolution) * settings.resolution * settings.resolution;
  DescriptorMatrix out;
  for (size_t c = 0; c < frames.candidates.size(); ++c) {
    auto d = single(surface, frames.candidates[c], settings);
    if (!d) return d.error();
    if (c == 0) out.resize(static_cast<Eigen::Index>(frames.candidates.size()), k3);
    out.row(static_cast<Eigen::Index>(c)) = d.value().transpose();
  }
  return out;
}

}  // namespace

Status validateVoxelDescriptorSettings(const VoxelDescriptorSettings& settings) {
  return checkGrid(settings.resolution, settings.halfExtent);
}

Status validateImprovedVoxelDescriptorSettings(const ImprovedVoxelDescriptorSettings& settings) {
  if (auto status = checkGrid(settings.resolution, settings.halfExtent); !status) return status;
  if (!std::isfinite(settings.clampVoxels) || settings.clampVoxels < 0.5 || settings.clampVoxels > settings.resolution) {
    return makeError(ErrorCode::InvalidArgument, "ImprovedVoxelDescriptorSettings.clampVoxels must be in [0.5, resolution]");
  }
  return Ok{};
}

Result<Descriptor> computeVoxelDescriptor(const TriangleMesh& surface, const CanonicalFrame& frame,
                                          const VoxelDescriptorSettings& settings) {
  if (auto status = validateVoxelDescriptorSettings(settings); !status) return status.error();
  if (auto status = checkFrame(frame); !status) return status.error();
  if (auto status = detail::checkClosedSurface(surface); !status) return status.error();
  // Occupancy only needs the sign; a narrow band keeps the conversion cheap (the interior outside
  // the band is signed by OpenVDB's flood fill).
  const auto sdf = sampleSignedDistance(surface, frame, {settings.resolution, settings.halfExtent, 1.5f});
  if (!sdf) return sdf.error();
  Descriptor out(static_cast<Eigen::Index>(sdf.value().size()));
  for (size_t n = 0; n < sdf.value().size(); ++n) out[static_cast<Eigen::Index>(n)] = sdf.value()[n] <= 0.0f ? 1.0f : 0.0f;
  return out;
}

Result<Descriptor> computeImprovedVoxelDescriptor(const TriangleMesh& surface, const CanonicalFrame& frame,
                                                  const ImprovedVoxelDescriptorSettings& settings) {
  if (auto status = validateImprovedVoxelDescriptorSettings(settings); !status) return status.error();
  if (auto status = checkFrame(frame); !status) return status.error();
  if (auto status = detail::checkClosedSurface(surface); !status) return status.error();
  // The band reaches one voxel past the clamp so every unclamped value is a true distance.
  const float band = static_cast<float>(settings.clampVoxels) + 1.0f;
  const auto sdf = sampleSignedDistance(surface, frame, {settings.resolution, settings.halfExtent, band});
  if (!sdf) return sdf.error();
  const double h = 2.0 * settings.halfExtent / settings.resolution;
  const float inv = static_cast<float>(1.0 / (settings.clampVoxels * h));
  Descriptor out(static_cast<Eigen::Index>(sdf.value().size()));
  for (size_t n = 0; n < sdf.value().size(); ++n) {
    out[static_cast<Eigen::Index>(n)] = std::clamp(sdf.value()[n] * inv, -1.0f, 1.0f);
  }
  return out;
}

Result<DescriptorMatrix> computeVoxelDescriptors(const TriangleMesh& surface, const CanonicalFrames& frames,
                                                 const VoxelDescriptorSettings& settings) {
  return forEachFrame(surface, frames, settings,
                      [](const TriangleMesh& s, const CanonicalFrame& f, const VoxelDescriptorSettings& v) {
                        return computeVoxelDescriptor(s, f, v);
                      });
}

Result<DescriptorMatrix> computeImprovedVoxelDescriptors(const TriangleMesh& surface, const CanonicalFrames& frames,
                                                         const ImprovedVoxelDescriptorSettings& settings) {
  return forEachFrame(surface, frames, settings,
                      [](const TriangleMesh& s, const CanonicalFrame& f, const ImprovedVoxelDescriptorSettings& v) {
                        return computeImprovedVoxelDescriptor(s, f, v);
                      });
}

}  // namespace brittle
