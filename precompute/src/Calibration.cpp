// Calibration.cpp — calibrateMaterial (Calibration.h). Ceres stays in this translation unit.
#include "brittle/precompute/Calibration.h"

#include <ceres/ceres.h>

#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <optional>

#include "brittle/core/Timing.h"
#include "brittle/descriptors/MassProperties.h"
#include "brittle/precompute/ModalAnalysis.h"
#include "brittle/runtime/FemAssembly.h"

namespace brittle {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kTwoPi = 2.0 * std::numbers::pi;
// Step of the central difference of K in ν. K is rational in ν with poles at −1 and 0.5, so the
// truncation error is ~1e-10 relative and the rounding error ~1e-11.
constexpr double kPoissonStep = 1e-5;

bool finitePositive(double v) { return std::isfinite(v) && v > 0.0; }

// The eigenvalues λᵢ(ν) of the mesh made of the reference material with Poisson ratio ν, and
// their derivatives in ν, from one modal solve per distinct ν (cached: Ceres evaluates the same
// point more than once).
class PoissonSweep {
 public:
  struct Sample {
    std::vector<double> eigenvalues;   // rad²/s², the `count` lowest elastic ones
    std::vector<double> derivatives;   // ∂λᵢ/∂ν
  };

  PoissonSweep(const FemMesh& mesh, FemSettings fem, Material reference, int count, int modeCount, uint64_t seed,
               ProgressSink* progress)
      : mMesh(mesh), mFem(fem), mReference(std::move(reference)), mCount(count), mModeCount(modeCount), mSeed(seed),
        mProgress(progress) {}

  /// The sample at ν, or nullptr after an error (kept in error()).
  const Sample* at(double nu) {
    if (const auto it = mCache.find(nu); it != mCache.end()) return &it->second;
    if (mError) return nullptr;
    if (isInterrupted(mProgress)) return fail(makeError(ErrorCode::Cancelled, "calibration cancelled"));
    Material material = mReference;
    material.poissonRatio = nu;
    auto system = assembleFem(mMesh, material, mFem);
    if (!system) return fail(system.error());
    ModalSettings modal;
    modal.modeCount = mModeCount;
    modal.shiftRad2PerS2 = defaultShift(mMesh.nodes(), material);
    modal.seed = mSeed;
    auto modes = computeModes(system.value(), mMesh.nodes(), modal);
    if (!modes) return fail(modes.error());
    ++mSolves;
    reportProgress(mProgress, "calibrate", std::min(1.0, mSolves / 20.0));

    // ∂K/∂ν by a central difference of the assembly (M does not depend on ν).
    Material plus = material, minus = material;
    plus.poissonRatio += kPoissonStep;
    minus.poissonRatio -= kPoissonStep;
    auto kPlus = assembleFem(mMesh, plus, mFem);
    auto kMinus = assembleFem(mMesh, minus, mFem);
    if (!kPlus) return fail(kPlus.error());
    if (!kMinus) return fail(kMinus.error());
    const SparseMatrixd dK = (kPlus.value().stiffness - kMinus.value().stiffness) / (2.0 * kPoissonStep);

    const ModalBasis& basis = modes.value().basis;
    Sample sample;
    for (int i = 0; i < mCount; ++i) {
      const Eigen::VectorXd phi = basis.modes.col(i);
      sample.eigenvalues.push_back(basis.eigenvaluesRad2PerS2(i));
      sample.derivatives.push_back(phi.dot(dK * phi));
    }
    return &mCache.emplace(nu, std::move(sample)).first->second;
  }

  const std::optional<Error>& error() const { return mError; }
  int solves() const { return mSolves; }
  double referenceModulusPa() const { return mReference.youngsModulusPa; }

 private:
  const Sample* fail(Error error) {
    mError = std::move(error);
    return nullptr;
  }

