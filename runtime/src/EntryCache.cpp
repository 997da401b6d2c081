#include "EntryCache.h"

#include <string>

namespace brittle::detail {

template <class T, class Make>
Result<T> EntryCache::ofEntry(int32_t entry, Make&& make) const {
  if (entry < 0 || static_cast<size_t>(entry) >= mDatabase.entries.size()) {
    return makeError(ErrorCode::InvalidArgument, "entry " + std::to_string(entry) + " out of range");
  }
  if (!mDatabase.entrySource) return make(mDatabase.entries[static_cast<size_t>(entry)]);
  const auto read = mEntries.get(entry, [&] { return mDatabase.entrySource->load(entry); });
  if (!*read) {
    // Damage stays (the answer is kept); a read the disk failed is tried again next time.
    if (read->error().code == ErrorCode::PackIoError) mEntries.drop(entry);
    return read->error();
  }
  return make(read->value());
}

std::shared_ptr<const Result<TetTopology>> EntryCache::topology(int32_t entry) const {
  return mTopologies.get(entry, [&] {
    return ofEntry<TetTopology>(entry, [](const FragmentEntry& e) { return buildTetTopology(e.asset.tetMesh); });
  });
}

std::shared_ptr<const Result<EntryAtPoisson>> EntryCache::atPoisson(int32_t entry, double poissonRatio) const {
  // Keyed by the value itself: instantiateEntry corrects wherever ν differs from ν₀ at all.
  return mBases.get({entry, poissonRatio}, [&] {
    return ofEntry<EntryAtPoisson>(
        entry, [&](const FragmentEntry& e) { return entryAtPoisson(e, mDatabase.referenceMaterial, poissonRatio); });
  });
}

Result<ObjectAsset> EntryCache::place(int32_t entry, const Material& target, const CanonicalFrame& frame) const {
  return ofEntry<ObjectAsset>(entry, [&](const FragmentEntry& e) -> Result<ObjectAsset> {
    std::shared_ptr<const Result<EntryAtPoisson>> corrected;  // held while the entry is placed
    if (target.poissonRatio != mDatabase.referenceMaterial.poissonRatio) {
      corrected = atPoisson(entry, target.poissonRatio);
      if (!*corrected) return corrected->error();
    }
    return instantiateEntry(e, mDatabase.referenceMaterial, target, frame, nullptr,
                            corrected ? &corrected->value() : nullptr);
  });
}

}  // namespace brittle::detail
