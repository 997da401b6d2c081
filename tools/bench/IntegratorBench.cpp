#include "IntegratorBench.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <numbers>

#include "brittle/core/Timing.h"
#include "brittle/precompute/ModalIntegrators.h"
#include "brittle/runtime/ModalResponse.h"

namespace brittle::bench {
namespace {

constexpr ModalIntegrator kIntegrators[] = {ModalIntegrator::Exact, ModalIntegrator::ExplicitEuler,
                                            ModalIntegrator::SymplecticEuler, ModalIntegrator::ImplicitEuler};
constexpr double kPulseS = 1e-4;

double halfSine(double t) { return t < kPulseS ? std::sin(std::numbers::pi * t / kPulseS) : 0.0; }

// A grid of equal steps h over [0, 11 pulses] and the half-sine sampled on it.
void grid(double h, std::vector<double>& t, std::vector<double>& f) {
  const auto steps = static_cast<int>(std::lround(11.0 * kPulseS / h));
  t.clear();
  f.clear();
  for (int k = 0; k <= steps; ++k) {
    t.push_back(k * h);
    f.push_back(halfSine(t.back()));
  }
}

double maxAbs(const Eigen::MatrixXd& q, Eigen::Index from, Eigen::Index stride = 1) {
  double m = 0.0;
  for (Eigen::Index k = from; k < q.rows(); k += stride) {
    // A blown-up scheme reaches inf, then NaN (inf − inf): both count as infinitely large.
    if (!std::isfinite(q(k, 0))) return std::numeric_limits<double>::infinity();
    m = std::max(m, std::abs(q(k, 0)));
  }
  return m;
}

}  // namespace

Status runIntegratorBench(const IntegratorBenchSettings& s) {
  std::ofstream csv(s.csv);
  if (!csv) return makeError(ErrorCode::PackIoError, "cannot write " + s.csv.string());
  csv << "integrator,zeta,omega_h,steps_per_period,peak_error,late_amplitude\n";
  const double h = kPulseS / s.pulseSteps;
  std::vector<double> t, f, tr, fr;
  grid(h, t, f);
  const Eigen::VectorXd load = Eigen::VectorXd::Ones(1);
  for (double zeta : s.dampingRatios) {
    for (int i = 0; i < s.points; ++i) {
      const double wh = 0.01 * std::pow(1e4, i / double(s.points - 1));
      const double w = wh / h;
      // The reference: 256 sub-steps per step, and at least 64 per period.
      const int sub = std::max(256, static_cast<int>(std::ceil(64.0 * wh / (2.0 * std::numbers::pi))));
      grid(h / sub, tr, fr);
      Eigen::MatrixXd ref, q;
      const Eigen::VectorXd omega = Eigen::VectorXd::Constant(1, w), damping = Eigen::VectorXd::Constant(1, zeta);
      if (Status st = integrateModalResponse(omega, damping, load, tr, fr, ref); !st) return st;
      Eigen::MatrixXd refOnGrid(static_cast<Eigen::Index>(t.size()), 1);
      for (Eigen::Index k = 0; k < refOnGrid.rows(); ++k) refOnGrid(k, 0) = ref(std::min(k * sub, ref.rows() - 1), 0);
      const Eigen::Index late = refOnGrid.rows() * 9 / 10;
      for (ModalIntegrator integrator : kIntegrators) {
        if (Status st = integrateModalResponse(omega, damping, load, t, f, q, integrator); !st) return st;
        const double peakError = maxAbs(q - refOnGrid, 0) / maxAbs(refOnGrid, 0);
        const double lateAmplitude = maxAbs(q, late) / maxAbs(refOnGrid, 0);
        csv << modalIntegratorName(integrator) << "," << zeta << "," << wh << "," << 2.0 * std::numbers::pi / wh << ","
            << peakError << "," << lateAmplitude << "\n";
      }
    }
  }
  if (!csv.flush()) return makeError(ErrorCode::PackIoError, "cannot write " + s.csv.string());

  // Cost: 200 modes from 100 Hz to 100 kHz on the grid, median of the repeats.
  std::ofstream timing(s.timingCsv);
  if (!timing) return makeError(ErrorCode::PackIoError, "cannot write " + s.timingCsv.string());
  timing << "integrator,modes,steps,median_s,ns_per_mode_step,ratio_to_exact\n";
  const int modes = 200;
  Eigen::VectorXd omega(modes), damping = Eigen::VectorXd::Constant(modes, 0.01), loads = Eigen::VectorXd::Ones(modes);
  for (int j = 0; j < modes; ++j) omega(j) = 2.0 * std::numbers::pi * 100.0 * std::pow(1e3, j / double(modes - 1));
  double exactMedian = 0.0;
  Eigen::MatrixXd q;
  for (ModalIntegrator integrator : kIntegrators) {
    std::vector<double> seconds;
    for (int rep = 0; rep < s.timingRepeats; ++rep) {
      const auto start = SteadyClock::now();
      if (Status st = integrateModalResponse(omega, damping, loads, t, f, q, integrator); !st) return st;
      seconds.push_back(secondsSince(start));
    }
    std::nth_element(seconds.begin(), seconds.begin() + seconds.size() / 2, seconds.end());
    const double median = seconds[seconds.size() / 2];
    if (integrator == ModalIntegrator::Exact) exactMedian = median;
    timing << modalIntegratorName(integrator) << "," << modes << "," << t.size() - 1 << "," << median << ","
           << 1e9 * median / (modes * double(t.size() - 1)) << "," << median / exactMedian << "\n";
  }
  if (!timing.flush()) return makeError(ErrorCode::PackIoError, "cannot write " + s.timingCsv.string());
  return Ok{};
}

}  // namespace brittle::bench