  const FemMesh& mMesh;
  FemSettings mFem;
  Material mReference;
  int mCount, mModeCount;
  uint64_t mSeed;
  ProgressSink* mProgress;
  std::map<double, Sample> mCache;
  std::optional<Error> mError;
  int mSolves = 0;
};

// Residuals (fᵢ − f̂ᵢ)/f̂ᵢ with fᵢ = √(e^s λᵢ(ν)) / 2π; parameters s = log(E/E₀) and ν.
class FrequencyCost final : public ceres::CostFunction {
 public:
  FrequencyCost(PoissonSweep& sweep, const std::vector<double>& measuredHz) : mSweep(sweep), mMeasured(measuredHz) {
    set_num_residuals(static_cast<int>(measuredHz.size()));
    mutable_parameter_block_sizes()->assign({1, 1});
  }

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    const double scale = std::exp(parameters[0][0]);
    const PoissonSweep::Sample* sample = mSweep.at(parameters[1][0]);
    if (!sample) return false;
    for (size_t i = 0; i < mMeasured.size(); ++i) {
      const double lambda = scale * sample->eigenvalues[i];
      if (!(lambda > 0.0)) return false;
      const double f = std::sqrt(lambda) / kTwoPi;
      residuals[i] = (f - mMeasured[i]) / mMeasured[i];
      if (jacobians && jacobians[0]) jacobians[0][i] = 0.5 * f / mMeasured[i];
      // df/dλ = 1 / (8π² f).
      if (jacobians && jacobians[1]) jacobians[1][i] = scale * sample->derivatives[i] / (2.0 * kTwoPi * kTwoPi * f) / mMeasured[i];
    }
    return true;
  }

 private:
  PoissonSweep& mSweep;
  const std::vector<double>& mMeasured;
};

// (σ̄ (a + b ωᵢ²/ω̄²) − σ̂ᵢ)/σ̂ᵢ: α = 2σ̄a and β = 2σ̄b/ω̄², scaled so that a and b are O(1).
struct DecayResidual {
  double omegaSquaredRatio;
  double measured;
  double meanRate;
  template <typename T>
  bool operator()(const T* a, const T* b, T* residual) const {
    residual[0] = (meanRate * (a[0] + b[0] * omegaSquaredRatio) - measured) / measured;
    return true;
  }
};

class StopWhenInterrupted final : public ceres::IterationCallback {
 public:
  explicit StopWhenInterrupted(ProgressSink* progress) : mProgress(progress) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary&) override {
    return isInterrupted(mProgress) ? ceres::SOLVER_ABORT : ceres::SOLVER_CONTINUE;
  }

 private:
  ProgressSink* mProgress;
};

ceres::Solver::Options solverOptions(int maxIterations, ceres::IterationCallback* callback) {
  ceres::Solver::Options options;
  options.minimizer_type = ceres::TRUST_REGION;
  options.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  options.linear_solver_type = ceres::DENSE_QR;
  options.max_num_iterations = maxIterations;
  options.function_tolerance = 1e-14;
  options.gradient_tolerance = 1e-14;
  options.parameter_tolerance = 1e-12;
  options.logging_type = ceres::SILENT;
  options.minimizer_progress_to_stdout = false;
  options.num_threads = 1;
  options.callbacks.push_back(callback);
  options.update_state_every_iteration = false;
  return options;
}

// 1σ of the free scalar blocks, from (JᵀJ)⁻¹ scaled by the residual variance; NaN without
// redundancy or when the covariance is rank deficient.
std::vector<double> standardDeviations(ceres::Problem& problem, const std::vector<double*>& blocks, double cost,
                                       int residualCount) {
  std::vector<double> out(blocks.size(), kNaN);
  const int dof = residualCount - static_cast<int>(blocks.size());
  if (dof <= 0) return out;
  ceres::Covariance::Options options;
  options.num_threads = 1;
  ceres::Covariance covariance(options);
  std::vector<std::pair<const double*, const double*>> pairs;
  for (double* block : blocks) pairs.emplace_back(block, block);
  if (!covariance.Compute(pairs, &problem)) return out;
  const double variance = 2.0 * cost / dof;
  for (size_t i = 0; i < blocks.size(); ++i) {
    double c = kNaN;
    if (covariance.GetCovarianceBlock(blocks[i], blocks[i], &c) && c >= 0.0) out[i] = std::sqrt(c * variance);
  }
  return out;
}

