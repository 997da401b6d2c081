// ElementBench.h — linear (P1) against quadratic (P2) tetrahedra: the first frequency's error
// against the degrees of freedom, and the impact time against that error, behind
// `brittle bench elements` (chart: tools/scripts/plot_elements.py).
//
// Each case is one surface and material with a converged first frequency known independently:
//   plate  0.3 × 0.3 × 0.01 m glass: 389.4 Hz, CalculiX C3D10 at 41k elements (PlateFrequencyTest);
//   beam   1 × 0.1 × 0.1 m glass: 526.0 Hz, the first bending pair, CalculiX C3D10 converged
//          (BeamFrequencyTest);
//   brick  the bundled brick, concrete: 4 267.0 Hz, brittle's P2 at 9 833 tets (accuracy.md).
// Each case is baked in each order at each of its tet targets through the real pipeline (Mesh_3,
// FEM, ARPACK), and `impacts` steel-ball impacts at `speedMps` are timed on it in a World (points
// drawn by area with drawSceneImpacts, each on a fresh copy of the object whose static correction
// was built at placement, so that the time is an impact's and not a placement's).
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "brittle/core/Result.h"

namespace brittle::bench {

struct ElementBenchSettings {
  std::vector<std::string> cases = {"plate", "beam", "brick"};
  std::filesystem::path brickMesh = "assets/meshes/brick.off";
  int modes = 40;         ///< modes baked and used by the impacts (the default pack's)
  int impacts = 5;        ///< impacts timed per mesh (median)
  double speedMps = 10.0;
  uint64_t seed = 1;
  /// Tet targets per order; empty: each case's own ladder (ElementBench.cpp).
  std::vector<int64_t> p1Tets, p2Tets;
  std::filesystem::path csv = "docs/results/data/elements.csv";
  bool quiet = false;
};

/// Errors: those of the bake and the runtime; InvalidArgument (an unknown case, modes or impacts
/// < 1, a speed not finite and positive); PackIoError (CSV).
Status runElementBench(const ElementBenchSettings& settings);

}  // namespace brittle::bench
