#include "brittle/descriptors/MomentDescriptor.h"

#include <cmath>
#include <string>

#include "SurfaceChecks.h"

namespace brittle {

Status validateMomentDescriptorSettings(const MomentDescriptorSettings& s) {
  if (s.maxOrder < 2 || s.maxOrder > kMaxMomentOrder) {
    return makeError(ErrorCode::InvalidArgument, "MomentDescriptorSettings.maxOrder " + std::to_string(s.maxOrder) +
                                                     " is outside [2, " + std::to_string(kMaxMomentOrder) + "]");
  }
  if (!s.orderWeights.empty()) {
    if (static_cast<int>(s.orderWeights.size()) != s.maxOrder + 1) {
      return makeError(ErrorCode::InvalidArgument, "MomentDescriptorSettings.orderWeights has " +
                                                       std::to_string(s.orderWeights.size()) + " entries, expected " +
                                                       std::to_string(s.maxOrder + 1));
    }
    for (size_t n = 0; n < s.orderWeights.size(); ++n) {
      if (!std::isfinite(s.orderWeights[n]) || s.orderWeights[n] < 0.0) {
        return makeError(ErrorCode::InvalidArgument,
                         "MomentDescriptorSettings.orderWeights[" + std::to_string(n) + "] must be finite and ≥ 0");
      }
    }
  }
  return Ok{};
}

int momentDescriptorSize(int maxOrder) { return 3 + monomialCount(maxOrder) - monomialCount(2); }

std::vector<std::array<int, 3>> momentDescriptorLayout(int maxOrder) {
  std::vector<std::array<int, 3>> out = {{2, 0, 0}, {0, 2, 0}, {0, 0, 2}};
  for (int m = monomialCount(2); m < monomialCount(maxOrder); ++m) out.push_back(monomialExponents(m));
  return out;
}

Result<Descriptor> momentDescriptorFromMoments(const VolumeMoments& canonicalMoments,
                                               const MomentDescriptorSettings& settings) {
  if (auto status = validateMomentDescriptorSettings(settings); !status) return status.error();
  if (canonicalMoments.maxOrder < settings.maxOrder) {
    return makeError(ErrorCode::InvalidArgument, "moments of order " + std::to_string(canonicalMoments.maxOrder) +
                                                     " cannot give a descriptor of order " +
                                                     std::to_string(settings.maxOrder));
  }
  const auto weight = [&](int order) {
    return settings.orderWeights.empty() ? 1.0 : std::sqrt(settings.orderWeights[order]);
  };
  Descriptor out(momentDescriptorSize(settings.maxOrder));
  const auto& v = canonicalMoments.values;
  const double w2 = weight(2);
  out[0] = static_cast<float>(w2 * v[monomialIndex(2, 0, 0)]);
  out[1] = static_cast<float>(w2 * v[monomialIndex(0, 2, 0)]);
  out[2] = static_cast<float>(w2 * v[monomialIndex(0, 0, 2)]);
  int k = 3;
  for (int n = 3; n <= settings.maxOrder; ++n) {
    const double w = weight(n);
    for (int m = monomialCount(n - 1); m < monomialCount(n); ++m) out[k++] = static_cast<float>(w * v[m]);
  }
  return out;
}

Result<Descriptor> computeMomentDescriptor(const TriangleMesh& surface, const CanonicalFrame& frame,
                                           const MomentDescriptorSettings& settings) {
  if (auto status = validateMomentDescriptorSettings(settings); !status) return status.error();
  if (auto status = detail::checkFrame(frame); !status) return status.error();
  auto raw = computeVolumeMoments(surface, settings.maxOrder, frame.translationM);
  if (!raw) return raw.error();
  return momentDescriptorFromMoments(transformVolumeMoments(raw.value(), frame.scalePerM * frame.rotation),
                                     settings);
}

Result<DescriptorMatrix> computeMomentDescriptors(const TriangleMesh& surface, const CanonicalFrames& frames,
                                                  const MomentDescriptorSettings& settings) {
  if (auto status = validateMomentDescriptorSettings(settings); !status) return status.error();
  if (frames.candidates.empty()) return makeError(ErrorCode::InvalidArgument, "no canonical frame given");
  for (const auto& frame : frames.candidates) {
    if (auto status = detail::checkFrame(frame); !status) return status.error();
  }
  const Eigen::Vector3d origin = frames.candidates.front().translationM;
  auto raw = computeVolumeMoments(surface, settings.maxOrder, origin);
  if (!raw) return raw.error();
  DescriptorMatrix out(static_cast<Eigen::Index>(frames.candidates.size()), momentDescriptorSize(settings.maxOrder));
  for (size_t c = 0; c < frames.candidates.size(); ++c) {
    const auto& frame = frames.candidates[c];
    auto d = momentDescriptorFromMoments(
        transformVolumeMoments(raw.value(), frame.scalePerM * frame.rotation, frame.translationM - origin), settings);
    if (!d) return d.error();
    out.row(static_cast<Eigen::Index>(c)) = d.value().transpose();
  }
  return out;
}

Result<DescriptorMatrix> momentDescriptorsFromFrames(const CanonicalFrames& frames,
                                                     const MomentDescriptorSettings& settings) {
  if (auto status = validateMomentDescriptorSettings(settings); !status) return status.error();
  if (frames.candidates.empty()) return makeError(ErrorCode::InvalidArgument, "no canonical frame given");
  if (settings.maxOrder > frames.centralMoments.maxOrder) {
    return makeError(ErrorCode::InvalidArgument, "frames store moments up to order " +
                                                     std::to_string(frames.centralMoments.maxOrder) +
                                                     ", descriptor needs " + std::to_string(settings.maxOrder));
  }
  DescriptorMatrix out(static_cast<Eigen::Index>(frames.candidates.size()), momentDescriptorSize(settings.maxOrder));
  for (size_t c = 0; c < frames.candidates.size(); ++c) {
    const auto& frame = frames.candidates[c];
    if (auto status = detail::checkFrame(frame); !status) return status.error();
    auto d = momentDescriptorFromMoments(transformVolumeMoments(frames.centralMoments, frame.scalePerM * frame.rotation,
                                                                frame.translationM - frames.centerOfMassM),
                                         settings);
    if (!d) return d.error();
    out.row(static_cast<Eigen::Index>(c)) = d.value().transpose();
  }
  return out;
}

}  // namespace brittle