double rms(const std::vector<double>& values) {
  double sum = 0.0;
  for (double v : values) sum += v * v;
  return values.empty() ? 0.0 : std::sqrt(sum / static_cast<double>(values.size()));
}

Status checkInputs(const TetMesh& mesh, const Material& base, const CalibrationMeasurements& m,
                   const CalibrationSettings& s) {
  auto invalid = [](const std::string& what) { return makeError(ErrorCode::InvalidArgument, "calibration: " + what); };
  if (Status valid = validateMaterial(base); !valid) return valid.error();
  if (mesh.tets.rows() == 0) return invalid("the mesh has no tetrahedra");
  const size_t needed = s.fitPoissonRatio ? 2 : 1;
  if (m.frequenciesHz.size() < needed) {
    return invalid("needs at least " + std::to_string(needed) + " measured frequencies" +
                   (s.fitPoissonRatio ? " to fit both E and the Poisson ratio (or keep the ratio fixed)" : ""));
  }
  for (size_t i = 0; i < m.frequenciesHz.size(); ++i) {
    if (!finitePositive(m.frequenciesHz[i])) return invalid("frequency " + std::to_string(i) + " is not finite and positive");
    if (i > 0 && m.frequenciesHz[i] < m.frequenciesHz[i - 1]) {
      return invalid("frequencies must be ascending (the lowest modes in order); frequency " + std::to_string(i) +
                     " is below the one before");
    }
  }
  if (!m.decayRatesPerS.empty() && m.decayRatesPerS.size() != m.frequenciesHz.size()) {
    return invalid(std::to_string(m.decayRatesPerS.size()) + " decay rates for " +
                   std::to_string(m.frequenciesHz.size()) + " frequencies (one per frequency, or none)");
  }
  for (size_t i = 0; i < m.decayRatesPerS.size(); ++i) {
    if (!finitePositive(m.decayRatesPerS[i])) return invalid("decay rate " + std::to_string(i) + " is not finite and positive");
  }
  if (!std::isfinite(m.massKg) || m.massKg < 0.0) return invalid("the mass must be finite and positive (or 0: not measured)");
  if (!(s.poissonMin > -1.0 && s.poissonMax < 0.5 && s.poissonMin < s.poissonMax)) {
    return invalid("Poisson ratio bounds must satisfy -1 < min < max < 0.5");
  }
  if (s.fitPoissonRatio && (base.poissonRatio < s.poissonMin || base.poissonRatio > s.poissonMax)) {
    return invalid("the base material's Poisson ratio lies outside the bounds");
  }
  if (s.modeCount < 0 || s.maxIterations < 1) return invalid("modeCount must be ≥ 0 and maxIterations ≥ 1");
  if (s.modeCount > 0 && static_cast<size_t>(s.modeCount) < m.frequenciesHz.size()) {
    return invalid("modeCount is below the number of measured frequencies");
  }
  return Ok{};
}

}  // namespace

Result<std::vector<double>> naturalFrequenciesHz(const TetMesh& mesh, const Material& material, int count, uint64_t seed,
                                                 ElementOrder order, bool lumpedMass) {
  auto femMesh = makeFemMesh(mesh, order);
  if (!femMesh) return femMesh.error();
  auto system = assembleFem(femMesh.value(), material, FemSettings{.lumpedMass = lumpedMass});
  if (!system) return system.error();
  ModalSettings modal;
  modal.modeCount = count;
  modal.shiftRad2PerS2 = defaultShift(femMesh.value().nodes(), material);
  modal.seed = seed;
  auto modes = computeModes(system.value(), femMesh.value().nodes(), modal);
  if (!modes) return modes.error();
  const Eigen::VectorXd& f = modes.value().basis.frequenciesHz;
  return std::vector<double>(f.data(), f.data() + f.size());
}

