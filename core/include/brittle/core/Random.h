// Random.h — the seeded mixing every module shares: splitmix64 and bits mapped to [0, 1).
//
// Fixed integer arithmetic, so the same seed gives the same numbers on every platform and in
// every process (std distributions do not promise that). Seeds derived with splitmix64 are
// pinned by fingerprints: changing this function changes every bake and every crack.
#pragma once

#include <cstdint>

namespace brittle {

/// splitmix64 (Steele, Lea, Flood 2014): adds the golden-ratio increment to x and mixes the sum.
/// A bijection on 64-bit values, so distinct inputs give unrelated, distinct outputs.
constexpr uint64_t splitmix64(uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

/// The top 53 bits of `bits` as a double in [0, 1), every value a multiple of 2⁻⁵³.
constexpr double unitInterval(uint64_t bits) { return static_cast<double>(bits >> 11) * 0x1.0p-53; }

/// The splitmix64 sequence from `seed`: next() returns splitmix64(seed), splitmix64(seed + γ), ...
/// with γ the golden-ratio increment; a fixed stream for tests and sampling.
class SplitMix64 {
 public:
  explicit constexpr SplitMix64(uint64_t seed) : mState(seed) {}
  constexpr uint64_t next() {
    const uint64_t out = splitmix64(mState);
    mState += 0x9e3779b97f4a7c15ull;
    return out;
  }

 private:
  uint64_t mState;
};

}  // namespace brittle
