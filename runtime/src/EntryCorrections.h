// EntryCorrections.h — the static corrections of a pack's database entries, one per entry and
// material, each shared by every fragment matched to that entry (StaticCorrection::placed).
// Private to the runtime: ImpactStages.cpp's matched fragments adopt them, the World owns them.
//
// A matched fragment is its entry placed (ScalingLaws.h: x = L R x̂ + t, the target material):
// its K + μM is the entry's at unit size with that material, scaled by L and rotated. So the
// entry's correction is factorised once, on first use, by whichever thread needs it (others
// wait), and a fragment's correction costs no factorisation. Built once per (entry, material),
// kept for the most recently matched ones (SharedSlots.h): what the fragment's own factorisation
// would give, within rounding.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>

#include "brittle/core/Result.h"
#include "brittle/database/FragmentDatabase.h"
#include "brittle/database/Material.h"
#include "brittle/runtime/StaticCorrection.h"
#include "EntryCache.h"
#include "SharedSlots.h"

namespace brittle::detail {

class EntryCorrections {
 public:
  /// `cache` (the same database's entries, placed with the bases the matched bodies share)
  /// outlives this. capacity: the (entry, material) corrections kept, the least recently used
  /// dropped first; 0: no bound (WorldSettings::entryCacheCapacity).
  explicit EntryCorrections(const EntryCache& cache, size_t capacity = 0) : mCache(cache), mSlots(capacity) {}

  /// Entry `entry`'s correction at unit size in `material` over its first `modes` modes (the
  /// matched body's count, the same for every fragment of an entry in one World), built on first
  /// use. Errors: those of instantiateEntry and StaticCorrection::build, InvalidArgument (an entry
  /// out of range).
  std::shared_ptr<const Result<StaticCorrection>> get(int32_t entry, const Material& material, int modes) const;
  /// How many (entry, material) corrections are built so far, failed and rebuilt ones included.
  int32_t built() const { return mSlots.built(); }
  /// How many are kept now.
  size_t held() const { return mSlots.size(); }

 private:
  const EntryCache& mCache;
  mutable SharedSlots<std::pair<int32_t, std::string>, StaticCorrection> mSlots;
};

}  // namespace brittle::detail
