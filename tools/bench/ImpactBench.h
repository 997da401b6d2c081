// ImpactBench.h — impact-event latency of the runtime, behind `brittle bench impact`.
//
// For each target tet count × mode count it bakes a glass slab (0.2 × 0.2 × 0.05 m: thick enough
// to mesh at 1k tets), places it in a warm world (pack loaded, K factorised) and hits it
// `impacts` times with a 100 g steel ball at random points of its top face, at `speedMps`. Each impact is timed per stage; the same impacts without pruning
// are timed in the same run as the reference. Output: one CSV row per setting and stage with the
// median and p99 (ms), and the pruned/unpruned ratio of the medians.
//
// With a database (`databasePack`: a pack whose fragment database is used, e.g. the default pack's
// 70 entries or a 10⁴-entry one from bake-db), fragments become objects as in a scene: the exact
// path up to exactModesMaxTets, the database match beyond. The stage "matching" is what the impact
// itself spends on them (the fragment's solid, the database search); "bodies" is making their
// modal data afterwards (World: on its workers; here on the caller's thread, one worker, so that
// it is timed), and "to_objects" the sum: contact to every fragment a breakable object.
#pragma once

#include <cstdint>
#include <filesystem>
#include <vector>

#include "brittle/core/Result.h"
#include "brittle/database/ObjectAsset.h"
#include "brittle/runtime/World.h"

namespace brittle::bench {

struct ImpactBenchSettings {
  std::vector<int64_t> tets = {1000, 5000, 20000};
  std::vector<int> modes = {20, 40};
  int impacts = 30;
  double speedMps = 50.0;   // breaks the slab every time (5 fragments on average at 1k tets)
  uint64_t seed = 1;
  std::filesystem::path csv = "docs/results/data/impact_latency.csv";
  std::filesystem::path databasePack;  ///< empty: no database, fragments stay surfaces
  /// How the database's entries are read: on demand, as the runtime commands read a pack, or
  /// whole (every entry in memory before the first impact), to compare the two.
  EntryReading databaseReading = EntryReading::OnDemand;
  int exactModesMaxTets = 150;         ///< with a database: the World's default
  int polynomialModeDegree = FractureSettings{}.polynomialModeDegree;  ///< matched bodies' own frequencies (0: the entries')
  int meshRatioMaxDof = FractureSettings{}.meshRatioMaxDof;            ///< ... corrected by their own mesh up to this size (0: never)
  ElementOrder elementOrder = ElementOrder::P1;  ///< the slab's element (P2: thin parts' accuracy)
  /// The World's worker threads (0: one per core). The impact's parallel stages (the seed scan,
  /// surfaces beside moments, new bodies) use them; with 1 an impact runs on this thread alone.
  int threads = 0;
  /// The scans timed: pruned by the stress bounds (the World's default), unpruned (every element
  /// at every instant, the reference), or both.
  std::vector<bool> pruning = {true, false};
  /// How cracks meet: crossing each other (false, the World's default) or ending at one another
  /// (true, CrackSettings::endAtCracks), or both; a row each.
  std::vector<bool> crackEnds = {false};
  bool quiet = false;
};

/// Errors: those of the bake and the runtime, PackIoError when the CSV cannot be written.
Status runImpactBench(const ImpactBenchSettings& settings);

/// `brittle bench place PACK`: what placing each pack object costs the caller (World::addObject,
/// its first instance: topology, stress bounds; the K factorisation starts on a worker), against
/// the reference measured in the same run, reading the object's bytes from the pack (the pack's
/// read time shared out by the objects' array bytes), and the background preparation it starts;
/// then what destroying a World costs its host when it is prepared (freeing its memory) and a
/// quarter, half and three quarters into the preparation (which it stops), against the preparation
/// left then, which the destructor waited for before.
struct PlacementBenchSettings {
  std::filesystem::path pack;
  int repeats = 5;  ///< medians over this many fresh worlds
  std::filesystem::path csv = "docs/results/data/placement.csv";
};
Status runPlacementBench(const PlacementBenchSettings& settings);

}  // namespace brittle::bench
