// EntryCorrections.h — the static corrections of a pack's database entries, one per entry and
// material, each shared by every fragment matched to that entry (StaticCorrection::placed).
// Private to the runtime: ImpactStages.cpp's matched fragments adopt them, the World owns them.
//
// A matched fragment is its entry placed (ScalingLaws.h: x = L R x̂ + t, the target material):
// its K + μM is the entry's at unit size with that material, scaled by L and rotated. So the
// entry's correction is factorised once, on first use, by whichever thread needs it (others
// wait), and a fragment's correction costs no factorisation. Built once per (entry, material):
// what the fragment's own factorisation would give, within rounding.
#pragma once

#include <atomic>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <utility>

#include "brittle/core/Result.h"
#include "brittle/database/FragmentDatabase.h"
#include "brittle/database/Material.h"
#include "brittle/runtime/StaticCorrection.h"
#include "EntryCache.h"

namespace brittle::detail {

class EntryCorrections {
 public:
  /// `cache` (the same database's entries, placed with the bases the matched bodies share)
  /// outlives this.
  explicit EntryCorrections(const EntryCache& cache) : mCache(cache) {}

  /// Entry `entry`'s correction at unit size in `material` over its first `modes` modes (the
  /// matched body's count, the same for every fragment of an entry in one World), built on first
  /// use. Errors: those of instantiateEntry and StaticCorrection::build, InvalidArgument (an entry
  /// out of range).
  const Result<StaticCorrection>& get(int32_t entry, const Material& material, int modes) const;
  /// How many (entry, material) corrections are built so far, failed ones included.
  int32_t built() const { return mBuilt.load(std::memory_order_acquire); }

 private:
  struct Slot {
    std::once_flag once;
    std::optional<Result<StaticCorrection>> correction;
  };
  const EntryCache& mCache;
  mutable std::mutex mMutex;  // guards mSlots' structure; each slot is built under its own once_flag
  mutable std::map<std::pair<int32_t, std::string>, std::unique_ptr<Slot>> mSlots;
  mutable std::atomic<int32_t> mBuilt{0};
};

}  // namespace brittle::detail
