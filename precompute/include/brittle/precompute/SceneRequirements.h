// SceneRequirements.h — what a scene asks of its pack (read by loadSceneRequirements), and the
// settings of the sizing that answers it (ModelSizing.h, FragmentSizing.h).
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
#pragma once

#include <cstdint>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "brittle/core/Result.h"
#include "brittle/database/Material.h"
#include "brittle/database/ObjectAsset.h"

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
  /// Neighbouring modes whose frequencies differ by less than this (relative) are one cluster, and
  /// a ladder count that would keep part of a cluster is raised to keep all of it: a body of
  /// revolution's or a square's pairs of equal frequencies, split by the mesh by a fraction of a
  /// percent, give a basis that answers a hit by the direction it comes from when one of the pair
  /// is kept without the other (the default vase's modes 30 and 31, 11 278.0 and 11 286.9 Hz, at
  /// the ladder's 30). 0: counts are kept as given.
  double modeClusterGap = 0.005;
  int points = 3;                    ///< surface points per impactor and speed
  /// Search precisions tried: factors on the `checks` of the index the database stores for each
  /// kind (a graph's ef, an inverted file's lists probed, a kd-forest's checks); 0: the exact search.
  std::vector<double> searchPrecision = {0.25, 1.0, 4.0, 0.0};
  int fragmentsPerImpact = 12;       ///< fragments studied per top-speed impact, spread over their sizes
  int referenceStepsPerContact = 60; ///< Newmark steps per contact time
  int timingRepeats = 3;             ///< impacts timed per mode count and impact (median)
  uint64_t seed = 1;
  /// Element orders tried for each scene object; empty keeps each manifest object's own. With
  /// more than one, every scene object is baked and sized in each order (the same tets: the
  /// mesher does not depend on the order) and the cheapest that meets both targets is kept:
  /// the peak-stress target at its chosen mode count, and frequencyErrorTarget on its first
  /// frequency. That error is estimated against P2 on the same tets, so P2 must be among them:
  /// P2's eigenvalue error falls as h⁴ where P1's falls as h² (and P1 locks in bending), so the
  /// difference is P1's error to within P2's own. Cheapest means the fewest values an impact
  /// reads, stress modes and modes at the chosen count (6 per stress point and 3 per FEM node,
  /// per mode): the impact times, which follow them, are measured and reported, but a choice made
  /// on a timing would make the pack depend on the machine's load.
  std::vector<ElementOrder> elementOrders;
  double frequencyErrorTarget = 0.02;  ///< the first frequency's allowed error (relative)
  /// The sized pack's bodies' frequency-error models (FrequencyErrorCalibration.h), fitted to the
  /// pieces of the scene's own impacts, when it keeps a database: `frequencyErrorPoints` surface
  /// points per impactor, at both ends of each object's speed range (0: not calibrated; the pack
  /// then predicts no body's error and escalates nothing).
  int frequencyErrorPoints = 4;
  int frequencyErrorPiecesPerImpact = 8;  ///< pieces measured per impact, spread over their sizes
};

}  // namespace brittle
