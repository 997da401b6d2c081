#include "brittle/core/Random.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace brittle {
namespace {

// Reference outputs of splitmix64 (Vigna's splitmix64.c seeded with 0): seeds and fingerprints
// derived from them are pinned, so the function may never change.
TEST(RandomTest, SplitMix64MatchesTheReferenceSequence) {
  SplitMix64 stream(0);
  EXPECT_EQ(stream.next(), 0xe220a8397b1dcdafull);
  EXPECT_EQ(stream.next(), 0x6e789e6aa1b965f4ull);
  EXPECT_EQ(stream.next(), 0x06c45d188009454full);
  EXPECT_EQ(splitmix64(0), 0xe220a8397b1dcdafull);
}

TEST(RandomTest, UnitIntervalKeepsTheTop53Bits) {
  EXPECT_EQ(unitInterval(0), 0.0);
  EXPECT_EQ(unitInterval(~0ull), 1.0 - 0x1.0p-53);
  EXPECT_EQ(unitInterval(1ull << 63), 0.5);
}

// The crack's turns: pinned values (the same bits on every platform), the bounds, and the moments
// of the Irwin–Hall sum over a long stream.
TEST(RandomTest, NearNormalIsPinnedBoundedAndHasUnitVariance) {
  constexpr double kScale = 1.7320508075688772 * 0x1.0p-17;
  EXPECT_EQ(nearNormal(0), -262140.0 * kScale);  // every quarter 0
  EXPECT_EQ(nearNormal(~0ull), 262140.0 * kScale);
  EXPECT_EQ(nearNormal(0x7fff7fff80008000ull), 0.0);  // the quarters' sum at its middle
  EXPECT_EQ(nearNormal(0x8000800080007fffull), 2.0 * kScale);  // one step above it
  EXPECT_NEAR(nearNormal(~0ull), 2.0 * std::sqrt(3.0), 1e-4);
  static_assert(nearNormal(0x0001000200030004ull) == (2.0 * 10 - 262140) * kScale);
  SplitMix64 stream(7);
  double sum = 0.0, squares = 0.0, fourth = 0.0, most = 0.0;
  constexpr int kDraws = 1 << 20;
  for (int i = 0; i < kDraws; ++i) {
    const double z = nearNormal(stream.next());
    sum += z;
    squares += z * z;
    fourth += z * z * z * z;
    most = std::max(most, std::abs(z));
  }
  const double mean = sum / kDraws, variance = squares / kDraws - mean * mean;
  EXPECT_NEAR(mean, 0.0, 5e-3);       // σ/√n ≈ 1e-3
  EXPECT_NEAR(variance, 1.0, 5e-3);   // ≈ 1.3e-3 for kurtosis 2.7
  EXPECT_NEAR(fourth / kDraws, 2.7, 0.03);  // Irwin–Hall n = 4: 3 − 6/(5·4)
  EXPECT_LE(most, 2.0 * std::sqrt(3.0));
  EXPECT_GT(most, 3.0);  // the tails are reached
}

}  // namespace
}  // namespace brittle
