// ResolutionBench.h — tet resolution against frequency error and bake time, behind
// `brittle bench resolution` (chart: tools/scripts/plot_resolution.py).
//
// Bakes one surface (default: the bundled brick, concrete) at each target tet count through the
// real pipeline (Mesh_3, P1 FEM, ARPACK) and compares its lowest `modes` elastic frequencies
// with a reference: the Richardson extrapolation of the two finest meshes, taking the P1
// eigenvalue error as O(h²) with h ∝ tets^(−1/3). The finest mesh's own error is thus an
// estimate, and the CSV also gives every mesh's difference from the finest one. Bake time is the
// pipeline's total (meshing, assembly, modes, stress modes) from the asset's record.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "brittle/core/Result.h"

namespace brittle::bench {

struct ResolutionBenchSettings {
  std::filesystem::path mesh = "assets/meshes/brick.off";
  std::string material = "concrete";
  std::vector<int64_t> tets = {300, 1000, 3000, 10000, 30000, 100000};
  int modes = 10;
  std::filesystem::path csv = "docs/results/data/resolution.csv";
  bool quiet = false;
};

/// Errors: those of the bake; InvalidArgument (fewer than two tet counts, modes < 1);
/// PackIoError (CSV).
Status runResolutionBench(const ResolutionBenchSettings& settings);

}  // namespace brittle::bench
