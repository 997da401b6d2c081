// FragmentMatcher.h — nearest database entries to a query solid, and the transform that places
// each entry onto it.
//
// A query surface is reduced to its canonical frame candidates (CanonicalFrame.h) and one
// descriptor per candidate. Each candidate is searched in the kind's index; an entry found from
// several candidates keeps its smallest distance and that candidate's frame. Ties break by the
// lower entry id, so results are deterministic for a given index.
//
// Placement: entry point x̂ (canonical, unit volume) lies at frame.toQuery(x̂) in the query frame,
// where frame is FragmentMatch::queryFrame. instantiateEntry (ScalingLaws.h) uses the same frame
// to rescale the entry's physical data to the query's size and material.
#pragma once

#include <array>
#include <optional>
#include <vector>

#include "brittle/database/DescriptorIndex.h"
#include "brittle/database/FragmentDatabase.h"
#include "brittle/database/MatchErrors.h"
#include "brittle/descriptors/CanonicalFrame.h"
#include "brittle/core/Result.h"

namespace brittle {

struct FragmentMatch {
  int64_t entry = -1;          ///< row in FragmentDatabase::entries
  float distance = 0.0f;       ///< Euclidean descriptor distance (not squared)
  int candidate = 0;           ///< which of the query's candidate frames matched
  CanonicalFrame queryFrame;   ///< query → canonical; its inverse places the entry on the query
  /// The relative error of the entry's first three frequencies expected at this distance, from the
  /// database's calibration (MatchErrors.h); NaN when the database has none.
  MatchErrorPrediction predictedError;
};

struct FragmentMatcherSettings {
  /// Per kind: index settings that override the database's stored ones (nullopt: use stored).
  std::array<std::optional<DescriptorIndexSettings>, kDescriptorKindCount> indexOverride;
  /// Kinds to build indices for; the others cannot be queried.
  std::array<bool, kDescriptorKindCount> enabled = {true, true, true};
  /// Search only the first entryLimit entries (0: all). A smaller database answers faster and
  /// matches worse; the search benchmark sweeps it.
  int64_t entryLimit = 0;
  /// A fragment's candidate frames (one to four) searched as one set, in one walk of a graph index
  /// (DescriptorIndex::queryNearestOfSet), instead of one search per frame, merged. The exact and
  /// kd-forest indices give the same answer either way. On a graph, a fragment with several frames
  /// costs about one search, but the frames share one beam. Measured on moment descriptors: at 10⁴
  /// entries the p99 falls by 45 % at the same recall, and at 10⁵ the recall falls from 0.993 to
  /// 0.985 with no gain in the median (docs/results/fragment-database.md). So it is off by default.
  bool framesAsOneSet = false;
};

class FragmentMatcher {
 public:
  /// Builds one index per enabled kind over the database's descriptor matrices (read now, for a
  /// database read on demand, and dropped once indexed). The database is referenced, not copied:
  /// it must outlive the matcher.
  /// Errors: InvalidArgument (empty database, bad index settings), those of DescriptorIndex::build,
  /// the pack's read errors of a matrix read on demand.
  static Result<FragmentMatcher> build(const FragmentDatabase& database, const FragmentMatcherSettings& settings = {});

  /// The k best entries for the solid bounded by `surface` (closed, outward, metres), nearest
  /// first, k ≤ entry count. Errors: InvalidArgument (k out of range, kind not enabled, zero volume,
  /// inward surface), EmptyMesh, NonFiniteValue, OpenMesh (as computeCanonicalFrames).
  Result<std::vector<FragmentMatch>> match(const TriangleMesh& surface, DescriptorKind kind, int k) const;

  /// Same, with the solid's moments given (order ≥ 4, about momentsOriginM; the runtime sums them
  /// over the fragment's tets and cut cells): the frames and the moment descriptor then need no
  /// pass over the surface's faces (the voxel kinds still fill it). Same answer up to rounding.
  Result<std::vector<FragmentMatch>> match(const TriangleMesh& surface, const VolumeMoments& moments,
                                           const Eigen::Vector3d& momentsOriginM, DescriptorKind kind, int k) const;

  /// Same, from frames and descriptors already computed (one descriptor row per candidate frame,
  /// computed with the database's descriptor settings).
  Result<std::vector<FragmentMatch>> matchDescriptors(const CanonicalFrames& frames,
                                                      const DescriptorMatrix& descriptors, DescriptorKind kind,
                                                      int k) const;

  const FragmentDatabase& database() const { return *mDatabase; }
  const DescriptorIndex* index(DescriptorKind kind) const {
    const auto& i = mIndices[static_cast<size_t>(kind)];
    return i ? &*i : nullptr;
  }

 private:
  FragmentMatcher() = default;
  const FragmentDatabase* mDatabase = nullptr;
  bool mFramesAsOneSet = false;
  std::array<std::optional<DescriptorIndex>, kDescriptorKindCount> mIndices;
};

}  // namespace brittle
