// FractureStatsBench.h — fracture statistics against impact speed over many seeds, behind
// `brittle bench fracture` (chart: tools/scripts/plot_fracture.py).
//
// Two standard cases, each baked once through the real pipeline:
//   plate  a free 0.3 × 0.3 × 0.01 m glass plate hit by a 100 g steel ball of 20 mm, at a point
//          drawn within `jitterM` of the centre;
//   brick  the bundled concrete brick dropped on the ground (immovable, flat) on one of its eight
//          corners, drawn by the seed, with the normal along the corner's diagonal.
// For each speed and seed, a fresh world (WorldSettings::seed = the seed) takes one impact and the
// CSV records whether the body broke, the number of fragments (all, and those above the debris
// threshold), the largest fragment's share of the mass and the impact time. The spread over seeds
// comes from both the point and the crack noise; a seed gives the same row on every run.
#pragma once

#include <cstdint>
#include <filesystem>
#include <vector>

#include "brittle/core/Result.h"

namespace brittle::bench {

struct FractureStatsBenchSettings {
  std::vector<double> plateSpeedsMps = {1, 2, 3, 5, 8, 12, 20, 30, 50};
  std::vector<double> brickSpeedsMps = {0.5, 1, 2, 3, 5, 8, 12, 20, 50};
  int seeds = 32;
  int64_t plateTets = 3000;
  int64_t brickTets = 3000;
  int modes = 40;  // the bake default (ModalSettings)
  double jitterM = 0.03;
  std::filesystem::path brickMesh = "assets/meshes/brick.off";
  std::filesystem::path csv = "docs/results/data/fracture.csv";
  bool quiet = false;
};

/// Errors: those of the bake and the runtime; InvalidArgument (no speeds, seeds < 1, a speed ≤ 0);
/// PackIoError (CSV).
Status runFractureStatsBench(const FractureStatsBenchSettings& settings);

}  // namespace brittle::bench
