// EntryCache.h — what a database entry gives every fragment matched to it, derived once: its tet
// connectivity (per entry) and its basis at a Poisson ratio other than the database's (per entry
// and ν). Private to the runtime: the World owns one per database, matched fragments' bodies read
// it on the workers (ImpactStages.cpp), and EntryCorrections builds its corrections from it.
//
// A matched fragment's body is its entry placed (ScalingLaws.h). Of that work, the Rayleigh–Ritz
// correction for ν ≠ ν₀ and the tet connectivity (hash maps over the entry's tets and faces)
// depend on the entry and ν alone, not on the fragment's size, pose or frequencies, and they were
// a third of the CPU a matched body cost (measured on the main job's vase hit: the correction 27 %
// of the body making, the connectivity 9–14 %). Built on first use by whichever worker needs it
// (others wait), kept for the World's life: ~0.1–1 MB an (entry, ν) for the default database's
// 1k-tet, 12-mode entries, only for the entries matched. Results are the same bits as without it.
#pragma once

#include <atomic>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <utility>

#include "brittle/core/Result.h"
#include "brittle/database/FragmentDatabase.h"
#include "brittle/database/ScalingLaws.h"
#include "brittle/runtime/TetTopology.h"

namespace brittle::detail {

class EntryCache {
 public:
  /// `database` outlives this.
  explicit EntryCache(const FragmentDatabase& database) : mDatabase(database) {}

  /// Entry `entry`'s tet topology (of its own mesh: the connectivity is what a placed copy shares,
  /// buildTetTopology(mesh, sameTets)). Errors: those of buildTetTopology, InvalidArgument (an
  /// entry out of range).
  const Result<TetTopology>& topology(int32_t entry) const;
  /// entryAtPoisson(entry, the database's reference material, ν). Errors: those of
  /// entryAtPoisson, InvalidArgument (an entry out of range).
  const Result<EntryAtPoisson>& atPoisson(int32_t entry, double poissonRatio) const;
  /// instantiateEntry of entry `entry` in `target` at `frame`, with the basis at target's ν from
  /// this cache where ν differs from the database's (atPoisson): every placement of a database
  /// entry in the runtime goes through here. Errors: those of atPoisson and instantiateEntry,
  /// InvalidArgument (an entry out of range).
  Result<ObjectAsset> place(int32_t entry, const Material& target, const CanonicalFrame& frame) const;
  /// How many topologies and bases are built so far, failed ones included.
  int32_t built() const { return mBuilt.load(std::memory_order_acquire); }

 private:
  template <class T>
  struct Slot {
    std::once_flag once;
    std::optional<Result<T>> value;
  };
  template <class T, class Key, class Make>
  const Result<T>& get(std::map<Key, std::unique_ptr<Slot<T>>>& slots, const Key& key, int32_t entry, Make&& make) const;

  const FragmentDatabase& mDatabase;
  mutable std::mutex mMutex;  // guards the maps' structure; each slot is built under its own once_flag
  mutable std::map<int32_t, std::unique_ptr<Slot<TetTopology>>> mTopologies;
  mutable std::map<std::pair<int32_t, double>, std::unique_ptr<Slot<EntryAtPoisson>>> mBases;
  mutable std::atomic<int32_t> mBuilt{0};
};

}  // namespace brittle::detail
