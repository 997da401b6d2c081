// FrequencyErrorCalibration.h — how far a matched body's own frequencies are from its fragment's,
// calibrated on fragments the runtime makes of the pack's own objects, for the pack to store
// (FragmentDatabase::frequencyErrors, MatchErrors.h; World::frequencyError reads it).
//
// A matched body rings at its fragment's polynomial Ritz values (FractureSettings::
// polynomialModeDegree), the lowest three corrected by the fragment's own mesh when it is small
// enough (meshRatioMaxDof, meshRatioLateMaxDof). Neither error depends on the descriptor distance;
// each has an indicator the runtime computes with the frequencies themselves:
//   * Ritz: the values' own convergence from degree p − 2 to p (MatchErrors.h, FrequencyErrorModels);
//   * checked: the mesh's gain over the polynomials (meshGain, FragmentModes.h), for the check in
//     linear tets (`checked`) and in quadratic ones (`checkedP2`; FractureSettings::meshRatioElement,
//     and frequencyErrorTarget's escalation).
// Each pack object (or those named) is hit `seeds` times at each speed by a steel ball at a surface
// point drawn by the seed (seededImpact); for each fragment that is not debris (up to
// maxFragmentsPerImpact, spread over their sizes), the truth is the fragment's solid in quadratic
// tets (its exact-path mesh, P2, three modes: chart 5's reference), and each (indicator, error)
// pair is a sample. The binned models are those of the match errors (fitMatchErrors): equal-count
// bins, median and 90th percentile made non-decreasing in the indicator.
//
// The seeds start at firstSeed (1001), away from those `brittle bench exact-modes` measures (1 to
// its --seeds), so that the bench's fragments are held back from the calibration.
//
// A scene's own impacts instead (`scene`, from a requirements file: `brittle size` and
// `calibrate-errors --scene`): each scene object is hit by impacts drawn as the sizing draws its
// own (drawSceneImpacts, from firstSeed: `seeds` surface points × each impactor × both ends of its
// speed range, a dropped object on its lowest node), so that the prediction is fitted to the pieces the scene
// makes: a brick dropped on the ground breaks differently from one hit by a ball.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "brittle/core/Result.h"
#include "brittle/database/MatchErrors.h"
#include "brittle/database/Pack.h"
#include "brittle/precompute/Progress.h"
#include "brittle/precompute/SceneRequirements.h"
#include "brittle/runtime/CrackPropagation.h"
#include "brittle/runtime/TetTopology.h"
#include "brittle/runtime/World.h"

namespace brittle {

struct FrequencyErrorCalibrationSettings {
  std::vector<std::string> objects;  ///< empty: every object of the pack (or of the scene)
  std::vector<double> speedsMps = {10, 30};  ///< without a scene
  /// Non-empty: the scene's objects (each must be in the pack), hit by its impacts (above); then
  /// `speedsMps` is not used, and `objects`, when given, must be among the scene's.
  std::vector<SceneObjectRange> scene;
  int seeds = 4;                     ///< 4: 113 pieces of the default objects, ~2 min (2: 61, whose p90 covered 0.79 of held-back Ritz errors)
  uint64_t firstSeed = 1001;
  int maxFragmentsPerImpact = 8;
  int degree = 5;                    ///< the runtime's polynomialModeDegree (≥ 3: degree − 2 is the indicator's)
  bool p2Checks = true;              ///< also the check in quadratic tets (checkedP2; ~80 ms a piece)
  int64_t checkMaxDof = 12000;       ///< pieces checked up to this many DOF (the runtime's later limit)
  int64_t referenceMaxTets = 20000;  ///< no truth (the fragment skipped) above this many tets
  MatchErrorSettings bins;
};

/// One fragment's indicators and errors (largest relative error of f1..f3 against the truth).
struct FrequencyErrorSample {
  std::string object;
  double speedMps = 0.0;
  uint64_t seed = 0;
  int fragment = -1;
  int64_t checkDof = 0;        ///< its check's linear DOF (CutCells::Prisms)
  double ritzIndicator = 0.0;  ///< matchFrequencyError of the degree-(p − 2) values against the degree-p ones
  double ritzError = 0.0;
  double checkIndicator = 0.0; ///< meshGain in linear tets; NaN where the piece was not checked
  double checkError = 0.0;     ///< NaN where not checked
  double checkP2Indicator = 0.0;  ///< the same in quadratic tets
  double checkP2Error = 0.0;
  double truthF1Hz = 0.0;
};

struct FrequencyErrorCalibration {
  FrequencyErrorModels models;  ///< ritz from every sample, checked and checkedP2 from the checked ones
  std::vector<FrequencyErrorSample> samples;
  int impacts = 0;  ///< impacts made (an impact that breaks off no piece gives no sample)
  /// The samples of each object broken, in the order broken (0: none had a piece with a truth).
  std::vector<std::pair<std::string, int>> piecesPerObject;
};

/// The impact the calibration and `bench exact-modes` make: a steel ball (a fifth of the
/// object's mass, a twentieth of its diagonal across) on the centroid of a boundary face drawn by
/// the seed, along the face's normal, at `speedMps`.
ImpactDesc seededImpact(const ObjectAsset& asset, ObjectId id, uint64_t seed, double speedMps);

/// The pieces of a break the calibration and `bench exact-modes` measure: the fragments that are
/// not debris, the largest first, at most `count` of them spread evenly over their sizes.
std::vector<size_t> piecesSpreadOverSizes(const ImpactResult& result, int count);

/// The calibration's pieces alone (`models` left empty): every impact made and every piece with a
/// truth measured; none is not an error here. Errors: those of calibrateFrequencyErrors but the
/// last.
Result<FrequencyErrorCalibration> measureFrequencyErrors(const Pack& pack, const FrequencyErrorCalibrationSettings& settings,
                                                         ProgressSink* progress = nullptr);

/// The models fitted to `samples` (FrequencyErrorModels, at settings.degree). Errors:
/// InvalidArgument (settings out of range, no sample), those of fitMatchErrors.
Result<FrequencyErrorModels> fitFrequencyErrors(const std::vector<FrequencyErrorSample>& samples,
                                                const FrequencyErrorCalibrationSettings& settings);

/// The calibration above: measureFrequencyErrors, then fitFrequencyErrors. Progress reports
/// "frequency errors" per impact. Errors: InvalidArgument
/// (settings out of range, an unknown object, a scene object the pack lacks, a pack without objects), those of World, and of
/// fitMatchErrors when fewer samples than one per bin (InvalidArgument: too few fragments; more
/// seeds or speeds give more).
Result<FrequencyErrorCalibration> calibrateFrequencyErrors(const Pack& pack, const FrequencyErrorCalibrationSettings& settings,
                                                           ProgressSink* progress = nullptr);

}  // namespace brittle
