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

/// A draw of unit variance near the standard normal from the 64 bits of one draw: their four
/// 16-bit quarters b_i as the uniforms (b_i + ½)/2¹⁶, summed (Irwin–Hall, n = 4), centred and
/// scaled by √3. It lies within ±2√3 (the normal's 3.46σ), with kurtosis 2.7 (the normal's 3). An
/// integer sum and one product by a constant: the same bits on every platform, where
/// std::normal_distribution leaves its algorithm to each standard library, and a few nanoseconds
/// (libstdc++'s polar method takes a logarithm, a square root and a rejection loop). Crack growth
/// draws its seeded turns with it.
constexpr double nearNormal(uint64_t bits) {
  const uint64_t sum = (bits & 0xffffu) + ((bits >> 16) & 0xffffu) + ((bits >> 32) & 0xffffu) + (bits >> 48);
  // Σu_i − 2 = (2·sum + 4 − 2¹⁸)/2¹⁷, exact in a double (|·| < 2¹⁸); √3·2⁻¹⁷ is one rounding of √3.
  return static_cast<double>(static_cast<int64_t>(2 * sum) - 262140) * (1.7320508075688772 * 0x1.0p-17);
}

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
