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
// (others wait), kept for the most recently matched entries (SharedSlots.h): ~0.1–1 MB an
// (entry, ν) for the default database's 1k-tet, 12-mode entries. Results are the same bits as
// without it.
//
// A database read on demand (EntryReading::OnDemand, Pack.h) holds no entry's arrays: the cache
// then reads each entry from the pack when it is first matched and keeps it like the rest, so a
// World over a 10⁴-entry pack holds its most recently matched entries instead of all of them.
// Reading is the same for the bits: an entry read on demand equals the one read whole.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <utility>

#include "brittle/core/Result.h"
#include "brittle/database/FragmentDatabase.h"
#include "brittle/database/ScalingLaws.h"
#include "brittle/runtime/TetTopology.h"
#include "SharedSlots.h"

namespace brittle::detail {

class EntryCache {
 public:
  /// `database` outlives this. capacity: the entries kept of each kind (connectivity, and basis
  /// per (entry, ν)), the least recently used dropped first; 0: no bound
  /// (WorldSettings::entryCacheCapacity).
  explicit EntryCache(const FragmentDatabase& database, size_t capacity = 0)
      : mDatabase(database), mEntries(capacity), mTopologies(capacity), mBases(capacity) {}

  /// Entry `entry`'s tet topology (of its own mesh: the connectivity is what a placed copy shares,
  /// buildTetTopology(mesh, sameTets)). Errors: those of buildTetTopology, InvalidArgument (an
  /// entry out of range).
  std::shared_ptr<const Result<TetTopology>> topology(int32_t entry) const;
  /// entryAtPoisson(entry, the database's reference material, ν). Errors: those of
  /// entryAtPoisson, InvalidArgument (an entry out of range).
  std::shared_ptr<const Result<EntryAtPoisson>> atPoisson(int32_t entry, double poissonRatio) const;
  /// instantiateEntry of entry `entry` in `target` at `frame`, with the basis at target's ν from
  /// this cache where ν differs from the database's (atPoisson): every placement of a database
  /// entry in the runtime goes through here. Errors: those of atPoisson and instantiateEntry,
  /// InvalidArgument (an entry out of range).
  Result<ObjectAsset> place(int32_t entry, const Material& target, const CanonicalFrame& frame) const;
  /// How many topologies and bases are built so far, failed and rebuilt ones included.
  int32_t built() const { return mTopologies.built() + mBases.built(); }
  /// How many are kept now.
  size_t held() const { return mTopologies.size() + mBases.size(); }
  /// How many entries were read from the pack so far (a database read on demand), and how many
  /// of them are kept now.
  int32_t entriesRead() const { return mEntries.built(); }
  size_t entriesHeld() const { return mEntries.size(); }

 private:
  // make(entry) for an entry in range, read first if the database holds no arrays; else an
  // InvalidArgument, or the read's error.
  template <class T, class Make>
  Result<T> ofEntry(int32_t entry, Make&& make) const;

  const FragmentDatabase& mDatabase;
  mutable SharedSlots<int32_t, FragmentEntry> mEntries;  // entries read on demand
  mutable SharedSlots<int32_t, TetTopology> mTopologies;
  mutable SharedSlots<std::pair<int32_t, double>, EntryAtPoisson> mBases;
};

}  // namespace brittle::detail
