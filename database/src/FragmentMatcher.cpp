#include "brittle/database/FragmentMatcher.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace brittle {

Result<FragmentMatcher> FragmentMatcher::build(const FragmentDatabase& database, const FragmentMatcherSettings& settings) {
  if (database.empty()) return makeError(ErrorCode::InvalidArgument, "the pack has no fragment database (0 entries)");
  if (settings.entryLimit < 0) return makeError(ErrorCode::InvalidArgument, "entryLimit must be ≥ 0");
  const auto rows = static_cast<Eigen::Index>(
      settings.entryLimit > 0 ? std::min<int64_t>(settings.entryLimit, static_cast<int64_t>(database.entries.size()))
                              : static_cast<int64_t>(database.entries.size()));
  FragmentMatcher matcher;
  matcher.mDatabase = &database;
  matcher.mFramesAsOneSet = settings.framesAsOneSet;
  for (DescriptorKind kind : kAllDescriptorKinds) {
    const auto slot = static_cast<size_t>(kind);
    if (!settings.enabled[slot]) continue;
    // A database read on demand holds no descriptors: the kind's matrix is read for its index.
    DescriptorMatrix read;
    if (database.entrySource && database.descriptorsOf(kind).size() == 0) {
      auto loaded = database.entrySource->descriptors(kind);
      if (!loaded) return loaded.error();
      read = std::move(loaded).value();
    }
    const DescriptorMatrix& m = read.size() > 0 ? read : database.descriptorsOf(kind);
    const DescriptorIndexSettings indexSettings = settings.indexOverride[slot].value_or(database.indexSettings[slot]);
    if (m.rows() != static_cast<Eigen::Index>(database.entries.size())) {
      return makeError(ErrorCode::InvalidArgument, std::string("the ") + descriptorKindName(kind) +
                                                       " descriptor matrix does not have one row per entry");
    }
    auto index = DescriptorIndex::build(m.data(), rows, m.cols(), indexSettings);
    if (!index) {
      return makeError(index.error().code,
                       std::string(descriptorKindName(kind)) + " index: " + index.error().message);
    }
    matcher.mIndices[slot].emplace(std::move(index).value());
  }
  return matcher;
}

namespace {

// Descriptors of the surface in frames computed by the caller, then the search.
Result<std::vector<FragmentMatch>> matchInFrames(const FragmentMatcher& matcher, const TriangleMesh& surface,
                                                 const Result<CanonicalFrames>& frames,
                                                 const ShapeDescriptorSettings& settings, DescriptorKind kind, int k) {
  if (!frames) return frames.error();
  auto descriptors = computeShapeDescriptors(surface, frames.value(), kind, settings);
  if (!descriptors) return descriptors.error();
  return matcher.matchDescriptors(frames.value(), descriptors.value(), kind, k);
}

}  // namespace

Result<std::vector<FragmentMatch>> FragmentMatcher::match(const TriangleMesh& surface, DescriptorKind kind,
                                                          int k) const {
  const ShapeDescriptorSettings& settings = mDatabase->descriptorSettings;
  return matchInFrames(*this, surface, computeCanonicalFrames(surface, settings.frame), settings, kind, k);
}

Result<std::vector<FragmentMatch>> FragmentMatcher::match(const TriangleMesh& surface, const VolumeMoments& moments,
                                                          const Eigen::Vector3d& momentsOriginM, DescriptorKind kind,
                                                          int k) const {
  const ShapeDescriptorSettings& settings = mDatabase->descriptorSettings;
  return matchInFrames(*this, surface, computeCanonicalFrames(surface, moments, momentsOriginM, settings.frame),
                       settings, kind, k);
}

Result<std::vector<FragmentMatch>> FragmentMatcher::matchDescriptors(const CanonicalFrames& frames,
                                                                     const DescriptorMatrix& descriptors,
                                                                     DescriptorKind kind, int k) const {
  const auto& index = mIndices[static_cast<size_t>(kind)];
  if (!index) {
    return makeError(ErrorCode::InvalidArgument,
                     std::string("no index was built for the ") + descriptorKindName(kind) + " descriptor");
  }
  if (k < 1 || k > index->size()) {
    return makeError(ErrorCode::InvalidArgument, "k = " + std::to_string(k) + " is outside [1, " +
                                                     std::to_string(index->size()) + "] (database entries)");
  }
  const auto candidates = static_cast<Eigen::Index>(frames.candidates.size());
  if (candidates == 0 || descriptors.rows() != candidates || descriptors.cols() != index->dims()) {
    return makeError(ErrorCode::InvalidArgument,
                     "expected one " + std::to_string(index->dims()) + "-value descriptor per candidate frame (" +
                         std::to_string(candidates) + "), got " + std::to_string(descriptors.rows()) + " x " +
                         std::to_string(descriptors.cols()));
  }
  // The fragment's candidate frames as one set: each entry at its distance in the nearest frame.
  std::vector<int64_t> ids(static_cast<size_t>(k));
  std::vector<float> squared(ids.size());
  std::vector<int32_t> rows(ids.size());
  if (Status st = index->queryNearestOfSet(descriptors.data(), candidates, k, ids.data(), squared.data(), rows.data(),
                                           !mFramesAsOneSet);
      !st) {
    return st.error();
  }
  std::vector<FragmentMatch> out(static_cast<size_t>(k));
  for (size_t j = 0; j < out.size(); ++j) {
    FragmentMatch& m = out[j];
    m.entry = ids[j];
    m.distance = std::sqrt(std::max(squared[j], 0.0f));
    m.candidate = rows[j];
    m.queryFrame = frames.candidates[static_cast<size_t>(rows[j])];
  }
  const MatchErrorModel& model = mDatabase->matchErrors[static_cast<size_t>(kind)];
  for (FragmentMatch& m : out) m.predictedError = predictMatchError(model, m.distance);
  return out;
}

}  // namespace brittle
