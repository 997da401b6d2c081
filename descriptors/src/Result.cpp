#include "brittle/descriptors/Result.h"

namespace brittle {

std::string_view errorCodeName(ErrorCode code) {
  switch (code) {
    case ErrorCode::FileNotFound: return "file_not_found";
    case ErrorCode::UnknownFormat: return "unknown_format";
    case ErrorCode::ParseError: return "parse_error";
    case ErrorCode::EmptyMesh: return "empty_mesh";
    case ErrorCode::NonFiniteValue: return "non_finite_value";
    case ErrorCode::OpenMesh: return "open_mesh";
    case ErrorCode::NonManifold: return "non_manifold";
    case ErrorCode::InconsistentOrientation: return "inconsistent_orientation";
    case ErrorCode::InwardFacing: return "inward_facing";
    case ErrorCode::DegenerateFace: return "degenerate_face";
    case ErrorCode::SelfIntersection: return "self_intersection";
    case ErrorCode::RepairFailed: return "repair_failed";
    case ErrorCode::MeshingFailed: return "meshing_failed";
    case ErrorCode::DegenerateElement: return "degenerate_element";
    case ErrorCode::FactorizationFailed: return "factorization_failed";
    case ErrorCode::EigenNotConverged: return "eigen_not_converged";
    case ErrorCode::RigidModeMismatch: return "rigid_mode_mismatch";
    case ErrorCode::UnknownMaterial: return "unknown_material";
    case ErrorCode::InvalidMaterial: return "invalid_material";
    case ErrorCode::PackIoError: return "pack_io_error";
    case ErrorCode::PackFormatMismatch: return "pack_format_mismatch";
    case ErrorCode::PackVersionMismatch: return "pack_version_mismatch";
    case ErrorCode::PackCorrupt: return "pack_corrupt";
    case ErrorCode::PackShapeMismatch: return "pack_shape_mismatch";
    case ErrorCode::InvalidArgument: return "invalid_argument";
    case ErrorCode::Cancelled: return "cancelled";
    case ErrorCode::CapacityExceeded: return "capacity_exceeded";
  }
  return "unknown";
}

}  // namespace brittle
