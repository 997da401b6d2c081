#include "EntryCache.h"

#include <string>

namespace brittle::detail {

template <class T, class Key, class Make>
const Result<T>& EntryCache::get(std::map<Key, std::unique_ptr<Slot<T>>>& slots, const Key& key, int32_t entry,
                                 Make&& make) const {
  Slot<T>* slot = nullptr;
  {
    std::lock_guard<std::mutex> lock(mMutex);
    auto& held = slots[key];
    if (!held) held = std::make_unique<Slot<T>>();
    slot = held.get();  // map nodes do not move: the pointer stays valid
  }
  std::call_once(slot->once, [&] {
    if (entry < 0 || static_cast<size_t>(entry) >= mDatabase.entries.size()) {
      slot->value.emplace(makeError(ErrorCode::InvalidArgument, "entry " + std::to_string(entry) + " out of range"));
    } else {
      slot->value.emplace(make(mDatabase.entries[static_cast<size_t>(entry)]));
    }
    mBuilt.fetch_add(1, std::memory_order_release);
  });
  return *slot->value;
}

const Result<TetTopology>& EntryCache::topology(int32_t entry) const {
  return get(mTopologies, entry, entry, [](const FragmentEntry& e) { return buildTetTopology(e.asset.tetMesh); });
}

const Result<EntryAtPoisson>& EntryCache::atPoisson(int32_t entry, double poissonRatio) const {
  // Keyed by the value itself: instantiateEntry corrects wherever ν differs from ν₀ at all.
  return get(mBases, std::pair<int32_t, double>{entry, poissonRatio}, entry, [&](const FragmentEntry& e) {
    return entryAtPoisson(e, mDatabase.referenceMaterial, poissonRatio);
  });
}

Result<ObjectAsset> EntryCache::place(int32_t entry, const Material& target, const CanonicalFrame& frame) const {
  if (entry < 0 || static_cast<size_t>(entry) >= mDatabase.entries.size()) {
    return makeError(ErrorCode::InvalidArgument, "entry " + std::to_string(entry) + " out of range");
  }
  const EntryAtPoisson* basis = nullptr;
  if (target.poissonRatio != mDatabase.referenceMaterial.poissonRatio) {
    const Result<EntryAtPoisson>& corrected = atPoisson(entry, target.poissonRatio);
    if (!corrected) return corrected.error();
    basis = &corrected.value();
  }
  return instantiateEntry(mDatabase.entries[static_cast<size_t>(entry)], mDatabase.referenceMaterial, target, frame,
                          nullptr, basis);
}

}  // namespace brittle::detail
