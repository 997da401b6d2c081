// Calibration.h — fitting a material to measurements of a real object (Ceres).
//
// The object is free (hung on soft strings or laid on foam, as for a tap test) and meshed as
// brittle meshes it (a pack object), with the pack object's element order and mass model: a fit
// must use the model the runtime will run, or it absorbs that model's discretisation error into
// the material (a P2 plate fitted with P1 tets, which lock in bending, gets half its E). Two fits, each a bounded nonlinear least-squares problem:
//
// 1. Elastic constants from natural frequencies. For a fixed mesh and density, K(E, ν) = E·K₁(ν)
//    and M does not depend on E or ν, so every eigenvalue is λᵢ = (E/E₀)·λᵢ(E₀, ν): one modal
//    solve (ModalAnalysis.h) per trial ν gives all frequencies for every E. The residuals are the
//    relative frequency errors (fᵢ − f̂ᵢ)/f̂ᵢ of the lowest measured modes, matched by rank (the
//    i-th lowest measured frequency to the i-th lowest elastic mode). The unknowns are log(E/E₀),
//    which keeps E positive and well scaled, and ν, bounded to [νmin, νmax]. The Jacobian is
//    analytic: ∂fᵢ/∂log E = fᵢ/2, and ∂λᵢ/∂ν = φᵢᵀ (∂K/∂ν) φᵢ for mass-normalised φᵢ (the
//    eigenvalue derivative of a symmetric pencil), with ∂K/∂ν from assembling K at ν ± h.
//    ν is only identifiable when the measured modes mix kinds (bending and torsion, say):
//    frequency ratios depend on ν alone. With fitPoissonRatio = false, ν is kept and one
//    frequency is enough.
// 2. Rayleigh damping from decay rates. A mode's amplitude envelope decays as e^{−σt} with
//    σᵢ = ζᵢωᵢ = (α + β ωᵢ²)/2; α, β ≥ 0 are fitted to the measured σ̂ᵢ at the measured ωᵢ
//    (relative residuals). Linear in α and β, so one Gauss-Newton step finds it; Ceres handles
//    the bounds.
// Uncertainty: the parameters' 1σ come from Ceres' covariance (JᵀJ)⁻¹ scaled by the residual
// variance 2·cost/(n − p); NaN when there are no more measurements than parameters.
// Everything else of the base material (strength, fracture energy, restitution) is kept: these
// measurements do not determine it. G_c is kept as an energy, not re-derived from a toughness.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "brittle/database/Material.h"
#include "brittle/database/ObjectAsset.h"
#include "brittle/core/Result.h"
#include "brittle/precompute/Progress.h"

namespace brittle {

struct CalibrationMeasurements {
  /// Natural frequencies (Hz) of the lowest elastic modes of the free object, ascending: the
  /// first is the lowest elastic mode, with no gaps (a missed mode shifts every later match).
  std::vector<double> frequenciesHz;
  /// Optional: the amplitude decay rate σ (1/s) of each of those modes (same count), or empty.
  std::vector<double> decayRatesPerS;
  /// Optional: the measured mass (kg). When > 0 the density becomes mass / mesh volume, since the
  /// frequencies give E/ρ, not E; otherwise the base material's density is kept.
  double massKg = 0.0;
};

struct CalibrationSettings {
  bool fitPoissonRatio = true;  ///< false: ν stays the base material's, E alone is fitted
  double poissonMin = 0.0;      ///< bounds on ν (brittle solids: 0.1–0.35)
  double poissonMax = 0.45;
  /// Elastic modes solved per trial ν; 0 means the number of frequencies + 4, so that the lowest
  /// modes are converged ones.
  int modeCount = 0;
  int maxIterations = 50;       ///< Levenberg-Marquardt iterations per fit
  uint64_t seed = 1;            ///< ARPACK's starting vector
  /// The object's FEM model (ObjectAsset::elementOrder and ::lumpedMass): the one the pack runs.
  ElementOrder elementOrder = ElementOrder::P1;
  bool lumpedMass = false;
};

struct CalibrationResult {
  Material material;                         ///< the base material with E, ν, ρ, α, β fitted
  double youngsModulusStdPa = 0.0;           ///< 1σ of E (NaN: no redundancy)
  double poissonRatioStd = 0.0;              ///< 1σ of ν (0 when ν is not fitted)
  double alphaStdPerS = 0.0;                 ///< 1σ of α (0 without decay rates)
  double betaStdS = 0.0;                     ///< 1σ of β
  std::vector<double> modelFrequenciesHz;    ///< of the fitted material, one per measurement
  std::vector<double> frequencyErrors;       ///< (model − measured) / measured
  std::vector<double> modelDecayRatesPerS;   ///< (α + β ω²)/2 at the measured ω (empty without rates)
  std::vector<double> decayRateErrors;       ///< (model − measured) / measured
  double rmsFrequencyError = 0.0;            ///< RMS of frequencyErrors
  double rmsDecayRateError = 0.0;            ///< RMS of decayRateErrors (0 without rates)
  bool poissonAtBound = false;               ///< ν ended on a bound: the data asked for more
  int iterations = 0;                        ///< Levenberg-Marquardt iterations, both fits
  int modalSolves = 0;                       ///< ARPACK solves (one per trial ν)
  double seconds = 0.0;                      ///< wall time of the whole calibration
};

/// Fits `base` to the measurements of the object meshed by `mesh`.
/// Errors: InvalidArgument (no frequencies; fewer than two when ν is fitted; a frequency or
/// decay rate not finite and positive; frequencies not ascending; decay-rate count differs; a
/// non-positive or non-finite mass; bounds outside (−1, 0.5) or empty; base ν outside the
/// bounds), InvalidMaterial (base), DegenerateElement, FactorizationFailed, EigenNotConverged,
/// RigidModeMismatch (from the modal solve), Cancelled (progress interrupted).
Result<CalibrationResult> calibrateMaterial(const TetMesh& mesh, const Material& base,
                                            const CalibrationMeasurements& measurements,
                                            const CalibrationSettings& settings, ProgressSink* progress = nullptr);

/// The lowest `count` elastic natural frequencies (Hz) of `mesh` made of `material` (ARPACK), with
/// `order` elements and the consistent (or lumped) mass: what a tap test on the model would
/// measure. Errors as makeFemMesh and computeModes.
Result<std::vector<double>> naturalFrequenciesHz(const TetMesh& mesh, const Material& material, int count,
                                                 uint64_t seed = 1, ElementOrder order = ElementOrder::P1,
                                                 bool lumpedMass = false);

}  // namespace brittle
