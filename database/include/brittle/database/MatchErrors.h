// MatchErrors.h — how far a database match's physics is from the query's, predicted from the
// descriptor distance, with statistics measured when the database is baked.
//
// Calibration (leave one out). Every entry of a database with physics is a query whose answer is
// known: its own modes. It is searched in the kind's index (the pack's index settings, k = 2) and
// its nearest *other* entry is the match; the error of that match is
//   e = max over j = 1..3 of |f_j(match) − f_j(entry)| / f_j(entry),
// the first three elastic frequencies (entries share the unit volume and the reference material,
// so no rescaling enters). The (distance, error) pairs are sorted by distance and cut into bins of
// equal counts; each bin keeps its upper distance and the median and 90th percentile of its errors.
// Both error curves are made non-decreasing in the distance (a running maximum): a farther match
// is never predicted to be better than a nearer one.
//
// A scene's calibration. `brittle size` breaks the scene's own objects over its impact range and
// matches each fragment against the database, the fragment's own modes being the truth: those
// (distance, error) pairs are queries of the runtime's kind, and the sized pack stores the model
// fitted to them (fitMatchErrors) for the descriptor kind it chose, in place of the leave-one-out one.
//
// Prediction. A match at distance d takes the first bin whose upper distance is ≥ d; beyond the
// last bin, the last bin's errors (an extrapolation, flagged by MatchErrorPrediction::beyondRange).
//
// What it does not know. The calibration's queries are database entries, cut or broken as the
// database was made; the runtime's fragments differ (faceted crack faces, thin necks). How well the
// prediction holds on those is measured, not assumed: `brittle bench exact-modes` charts predicted
// against measured errors on fragments the runtime makes (docs/results/speed-accuracy.md).
#pragma once

#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "brittle/core/Result.h"
#include "brittle/descriptors/ShapeDescriptors.h"

namespace brittle {

struct FragmentDatabase;

struct MatchErrorModel {
  std::vector<double> distance;     ///< per bin: its largest descriptor distance, ascending
  std::vector<double> medianError;  ///< per bin: median relative error of f1..f3, non-decreasing
  std::vector<double> p90Error;     ///< per bin: 90th percentile, non-decreasing, ≥ medianError
  int64_t samples = 0;              ///< entries the model was measured on
  bool empty() const { return distance.empty(); }
};

/// How far a matched body's own frequencies are from its fragment's (the runtime's
/// FractureSettings::polynomialModeDegree and meshRatioMaxDof), against an indicator the runtime
/// computes with them, in place of the descriptor distance (the same binned model):
/// - `ritz`: the Ritz values' own convergence, matchFrequencyError of the degree-(p − 2) values
///   against the degree-p ones (PolynomialModes.h; the lower degree's values lie above, its space
///   being nested in the higher's): a fragment whose frequencies still move from one degree to the
///   next has a part the polynomials do not follow yet;
/// - `checked`: the fragment's mesh's gain over the polynomials, 1 − min over j of its ratio
///   (meshGain, FragmentModes.h), for a body whose Ritz values its mesh corrected in linear tets;
/// - `checkedP2`: the same for a check in quadratic tets (FractureSettings::meshRatioElement, or
///   frequencyErrorTarget's escalation).
/// The truth is the fragment's own solid in quadratic tets; calibrated by breaking the pack's own
/// objects (brittle/precompute/FrequencyErrorCalibration.h). Empty models: not calibrated.
struct FrequencyErrorModels {
  MatchErrorModel ritz;
  MatchErrorModel checked;
  MatchErrorModel checkedP2;
  /// The polynomial degree the models were calibrated at: the runtime uses them only at that
  /// polynomialModeDegree (the indicators move with it). 0 with no models.
  int degree = 0;
  bool empty() const { return ritz.empty() && checked.empty() && checkedP2.empty(); }
};

struct MatchErrorPrediction {
  double median = std::numeric_limits<double>::quiet_NaN();  ///< NaN: the database has no model
  double p90 = std::numeric_limits<double>::quiet_NaN();
  bool beyondRange = false;  ///< the distance is beyond every calibrated one
};

struct MatchErrorSettings {
  int bins = 8;  ///< at most; fewer when there are fewer than 4 samples a bin
};

/// The error of a match: the largest relative error of the first three frequencies of `matchedHz`
/// against `truthHz` (the measure the models, `brittle size` and `bench exact-modes` share). NaN
/// when either has fewer than three.
double matchFrequencyError(const Eigen::VectorXd& matchedHz, const Eigen::VectorXd& truthHz);

/// Leave-one-out calibration of `kind` over `database` (see above). Entries without three modes
/// are skipped. Errors: InvalidArgument (no physics, the kind has no descriptors, fewer than two
/// entries, bins < 1), those of DescriptorIndex::build.
Result<MatchErrorModel> calibrateMatchErrors(const FragmentDatabase& database, DescriptorKind kind,
                                             const MatchErrorSettings& settings = {});

/// The binned model of (descriptor distance, relative error) samples, as above: the leave-one-out
/// calibration's, or a scene's own fragments matched against the database (`brittle size`).
/// Errors: InvalidArgument (no samples, a negative or non-finite one, bins < 1).
Result<MatchErrorModel> fitMatchErrors(std::vector<std::pair<double, double>> samples,
                                       const MatchErrorSettings& settings = {});

/// Calibrates every kind that has descriptors into database.matchErrors when the database has
/// physics and at least two entries; otherwise clears them. Errors: those of calibrateMatchErrors.
Status calibrateDatabaseMatchErrors(FragmentDatabase& database, const MatchErrorSettings& settings = {});

/// The predicted error of a match at descriptor distance `distance` (Euclidean, not squared).
MatchErrorPrediction predictMatchError(const MatchErrorModel& model, double distance);

/// Checks a model read from a pack: equal lengths, at most 1024 bins, finite ascending distances,
/// finite non-decreasing errors with 0 ≤ median ≤ p90. Error: InvalidArgument naming the fault.
Status validateMatchErrorModel(const MatchErrorModel& model);

}  // namespace brittle
