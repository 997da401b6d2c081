// ExactModesBench.h — chart 5: a fragment's database match against its own modal analysis at
// runtime (the exact path, FragmentModes.h), per fragment size, behind `brittle bench exact-modes`
// (chart: tools/scripts/plot_exact_modes.py).
//
// Each object of a pack (a database is needed) is hit `seeds` times at each speed by a steel ball
// at a surface point drawn by the seed. For each fragment that is not debris (up to
// maxFragmentsPerImpact, spread over their sizes from the largest to the smallest), the CSV records:
//   * the database path: descriptor match and rescaling of the entry (FragmentMatcher, ScalingLaws),
//     its time and its first three frequencies;
//   * the exact path: the fragment's tets in the broken body, K and M, modes and stress modes
//     (exactModes modes, as the World's exactModeCount), its time and its first three frequencies;
//   * the reference: the same solid in quadratic (P2) tets on the exact path's mesh, whatever the
//     parent's element (P1 locks in bending: a shard of the P1 vase wall or of a plate is too stiff
//     with it), and the error of each path's first three frequencies against it (the largest
//     relative error of the three, as in the search benchmark). It has the degrees of freedom of
//     P1 on that mesh split 1:8, the reference before P2 (which missed the locking of thin shards).
//     referenceSplit splits the mesh 1:8 under P2 as well, to check the reference's own
//     convergence on smaller fragments. A bake of the fragment's
//     surface through CGAL was tried first: Mesh_3 split most crack-faceted fragments into
//     several pieces at a few thousand tets, so it could not serve as the reference;
//   * the match's predicted error (median, 90th percentile, MatchErrors.h) from the pack's
//     calibration, to chart against the measured one. The pack objects' fragments are held back
//     from that calibration (it saw only the database's entries).
// The runtime's default exactModesMaxTets comes from where the exact path's median time crosses
// the budget the chart states.
#pragma once

#include <cstdint>
#include <filesystem>
#include <vector>

#include "brittle/core/Result.h"
#include "brittle/descriptors/ShapeDescriptors.h"

namespace brittle::bench {

struct ExactModesBenchSettings {
  std::filesystem::path pack = "out/default.h5";
  std::vector<std::string> objects;              ///< empty: every object of the pack
  std::vector<double> speedsMps = {10, 30};
  int seeds = 3;
  int maxFragmentsPerImpact = 8;
  int64_t referenceMaxTets = 20000;              ///< no reference above this many tets (of the split mesh with referenceSplit)
  bool referenceSplit = false;                   ///< the reference on the exact path's mesh split 1:8 (8× the P2 tets)
  int exactModes = 20;                           ///< modes of the exact path (FractureSettings::exactModeCount)
  int repeats = 3;                               ///< timings: the median of this many runs
  DescriptorKind descriptor = DescriptorKind::Moment;  ///< the kind fragments are matched with
  /// Match against the first N entries only, for each N here (0: all), one CSV row per fragment
  /// and N: the match error against the database's size, on the same fragments.
  std::vector<int64_t> entryLimits = {0};
  std::filesystem::path csv = "docs/results/data/exact_modes.csv";
  bool quiet = false;
};

/// Errors: those of readPack and World; InvalidArgument (no database in the pack, an
/// unknown object, no speeds, seeds < 1); PackIoError (CSV).
Status runExactModesBench(const ExactModesBenchSettings& settings);

}  // namespace brittle::bench
