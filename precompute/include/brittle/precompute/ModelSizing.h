// ModelSizing.h — the cheapest model that meets an accuracy target over a scene's impacts
// (the scene's requirements: SceneRequirements.h; what its fragments need: FragmentSizing.h).
//
// Sizing an object: it is baked once with the largest mode count of the ladder; impacts are drawn
// from the scene's range (`points` seeded draws × each impactor × the lowest and the highest speed
// — the two ends of the contact time t_c ∝ v^(−1/5)): a sphere hits a surface point drawn by
// area along the face's normal; the ground meets the body at its lowest node for an orientation
// drawn uniformly, as a body dropped at random lands on a corner. Each is solved once by
// the full-FEM reference (FullFemReference.h) and, for every mode count of the ladder, by the
// runtime with the static correction (the lowest r modes of the same basis). The chosen count is
// the smallest whose worst error over the impacts meets the target; when none does, the largest
// is kept and the result says so. The peak stress is linear in the load, so the error does not
// depend on the speed except through the pulse's length and shape, which the two ends bracket.
#pragma once

#include <cstdint>
#include <filesystem>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "brittle/database/Material.h"
#include "brittle/database/ObjectAsset.h"
#include "brittle/core/Result.h"
#include "brittle/precompute/BakePipeline.h"
#include "brittle/precompute/FragmentDatabaseBake.h"
#include "brittle/precompute/FragmentSizing.h"
#include "brittle/precompute/Progress.h"
#include "brittle/precompute/SceneRequirements.h"
#include "brittle/runtime/World.h"

