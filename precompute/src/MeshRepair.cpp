#include "brittle/precompute/MeshRepair.h"

#include <openvdb/openvdb.h>
#include <openvdb/tools/MeshToVolume.h>
#include <openvdb/tools/VolumeToMesh.h>

#include <cmath>
#include <mutex>

#include "brittle/descriptors/MassProperties.h"
#include "brittle/precompute/MeshValidation.h"

namespace brittle {

Result<TriangleMesh> repairSurfaceMesh(const TriangleMesh& mesh, const RepairSettings& s, RepairReport* report,
                                       ProgressSink* progress) {
  if (mesh.vertices.rows() == 0 || mesh.faces.rows() == 0) return makeError(ErrorCode::EmptyMesh, "cannot repair an empty mesh");
  if (!mesh.vertices.allFinite()) return makeError(ErrorCode::NonFiniteValue, "cannot repair a mesh with non-finite coordinates");
  if (mesh.faces.minCoeff() < 0 || mesh.faces.maxCoeff() >= mesh.vertices.rows()) {
    return makeError(ErrorCode::ParseError, "cannot repair a mesh whose faces refer to missing vertices");
  }
  static std::once_flag initOnce;
  std::call_once(initOnce, [] { openvdb::initialize(); });

  // OpenVDB works in float: move the mesh next to the origin first so no precision is lost.
  const Eigen::RowVector3d lo = mesh.vertices.colwise().minCoeff();
  const Eigen::RowVector3d extent = mesh.vertices.colwise().maxCoeff() - lo;
  const double voxel = s.voxelSizeM > 0.0 ? s.voxelSizeM : extent.maxCoeff() / std::max(8, s.voxelsPerLongestSide);
  if (!(voxel > 0.0)) return makeError(ErrorCode::RepairFailed, "mesh has zero extent");

  std::vector<openvdb::Vec3s> points;
  points.reserve(static_cast<size_t>(mesh.vertices.rows()));
  for (Eigen::Index v = 0; v < mesh.vertices.rows(); ++v) {
    const Eigen::RowVector3d p = mesh.vertices.row(v) - lo;
    points.emplace_back(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()));
  }
  std::vector<openvdb::Vec3I> triangles;
  triangles.reserve(static_cast<size_t>(mesh.faces.rows()));
  for (Eigen::Index f = 0; f < mesh.faces.rows(); ++f) {
    triangles.emplace_back(mesh.faces(f, 0), mesh.faces(f, 1), mesh.faces(f, 2));
  }

  reportProgress(progress, "repair: level set", 0.0);
  const auto xform = openvdb::math::Transform::createLinearTransform(voxel);
  openvdb::FloatGrid::Ptr grid;
  std::vector<openvdb::Vec3s> outPoints;
  std::vector<openvdb::Vec3I> outTriangles;
  std::vector<openvdb::Vec4I> outQuads;
  try {
    grid = openvdb::tools::meshToLevelSet<openvdb::FloatGrid>(*xform, points, triangles, 3.0f);
    reportProgress(progress, "repair: isosurface", 0.5);
    openvdb::tools::volumeToMesh(*grid, outPoints, outTriangles, outQuads, 0.0, s.adaptivity);
  } catch (const std::exception& e) {
    return makeError(ErrorCode::RepairFailed, std::string("OpenVDB failed: ") + e.what());
  }
  if (outPoints.empty() || (outTriangles.empty() && outQuads.empty())) {
    return makeError(ErrorCode::RepairFailed, "the level set is empty at voxel size " + std::to_string(voxel) +
                                                  " m (is the mesh thinner than a voxel?)");
  }

  TriangleMesh out;
  out.vertices.resize(static_cast<Eigen::Index>(outPoints.size()), 3);
  for (size_t i = 0; i < outPoints.size(); ++i) {
    out.vertices.row(static_cast<Eigen::Index>(i)) << outPoints[i].x() + lo.x(), outPoints[i].y() + lo.y(),
        outPoints[i].z() + lo.z();
  }
  out.faces.resize(static_cast<Eigen::Index>(outTriangles.size() + 2 * outQuads.size()), 3);
  Eigen::Index f = 0;
  for (const auto& t : outTriangles) out.faces.row(f++) << t[0], t[1], t[2];
  for (const auto& q : outQuads) {
    out.faces.row(f++) << q[0], q[1], q[2];
    out.faces.row(f++) << q[0], q[2], q[3];
  }
  // OpenVDB's winding convention is opposite to ours in some versions: orient by the volume sign.
  double outVolume = computeSurfaceMassProperties(out, 1.0).volumeM3;
  if (outVolume < 0.0) {
    out.faces.col(1).swap(out.faces.col(2));
    outVolume = -outVolume;
  }
  reportProgress(progress, "repair: checking", 0.9);
  if (Status valid = validateSurfaceMesh(out); !valid) {
    return makeError(ErrorCode::RepairFailed, "repaired surface is still invalid: " + valid.error().message);
  }
  if (report) {
    report->voxelSizeM = voxel;
    report->inputVolumeM3 = std::abs(computeSurfaceMassProperties(mesh, 1.0).volumeM3);
    report->outputVolumeM3 = outVolume;
    report->relativeVolumeChange =
        report->inputVolumeM3 > 0.0 ? (outVolume - report->inputVolumeM3) / report->inputVolumeM3 : 0.0;
    report->inputFaces = mesh.faces.rows();
    report->outputFaces = out.faces.rows();
  }
  reportProgress(progress, "repair: checking", 1.0);
  return out;
}

}  // namespace brittle
