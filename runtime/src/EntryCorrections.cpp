#include "EntryCorrections.h"

#include "brittle/database/ScalingLaws.h"

namespace brittle::detail {

std::shared_ptr<const Result<StaticCorrection>> EntryCorrections::get(int32_t entry, const Material& material,
                                                                      int modes) const {
  return mSlots.get({entry, material.name}, [&]() -> Result<StaticCorrection> {
    // The entry at unit size and in its canonical axes, with the target material (and, where ν
    // differs, the same Rayleigh–Ritz modes the placed fragment gets).
    auto asset = mCache.place(entry, material, CanonicalFrame{});
    if (!asset) return asset.error();
    return StaticCorrection::build(asset.value(), material, modes);
  });
}

}  // namespace brittle::detail
