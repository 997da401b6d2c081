#include "CliSupport.h"

#include "brittle/precompute/RuntimeSettingsFile.h"

#include <unistd.h>

#include <cstdio>

namespace brittle::cli {

ExitCode exitCodeFor(ErrorCode code) {
  switch (code) {
    case ErrorCode::FileNotFound:
    case ErrorCode::UnknownFormat:
    case ErrorCode::ParseError:
    case ErrorCode::EmptyMesh:
    case ErrorCode::NonFiniteValue:
    case ErrorCode::OpenMesh:
    case ErrorCode::NonManifold:
    case ErrorCode::InconsistentOrientation:
    case ErrorCode::InwardFacing:
    case ErrorCode::DegenerateFace:
    case ErrorCode::SelfIntersection:
    case ErrorCode::RepairFailed: return kExitBadMesh;
    case ErrorCode::UnknownMaterial:
    case ErrorCode::InvalidMaterial: return kExitBadMaterial;
    case ErrorCode::MeshingFailed:
    case ErrorCode::DegenerateElement:
    case ErrorCode::FactorizationFailed:
    case ErrorCode::EigenNotConverged:
    case ErrorCode::RigidModeMismatch: return kExitSolve;
    case ErrorCode::PackIoError:
    case ErrorCode::PackFormatMismatch:
    case ErrorCode::PackVersionMismatch:
    case ErrorCode::PackCorrupt:
    case ErrorCode::PackShapeMismatch: return kExitPack;
    case ErrorCode::InvalidArgument:
    case ErrorCode::CapacityExceeded: return kExitUsage;  // a setting (a capacity) too small for the run
    case ErrorCode::Cancelled: return kExitInternal;
  }
  return kExitInternal;
}

int reportError(const Error& error) {
  std::fprintf(stderr, "error [%s]: %s\n", std::string(errorCodeName(error.code)).c_str(), error.message.c_str());
  return exitCodeFor(error.code);
}

TerminalProgress::TerminalProgress(bool quiet)
    : mQuiet(quiet), mTty(::isatty(STDERR_FILENO) != 0), mStart(SteadyClock::now()) {}

TerminalProgress::~TerminalProgress() { finish(); }

void TerminalProgress::report(std::string_view stage, double fraction) {
  if (mQuiet) return;
  const int percent = static_cast<int>(fraction * 100.0 + 0.5);
  const bool newStage = stage != mStage;
  if (!newStage && percent == mPercent) return;
  const double elapsed = secondsSince(mStart);
  if (mTty) {
    std::fprintf(stderr, "\r\033[K[%7.1fs] %.*s %3d%%", elapsed, static_cast<int>(stage.size()), stage.data(), percent);
    std::fflush(stderr);
  } else if (newStage) {
    std::fprintf(stderr, "[%7.1fs] %.*s\n", elapsed, static_cast<int>(stage.size()), stage.data());
  }
  mStage = std::string(stage);
  mPercent = percent;
}

void TerminalProgress::finish() {
  if (mTty && !mQuiet && !mStage.empty()) std::fprintf(stderr, "\n");
  mStage.clear();
}

Status applyRuntimeSettingsFile(const std::string& path, const CLI::App& cmd, FractureSettings& fracture) {
  auto loaded = loadRuntimeSettings(path, fracture);
  if (!loaded) return loaded.error();
  FractureSettings merged = loaded.value();
  auto given = [&](const char* flag) { return cmd.get_option_no_throw(flag) && cmd.count(flag) > 0; };
  if (given("--modes")) merged.modeCount = fracture.modeCount;
  if (given("--debris")) merged.debrisVolumeFraction = fracture.debrisVolumeFraction;
  if (given("--contact-spread")) merged.contactSpreadFraction = fracture.contactSpreadFraction;
  if (given("--descriptor")) merged.descriptor = fracture.descriptor;
  if (given("--exact-max-tets")) merged.exactModesMaxTets = fracture.exactModesMaxTets;
  if (given("--exact-max-dof")) merged.exactModesMaxDof = fracture.exactModesMaxDof;
  if (given("--match-error-target")) merged.matchErrorTarget = fracture.matchErrorTarget;
  if (given("--polynomial-degree")) merged.polynomialModeDegree = fracture.polynomialModeDegree;
  if (given("--mesh-ratio-max-dof")) merged.meshRatioMaxDof = fracture.meshRatioMaxDof;
  if (given("--mesh-ratio-element")) merged.meshRatioElement = fracture.meshRatioElement;
  if (given("--end-at-cracks")) merged.crack.endAtCracks = fracture.crack.endAtCracks;
  fracture = merged;
  return Ok{};
}

}  // namespace brittle::cli
