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
    // The entry at unit size and in its canonical axes, with the target material (and, where ν
    // differs, the same Rayleigh–Ritz modes the placed fragment gets).
    auto asset = mCache.place(entry, material, CanonicalFrame{});
    if (!asset) {
      slot->correction.emplace(asset.error());
      return;
    }
    slot->correction.emplace(StaticCorrection::build(asset.value(), material, modes));
  });
  return *slot->correction;
}

}  // namespace brittle::detail
