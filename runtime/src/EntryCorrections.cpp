#include "EntryCorrections.h"

#include "brittle/database/ScalingLaws.h"

namespace brittle::detail {

const Result<StaticCorrection>& EntryCorrections::get(int32_t entry, const Material& material, int modes) const {
  Slot* slot = nullptr;
  {
    std::lock_guard<std::mutex> lock(mMutex);
    auto& held = mSlots[{entry, material.name}];
    if (!held) held = std::make_unique<Slot>();
    slot = held.get();  // map nodes do not move: the pointer stays valid
  }
  std::call_once(slot->once, [&] {
    struct Count {
      std::atomic<int32_t>& built;
      ~Count() { built.fetch_add(1, std::memory_order_release); }
    } count{mBuilt};
    if (entry < 0 || static_cast<size_t>(entry) >= mDatabase.entries.size()) {
      slot->correction.emplace(makeError(ErrorCode::InvalidArgument, "entry " + std::to_string(entry) + " out of range"));
      return;
    }
    // The entry at unit size and in its canonical axes, with the target material (and, where ν
    // differs, the same Rayleigh–Ritz modes the placed fragment gets).
    CanonicalFrame unit;
    const EntryAtPoisson* atPoisson = nullptr;
    if (mCache && material.poissonRatio != mDatabase.referenceMaterial.poissonRatio) {
      const Result<EntryAtPoisson>& basis = mCache->atPoisson(entry, material.poissonRatio);
      if (!basis) {
        slot->correction.emplace(basis.error());
        return;
      }
      atPoisson = &basis.value();
    }
    auto asset = instantiateEntry(mDatabase.entries[static_cast<size_t>(entry)], mDatabase.referenceMaterial, material, unit,
                                  nullptr, atPoisson);
    if (!asset) {
      slot->correction.emplace(asset.error());
      return;
    }
    slot->correction.emplace(StaticCorrection::build(asset.value(), material, modes));
  });
  return *slot->correction;
}

}  // namespace brittle::detail