Result<CalibrationResult> calibrateMaterial(const TetMesh& mesh, const Material& base,
                                            const CalibrationMeasurements& measurements,
                                            const CalibrationSettings& settings, ProgressSink* progress) {
  const auto started = SteadyClock::now();
  if (Status ok = checkInputs(mesh, base, measurements, settings); !ok) return ok.error();
  const std::vector<double>& measuredHz = measurements.frequenciesHz;
  const int count = static_cast<int>(measuredHz.size());

  CalibrationResult result;
  Material reference = base;
  if (measurements.massKg > 0.0) reference.densityKgPerM3 = measurements.massKg / computeTetMassProperties(mesh, 1.0).volumeM3;
  auto femMesh = makeFemMesh(mesh, settings.elementOrder);
  if (!femMesh) return femMesh.error();
  PoissonSweep sweep(femMesh.value(), FemSettings{.lumpedMass = settings.lumpedMass}, reference, count,
                     settings.modeCount > 0 ? settings.modeCount : count + 4, settings.seed, progress);
  StopWhenInterrupted stop(progress);

  // 1. E (and ν). Start from the base ν and the E that fits best at it (closed form in √(E/E₀)).
  double nu = base.poissonRatio;
  const PoissonSweep::Sample* start = sweep.at(nu);
  if (!start) return *sweep.error();
  double num = 0.0, den = 0.0;
  for (int i = 0; i < count; ++i) {
    const double ratio = std::sqrt(std::max(start->eigenvalues[i], 0.0)) / kTwoPi / measuredHz[i];
    num += ratio;
    den += ratio * ratio;
  }
  if (!(num > 0.0 && den > 0.0)) return makeError(ErrorCode::EigenNotConverged, "calibration: non-positive eigenvalues");
  double logScale = 2.0 * std::log(num / den);

  {
    ceres::Problem::Options problemOptions;
    problemOptions.cost_function_ownership = ceres::TAKE_OWNERSHIP;
    ceres::Problem problem(problemOptions);
    problem.AddResidualBlock(new FrequencyCost(sweep, measuredHz), nullptr, &logScale, &nu);
    if (settings.fitPoissonRatio) {
      problem.SetParameterLowerBound(&nu, 0, settings.poissonMin);
      problem.SetParameterUpperBound(&nu, 0, settings.poissonMax);
    } else {
      problem.SetParameterBlockConstant(&nu);
    }
    ceres::Solver::Summary summary;
    ceres::Solve(solverOptions(settings.maxIterations, &stop), &problem, &summary);
    if (sweep.error()) return *sweep.error();
    if (isInterrupted(progress)) return makeError(ErrorCode::Cancelled, "calibration cancelled");
    if (!summary.IsSolutionUsable()) {
      return makeError(ErrorCode::EigenNotConverged, "calibration: the frequency fit failed: " + summary.message);
    }
    result.iterations += static_cast<int>(summary.iterations.size()) - 1;
    std::vector<double*> free = {&logScale};
    if (settings.fitPoissonRatio) free.push_back(&nu);
    const std::vector<double> sigma = standardDeviations(problem, free, summary.final_cost, count);
    if (sweep.error()) return *sweep.error();
    const double modulus = sweep.referenceModulusPa() * std::exp(logScale);
    result.youngsModulusStdPa = modulus * sigma[0];  // dE = E d(log E)
    result.poissonRatioStd = settings.fitPoissonRatio ? sigma[1] : 0.0;
    result.poissonAtBound = settings.fitPoissonRatio && (nu <= settings.poissonMin + 1e-9 || nu >= settings.poissonMax - 1e-9);
    result.material = reference;
    result.material.youngsModulusPa = modulus;
    result.material.poissonRatio = nu;
  }
  const PoissonSweep::Sample* fitted = sweep.at(nu);
  if (!fitted) return *sweep.error();
  for (int i = 0; i < count; ++i) {
    const double f = std::sqrt(std::exp(logScale) * fitted->eigenvalues[i]) / kTwoPi;
    result.modelFrequenciesHz.push_back(f);
    result.frequencyErrors.push_back((f - measuredHz[i]) / measuredHz[i]);
  }
  result.rmsFrequencyError = rms(result.frequencyErrors);

  // 2. Rayleigh damping at the measured ω. One rate fixes β alone (α = 0, as the presets).
  const std::vector<double>& rates = measurements.decayRatesPerS;
  if (!rates.empty()) {
    double meanRate = 0.0, meanOmega2 = 0.0;
    for (int i = 0; i < count; ++i) {
      meanRate += rates[i] / count;
      meanOmega2 += std::pow(kTwoPi * measuredHz[i], 2) / count;
    }
    double a = rates.size() >= 2 ? 0.5 : 0.0, b = 0.5;
    ceres::Problem problem;
    for (int i = 0; i < count; ++i) {
      const double ratio = std::pow(kTwoPi * measuredHz[i], 2) / meanOmega2;
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<DecayResidual, 1, 1, 1>(
                                   new DecayResidual{ratio, rates[i], meanRate}),
                               nullptr, &a, &b);
    }
    problem.SetParameterLowerBound(&b, 0, 0.0);
    std::vector<double*> free = {&b};
    if (rates.size() >= 2) {
      problem.SetParameterLowerBound(&a, 0, 0.0);
      free.insert(free.begin(), &a);
    } else {
      problem.SetParameterBlockConstant(&a);
    }
    ceres::Solver::Summary summary;
    ceres::Solve(solverOptions(settings.maxIterations, &stop), &problem, &summary);
    if (isInterrupted(progress)) return makeError(ErrorCode::Cancelled, "calibration cancelled");
    if (!summary.IsSolutionUsable()) {
      return makeError(ErrorCode::InvalidArgument, "calibration: the damping fit failed: " + summary.message);
    }
    result.iterations += static_cast<int>(summary.iterations.size()) - 1;
    const std::vector<double> sigma = standardDeviations(problem, free, summary.final_cost, count);
    result.material.rayleighAlphaPerS = 2.0 * meanRate * a;
    result.material.rayleighBetaS = 2.0 * meanRate * b / meanOmega2;
    result.alphaStdPerS = rates.size() >= 2 ? 2.0 * meanRate * sigma[0] : 0.0;
    result.betaStdS = 2.0 * meanRate * sigma.back() / meanOmega2;
    for (int i = 0; i < count; ++i) {
      const double omega2 = std::pow(kTwoPi * measuredHz[i], 2);
      const double model = 0.5 * (result.material.rayleighAlphaPerS + result.material.rayleighBetaS * omega2);
      result.modelDecayRatesPerS.push_back(model);
      result.decayRateErrors.push_back((model - rates[i]) / rates[i]);
    }
    result.rmsDecayRateError = rms(result.decayRateErrors);
  }

  result.material.source = "calibrated from " + std::to_string(count) + " measured frequencies" +
                           (rates.empty() ? "" : " and decay rates") +
                           (measurements.massKg > 0.0 ? " and the mass" : "") + " (brittle calibrate); base: " +
                           base.name + " (" + base.source + ")";
  if (Status valid = validateMaterial(result.material); !valid) return valid.error();
  result.modalSolves = sweep.solves();
  result.seconds = secondsSince(started);
  reportProgress(progress, "calibrate", 1.0);
  return result;
}

}  // namespace brittle
