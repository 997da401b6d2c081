// ModeCountBench.h — the number of modes against the peak-stress error and the impact time,
// with and without the static correction, behind `brittle bench modes` (chart:
// tools/scripts/plot_modes.py).
//
// The reference case of the static correction: a free 0.3 × 0.3 × 0.01 m glass plate hit by a
// 100 g steel ball of 20 mm at `speedMps`, at several points of its top face. The plate is baked
// once with the largest mode count; each impact uses the lowest r modes (FractureSettings::
// modeCount), on a fresh world, and reports the peak principal stress with the correction and
// the truncated model's own peak. The reference is the full-FEM implicit Newmark solution on the
// same mesh under the same pulse and load (FullFemReference.h), solved once per point. The impact
// time is the median of `repeats` impacts (warm world: K already factorised), fracture included.
#pragma once

#include <cstdint>
#include <filesystem>
#include <vector>

#include "brittle/core/Result.h"

namespace brittle::bench {

struct ModeCountBenchSettings {
  std::vector<int> modes = {5, 10, 20, 40, 60, 100, 150, 200};
  int64_t tets = 3000;
  int points = 3;             ///< impact points: the centre, then seeded random points of the top face
  double speedMps = 5.0;
  int repeats = 5;
  int referenceStepsPerContact = 60;
  uint64_t seed = 1;
  std::filesystem::path csv = "docs/results/data/modes.csv";
  bool quiet = false;
};

/// Errors: those of the bake, the runtime and the reference solver; PackIoError (CSV).
Status runModeCountBench(const ModeCountBenchSettings& settings);

}  // namespace brittle::bench
