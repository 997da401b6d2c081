// ModelSizing.h — the cheapest model that meets an accuracy target over a scene's impacts.
//
// A scene's requirements file says which objects the scene uses, the range of impacts each one
// takes (speeds and impactors) and the accuracy it needs:
//
//   { "peak_stress_error": 0.15,        // worst |σ_modal / σ_reference − 1| allowed
//     "match_frequency_error": 0.25,     // median error of a matched fragment's first 3 frequencies
//     "refracture": true,                // fragments must break again: the pack needs a database
//     "objects": [
//       { "name": "glass-plate", "speeds_mps": [2, 10],
//         "impactors": [ { "mass_kg": 0.1, "radius_m": 0.02, "material": "steel" } ] },
//       { "name": "brick", "speeds_mps": [3, 12], "impactors": [ { "ground": true } ] } ] }
//
// An impactor is a sphere (mass, radius, material preset or JSON file; default steel) or the
// ground (immovable and flat). Objects the file does not name are not baked.
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
//
// Sizing what the fragments need (sceneFragments, chooseDebrisThreshold, chooseSearch): every
// impact of the scene at its top speed breaks the object (at its chosen modes, no debris
// threshold); each fragment gets its own modes by the runtime's exact path (FragmentModes.h) and
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
#include "brittle/precompute/Progress.h"
#include "brittle/runtime/World.h"

namespace brittle {

struct SceneImpactor {
  double massKg = 0.1;                                          ///< +∞: immovable
  double radiusM = 0.02;                                        ///< +∞: flat
  Material material;                                            ///< steel unless given
  bool ground() const { return massKg == std::numeric_limits<double>::infinity(); }
};

struct SceneObjectRange {
  std::string name;                    ///< an object of the bake manifest
  double minSpeedMps = 1.0, maxSpeedMps = 10.0;
  std::vector<SceneImpactor> impactors;
};

struct SceneRequirements {
  double peakStressError = 0.15;
  /// Median error allowed on a matched fragment's first three frequencies, against the fragment's
  /// own modes ("match_frequency_error"; what picks the descriptor and the search precision).
  double matchFrequencyError = 0.25;
  bool refracture = true;
  std::vector<SceneObjectRange> objects;
};

/// Reads a requirements file. Material file names are relative to its directory.
/// Errors: FileNotFound, ParseError (naming the key: unknown keys, 0 < error < 1, 0 < min ≤ max
/// speed, positive mass and radius, at least one object and impactor, no name twice),
/// UnknownMaterial, InvalidMaterial.
Result<SceneRequirements> loadSceneRequirements(const std::filesystem::path& path);

struct ModelSizingSettings {
  std::vector<int> modeLadder = {5, 10, 15, 20, 30, 40, 60, 80, 100};  ///< ascending after validation
  int points = 3;                    ///< surface points per impactor and speed
  std::vector<int> searchChecks = {4, 16, 64, 0};  ///< kd-forest checks tried (0: the exact search)
  int fragmentsPerImpact = 12;       ///< fragments studied per top-speed impact, spread over their sizes
  int referenceStepsPerContact = 60; ///< Newmark steps per contact time
  int timingRepeats = 3;             ///< impacts timed per mode count and impact (median)
  uint64_t seed = 1;
};

/// One mode count of the ladder.
struct ModeTrial {
  int modes = 0;
  double worstError = 0.0;      ///< max over the impacts of |σ / σ_reference − 1|
  double medianImpactMs = 0.0;  ///< the runtime's impact time (warm world, fracture included)
};

struct ObjectSizing {
  std::string object;
  int chosenModes = 0;
  bool targetMet = false;
  double chosenError = 0.0;       ///< worst error at the chosen count
  int impacts = 0;                ///< impacts each count was measured on
  double referenceS = 0.0;        ///< time spent in the full-FEM reference
  std::vector<ModeTrial> trials;  ///< the ladder, ascending (counts above the stored modes dropped)
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
  double medianMatchMs = 0.0;
};

struct SearchSizing {
  DescriptorKind kind = DescriptorKind::Moment;
  int checks = 0;
  bool targetMet = false;
  double medianFrequencyError = std::numeric_limits<double>::quiet_NaN();
  double medianMatchMs = 0.0;
  int fragments = 0;
  std::vector<SearchTrial> trials;
  /// The index settings the sized pack stores for the chosen kind.
  DescriptorIndexSettings indexSettings() const;
};

/// Errors: InvalidArgument (empty database or fragment list, a fragment whose material is not in
/// `materials`), those of FragmentMatcher::build.
Result<SearchSizing> chooseSearch(const FragmentDatabase& database, const std::vector<FragmentRecord>& fragments,
                                  const std::vector<Material>& materials, double targetError,
                                  const ModelSizingSettings& settings = {});

/// A whole scene: what the sized pack saves against the all-maximum one (every manifest object
/// at the ladder's largest count, and the manifest's database).
struct SceneSizingReport {
  double targetError = 0.0;
  double matchTargetError = 0.0;           ///< SceneRequirements::matchFrequencyError
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
/// scene's objects at their chosen counts, plus the database when the scene refractures. Both
/// packs are written (writePack, atomic) to measure their size. Errors: InvalidArgument (a scene
/// object the manifest lacks, listing those it has), those of bakePack, bakeFragmentDatabase,
/// sizeObjectModes and writePack.
Result<SceneSizingReport> sizeScene(const std::vector<ObjectBakeSettings>& manifest,
                                    const std::optional<DatabaseBakeSettings>& database,
                                    const SceneRequirements& requirements, const SceneSizingPaths& paths,
                                    const ModelSizingSettings& settings = {}, ProgressSink* progress = nullptr);

/// Writes the bake manifest of the sized pack: `manifest`'s JSON with only the scene's objects,
/// each with its chosen "modes", and without the "database" section unless the scene
/// refractures; relative file names are rewritten for `out`'s directory, so that
/// `brittle bake --manifest out` bakes the sized pack. Errors: FileNotFound, ParseError,
/// PackIoError (writing).
Status writeSizedManifest(const std::filesystem::path& manifest, const SceneSizingReport& report,
                          const std::filesystem::path& out);

}  // namespace brittle
