// FragmentSizing.h — what a scene's fragments need (part of the sizing of ModelSizing.h).
//
// sceneFragments, chooseDebrisThreshold, chooseSearch: every impact of the scene at its top speed
// breaks the object (at its chosen modes, no debris threshold); each fragment gets its own modes by the runtime's exact path (FragmentModes.h) and
// is hit again, at one drawn point, by each of the scene's impactors at the top speed.
//   * Debris threshold: half the volume fraction of the smallest fragment that broke again
//     (nothing smaller would break in this scene, so it can be rigid), within [0.001, 0.5]; 0.5
//     when none broke. The scene's threshold is the smallest over its objects.
//   * Descriptor and search precision: each descriptor kind of the database × each precision of
//     the ladder (kd-forest checks, and the exact search) matches every fragment; the error is the
//     largest relative error of the match's first three frequencies against the fragment's own
//     modes, and the time covers descriptors, search and rescaling. The choice is the fastest
//     (median) trial whose median error meets matchFrequencyError, else the most accurate, and
//     the result says which. The sized pack's database stores the chosen index settings.
#pragma once

#include <Eigen/Core>
#include <limits>
#include <string>
#include <vector>

#include "brittle/core/MeshTypes.h"
#include "brittle/core/Result.h"
#include "brittle/database/DescriptorIndex.h"
#include "brittle/database/FragmentDatabase.h"
#include "brittle/database/Material.h"
#include "brittle/database/ObjectAsset.h"
#include "brittle/precompute/Progress.h"
#include "brittle/precompute/SceneRequirements.h"

namespace brittle {

/// One fragment of the scene (see the header comment).
struct FragmentRecord {
  std::string object;                 ///< the scene object it came from
  std::string material;
  double volumeFraction = 0.0;        ///< of the object
  bool brokeAgain = false;
  TriangleMesh surface;               ///< closed, outward, object frame (m)
  Eigen::Vector3d frequenciesHz = Eigen::Vector3d::Zero();  ///< first three of its own modes
};

/// Errors: InvalidArgument (settings, range), those of the runtime.
Result<std::vector<FragmentRecord>> sceneFragments(const ObjectAsset& asset, const Material& material,
                                                   const SceneObjectRange& range, int modes,
                                                   const ModelSizingSettings& settings = {},
                                                   ProgressSink* progress = nullptr);

struct DebrisSizing {
  std::string object;
  int fragments = 0, brokeAgain = 0;
  double smallestBrokenFraction = std::numeric_limits<double>::quiet_NaN();  ///< NaN: none broke again
  double debrisVolumeFraction = 0.5;  ///< chosen
};
DebrisSizing chooseDebrisThreshold(const std::string& object, const std::vector<FragmentRecord>& fragments);

struct SearchTrial {
  DescriptorKind kind = DescriptorKind::Moment;
  int checks = 0;                     ///< kd-forest checks; 0: the exact search
  int matched = 0;                    ///< fragments matched (a frame can be undefined)
  double medianFrequencyError = std::numeric_limits<double>::quiet_NaN();
  /// Descriptor values compared per frame's query: rows compared (the kd-forest's checks, at
  /// most the entries; every entry for the exact search) × the descriptor's width. What the
  /// choice weighs, since it is the same in every run (a measured time is not).
  double valuesCompared = 0.0;
  double medianMatchMs = 0.0;  ///< measured and reported, not weighed
  /// Per matched fragment: the match's descriptor distance and its error against the fragment's
  /// own first three frequencies (what MatchErrors.h's models are fitted to).
  std::vector<std::pair<double, double>> distanceErrors;
};

struct SearchSizing {
  DescriptorKind kind = DescriptorKind::Moment;
  int checks = 0;
  bool targetMet = false;
  double medianFrequencyError = std::numeric_limits<double>::quiet_NaN();
  double medianMatchMs = 0.0;
  int fragments = 0;
  std::vector<SearchTrial> trials;
  std::vector<std::pair<double, double>> distanceErrors;  ///< the chosen trial's
  /// The index settings the sized pack stores for the chosen kind.
  DescriptorIndexSettings indexSettings() const;
};

/// Errors: InvalidArgument (empty database or fragment list, a fragment whose material is not in
/// `materials`), those of FragmentMatcher::build.
Result<SearchSizing> chooseSearch(const FragmentDatabase& database, const std::vector<FragmentRecord>& fragments,
                                  const std::vector<Material>& materials, double targetError,
                                  const ModelSizingSettings& settings = {});

}  // namespace brittle