namespace brittle {

/// One mode count of the ladder.
struct ModeTrial {
  int modes = 0;
  double worstError = 0.0;      ///< max over the impacts of |σ / σ_reference − 1|
  double medianImpactMs = 0.0;  ///< the runtime's impact time (warm world, fracture included)
};

/// One element order tried for an object (ModelSizingSettings::elementOrders).
struct ElementTrial {
  ElementOrder elementOrder = ElementOrder::P1;
  double firstFrequencyHz = 0.0;  ///< the lowest elastic mode
  double frequencyError = 0.0;    ///< relative, against P2 on the same tets (0 for P2 itself)
  int chosenModes = 0;            ///< the peak-stress sizing's, in this order
  bool targetMet = false;         ///< both targets
  double impactValues = 0.0;      ///< values an impact reads at chosenModes (the cost compared)
  double medianImpactMs = 0.0;    ///< the runtime's impact time at chosenModes (reported only)
};

struct ObjectSizing {
  std::string object;
  ElementOrder elementOrder = ElementOrder::P1;  ///< the order sized (the chosen one, when several were tried)
  int chosenModes = 0;
  bool targetMet = false;
  double chosenError = 0.0;       ///< worst error at the chosen count
  int impacts = 0;                ///< impacts each count was measured on
  double referenceS = 0.0;        ///< time spent in the full-FEM reference
  std::vector<ModeTrial> trials;  ///< the ladder, ascending (counts above the stored modes dropped)
  std::vector<ElementTrial> elementTrials;  ///< the orders tried, in settings order (empty: one order)
};

/// Sizes one object whose asset holds at least the ladder's first count of modes (baked with its
/// largest). Errors: InvalidArgument (settings, an asset with fewer modes than the ladder's first
/// count), those of the runtime and of solveFullFemImpact.
Result<ObjectSizing> sizeObjectModes(const ObjectAsset& asset, const Material& material, const SceneObjectRange& range,
                                     double targetError, const ModelSizingSettings& settings = {},
                                     ProgressSink* progress = nullptr);

/// The impacts sizeObjectModes measures: `points` seeded draws × each impactor × the lowest and the
/// highest speed (one speed when they are equal), in the asset's frame. For a sphere, a point
/// drawn by area along its face's normal; for the ground, the lowest node for a uniformly drawn
/// direction. The object id is left unset.
std::vector<ImpactDesc> drawSceneImpacts(const ObjectAsset& asset, const SceneObjectRange& range, int points, uint64_t seed);

/// The sized pack's frequency-error calibration at the scene's impacts (ModelSizingSettings::
/// frequencyErrorPoints; FrequencyErrorCalibration.h).
struct FrequencyErrorSizing {
  bool calibrated = false;      ///< false: the pack holds no models (`note` says why)
  std::string note;
  int impacts = 0;
  std::vector<std::pair<std::string, int>> piecesPerObject;  ///< the scene's objects, in its order
  int ritzBins = 0, checkedBins = 0, checkedP2Bins = 0;
  double seconds = 0.0;
};

/// A whole scene: what the sized pack saves against the all-maximum one (every manifest object
/// at the ladder's largest count, and the manifest's database).
struct SceneSizingReport {
  double targetError = 0.0;
  double matchTargetError = 0.0;           ///< SceneRequirements::matchFrequencyError
  double frequencyTargetError = 0.0;       ///< ModelSizingSettings::frequencyErrorTarget (0: one order)
  bool refracture = true;
  std::vector<ObjectSizing> objects;       ///< the scene's, in its order
  std::vector<std::string> skippedObjects; ///< manifest objects the scene does not use
  double maximumBakeS = 0.0, sizedBakeS = 0.0;  ///< objects and database, each side baked for real
  double databaseBakeS = 0.0;                   ///< the database's share (once; reused by the sized side)
  int64_t maximumPackBytes = 0, sizedPackBytes = 0;
  double maximumImpactMs = 0.0, sizedImpactMs = 0.0;  ///< sums over the scene's objects of the median impact
  std::vector<DebrisSizing> debris;        ///< per scene object
  double debrisVolumeFraction = 0.01;      ///< the scene's: the smallest over its objects
  std::optional<SearchSizing> search;      ///< when the sized pack keeps a database
  std::optional<FrequencyErrorSizing> frequencyErrors;  ///< when it keeps one and frequencyErrorPoints > 0
  double fragmentSizingS = 0.0;            ///< time spent on sceneFragments and chooseSearch
  bool allMet() const {
    for (const auto& o : objects) {
      if (!o.targetMet) return false;
    }
    return true;
  }
};

struct SceneSizingPaths {
  std::filesystem::path sizedPack;    ///< written atomically
  std::filesystem::path maximumPack;  ///< empty: written beside sizedPack to be measured, then removed
};

/// Bakes the all-maximum pack, sizes every scene object on it, then bakes the sized pack: the
/// scene's objects at their chosen counts, plus the database when the scene refractures, with its
/// bodies' frequency errors calibrated at the scene's impacts (a scene whose impacts break off no
/// measurable piece gets none: FrequencyErrorSizing::note). Both
/// packs are written (writePack, atomic) to measure their size. With several element orders
/// (ModelSizingSettings::elementOrders), each scene object is also baked and sized in each, and
/// its cheapest order that meets both targets is the one sized and kept. Errors: InvalidArgument
/// (a scene object the manifest lacks, listing those it has; an order listed twice; several
/// orders without p2; a frequency target outside (0, 1)), those of bakePack,
/// bakeFragmentDatabase, sizeObjectModes and writePack.
Result<SceneSizingReport> sizeScene(const std::vector<ObjectBakeSettings>& manifest,
                                    const std::optional<DatabaseBakeSettings>& database,
                                    const SceneRequirements& requirements, const SceneSizingPaths& paths,
                                    const ModelSizingSettings& settings = {}, ProgressSink* progress = nullptr);

/// Writes the bake manifest of the sized pack: `manifest`'s JSON with only the scene's objects,
/// each with its chosen "modes" and "element", and without the "database" section unless the scene
/// refractures; relative file names are rewritten for `out`'s directory, so that
/// `brittle bake --manifest out` bakes the sized pack. Errors: FileNotFound, ParseError,
/// PackIoError (writing).
Status writeSizedManifest(const std::filesystem::path& manifest, const SceneSizingReport& report,
                          const std::filesystem::path& out);

}  // namespace brittle
