// IntegratorBench.h — error and stability of the modal time integrators against the time step,
// behind `brittle bench integrators` (chart: tools/scripts/plot_integrators.py).
//
// The runtime samples the contact force on a grid that resolves the pulse (pulseSteps over the
// contact time), so its low modes get many steps per period and its highest ones fewer than one.
// This bench keeps such a grid (a 100 µs half-sine pulse in `pulseSteps` steps, then a ring-down
// of 10 pulse lengths at the same step h) and sweeps the mode's ω so that ωh runs from 0.01 to
// 100. For each integrator (ModalResponse.h) and damping ratio it reports, at the grid instants:
//   peak_error        max |q − q_ref| / max |q_ref| (q_ref: the exact map on a grid 256 times finer,
//                     and at least 64 steps per period: the response to the continuous half-sine);
//   late_amplitude    max |q| over the last tenth of the window / max |q_ref| over all of it
//                     (> 1: the free vibration grew; ≫ 1: unstable);
// and, per integrator, the median time of one integration of 200 modes (ns per mode and step),
// against the exact map measured in the same run.
#pragma once

#include <cstdint>
#include <filesystem>
#include <vector>

#include "brittle/core/Result.h"

namespace brittle::bench {

struct IntegratorBenchSettings {
  std::vector<double> dampingRatios = {0.001, 0.05};
  int pulseSteps = 16;
  int points = 41;              ///< ωh values, log-spaced over [0.01, 100]
  int timingRepeats = 21;
  std::filesystem::path csv = "docs/results/data/integrators.csv";
  std::filesystem::path timingCsv = "docs/results/data/integrator_timing.csv";
};

/// Errors: PackIoError when a CSV cannot be written.
Status runIntegratorBench(const IntegratorBenchSettings& settings);

}  // namespace brittle::bench
