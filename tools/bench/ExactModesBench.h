// ExactModesBench.h — chart 5: a fragment's database match against its own modal analysis at
// runtime (the exact path, FragmentModes.h), per fragment size, behind `brittle bench exact-modes`
// (chart: tools/scripts/plot_exact_modes.py).
//
// Each object of a pack (a database is needed) is hit `seeds` times at each speed by a steel ball
// at a surface point drawn by the seed. For each fragment that is not debris (up to
// maxFragmentsPerImpact, largest first), the CSV records:
//   * the database path: descriptor match and rescaling of the entry (FragmentMatcher, ScalingLaws),
//     its time and its first three frequencies;
//   * the exact path: the fragment's tets in the broken body, K and M, modes and stress modes
//     (as many modes as the object has), its time and its first three frequencies;
//   * the reference: the fragment's exact surface baked through the full pipeline (CGAL tets at
//     referenceTets, ARPACK), and the error of each path's first three frequencies against it
//     (the largest relative error of the three, as in the search benchmark).
// The runtime's default exactModesMaxTets comes from where the exact path's median time crosses
// the budget the chart states.
#pragma once

#include <cstdint>
#include <filesystem>
#include <vector>

#include "brittle/descriptors/Result.h"

namespace brittle::bench {

struct ExactModesBenchSettings {
  std::filesystem::path pack = "out/default.h5";
  std::vector<std::string> objects;              ///< empty: every object of the pack
  std::vector<double> speedsMps = {10, 30};
  int seeds = 3;
  int maxFragmentsPerImpact = 6;
  int64_t referenceTets = 3000;                  ///< of the reference bake of each fragment
  int repeats = 3;                               ///< timings: the median of this many runs
  std::filesystem::path csv = "bench/exact_modes.csv";
  bool quiet = false;
};

/// Errors: those of readPack, World and the bake; InvalidArgument (no database in the pack, an
/// unknown object, no speeds, seeds < 1); PackIoError (CSV).
Status runExactModesBench(const ExactModesBenchSettings& settings);

}  // namespace brittle::bench
