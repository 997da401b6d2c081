// SharedSlots.h — values built once per key, on first use, by whichever thread asks first (the
// others asking for the same key wait for it, or build their own copy when its builder's thread is
// starved: OnceValue.h), and kept up to a capacity: past it, the least recently asked-for key is
// dropped. Private to the runtime: the World's per-entry caches
// (EntryCache.h, EntryCorrections.h) are made of it.
//
// A value is handed out as a shared pointer, so one that is dropped while a worker still uses it
// lives until that worker is done; asked for again, it is built again, to the same bits (the
// values are functions of their key). Without a bound, a long session with a 10⁴-entry database
// keeps every entry it ever matched: ~2.4 MB an entry at 1k tets (its connectivity, its basis at
// another ν, its static correction), unbounded in the entries matched.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>

#include "brittle/core/Result.h"
#include "OnceValue.h"

namespace brittle::detail {

template <class Key, class T>
class SharedSlots {
 public:
  /// capacity: the keys kept, ≥ 1; 0: no bound.
  explicit SharedSlots(size_t capacity) : mCapacity(capacity) {}

  /// The value of `key`: make()'s result (a Result<T>), built on the first call for the key, or
  /// again after the key was dropped.
  template <class Make>
  std::shared_ptr<const Result<T>> get(const Key& key, Make&& make) {
    std::shared_ptr<Slot> slot;
    {
      std::lock_guard<std::mutex> lock(mMutex);
      auto [it, inserted] = mSlots.try_emplace(key);
      if (inserted) it->second.slot = std::make_shared<Slot>();
      it->second.lastUse = ++mClock;
      slot = it->second.slot;
      if (inserted && mCapacity > 0 && mSlots.size() > mCapacity) dropLeastRecent();
    }
    const Result<T>& value = slot->value.get(make, [] {}, [this] { mBuilt.fetch_add(1, std::memory_order_release); });
    return std::shared_ptr<const Result<T>>(slot, &value);
  }

  /// Forgets `key`'s value (its holders keep it): asked for again, it is built again. For a
  /// failure that may not recur, such as a read the disk failed.
  void drop(const Key& key) {
    std::lock_guard<std::mutex> lock(mMutex);
    mSlots.erase(key);
  }

  /// Values built so far (failed ones and rebuilt ones included; a copy built beside a starved
  /// builder and dropped is not counted).
  int32_t built() const { return mBuilt.load(std::memory_order_acquire); }
  /// Keys held now (≤ the capacity).
  size_t size() const {
    std::lock_guard<std::mutex> lock(mMutex);
    return mSlots.size();
  }

 private:
  struct Slot {
    OnceValue<Result<T>> value;
  };
  struct Held {
    std::shared_ptr<Slot> slot;
    uint64_t lastUse = 0;
  };

  // One scan over the kept keys, once per key built past the capacity: nothing next to a build.
  void dropLeastRecent() {
    auto oldest = mSlots.begin();
    for (auto it = mSlots.begin(); it != mSlots.end(); ++it) {
      if (it->second.lastUse < oldest->second.lastUse) oldest = it;
    }
    mSlots.erase(oldest);
  }

  const size_t mCapacity;
  mutable std::mutex mMutex;  // guards mSlots and mClock; each value is built by its slot's OnceValue
  std::map<Key, Held> mSlots;
  uint64_t mClock = 0;
  std::atomic<int32_t> mBuilt{0};
};

}  // namespace brittle::detail
