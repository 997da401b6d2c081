// Result.h — the error vocabulary shared by every brittle module.
//
// Bad data never throws across a module boundary: functions return Result<T>, which holds either
// a value or an Error with a typed code and a message that names the file, element or field.
// Broken invariants are asserts; exceptions may exist inside offline code but are caught at the
// module boundary. core/ is the lowest module and header-only, so errorCodeName is inline.
#pragma once

#include <cassert>
#include <string>
#include <string_view>
#include <utility>
#include <variant>

namespace brittle {

/// Every typed failure brittle reports. The snake_case name (errorCodeName) is stable and is what
/// JSON output and tests use.
enum class ErrorCode {
  // Input files.
  FileNotFound,
  UnknownFormat,
  ParseError,
  EmptyMesh,
  NonFiniteValue,
  // Surface mesh validity.
  OpenMesh,
  NonManifold,
  InconsistentOrientation,
  InwardFacing,
  DegenerateFace,
  SelfIntersection,
  RepairFailed,
  // Meshing, FEM, modal analysis.
  MeshingFailed,
  DegenerateElement,
  FactorizationFailed,
  EigenNotConverged,
  RigidModeMismatch,
  // Materials.
  UnknownMaterial,
  InvalidMaterial,
  // Packs.
  PackIoError,
  PackFormatMismatch,
  PackVersionMismatch,
  PackCorrupt,
  PackShapeMismatch,
  // Generic.
  InvalidArgument,
  Cancelled,
  CapacityExceeded,  ///< a capacity declared in advance (e.g. WorldSettings) would be exceeded
};

/// Stable snake_case identifier of a code, e.g. "open_mesh".
inline std::string_view errorCodeName(ErrorCode code) {
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

struct Error {
  ErrorCode code;
  std::string message;  ///< Human-readable: what is wrong and where.
};

/// Value-or-error. Access value() only after checking ok().
template <typename T>
class [[nodiscard]] Result {
 public:
  Result(T value) : mData(std::move(value)) {}  // NOLINT: implicit by design
  Result(Error error) : mData(std::move(error)) {}  // NOLINT: implicit by design

  bool ok() const { return mData.index() == 0; }
  explicit operator bool() const { return ok(); }

  T& value() & {
    assert(ok());
    return std::get<0>(mData);
  }
  const T& value() const& {
    assert(ok());
    return std::get<0>(mData);
  }
  T&& value() && {
    assert(ok());
    return std::get<0>(std::move(mData));
  }
  const Error& error() const {
    assert(!ok());
    return std::get<1>(mData);
  }

 private:
  std::variant<T, Error> mData;
};

/// Result of an operation with no value.
struct Ok {};
using Status = Result<Ok>;

inline Error makeError(ErrorCode code, std::string message) { return Error{code, std::move(message)}; }
/// The commonest error: an argument a function cannot take.
inline Error invalidArgument(std::string message) { return makeError(ErrorCode::InvalidArgument, std::move(message)); }

}  // namespace brittle
