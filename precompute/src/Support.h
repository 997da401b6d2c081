// Support.h — small helpers shared inside precompute (private): the median the sizing code
// reports, and a uniform draw in [0, 1) that is the same on every standard library
// (std::uniform_real_distribution is not). Wall-clock seconds come from core/Timing.h.
#pragma once

#include <algorithm>
#include <limits>
#include <random>
#include <vector>

#include "brittle/core/Random.h"

namespace brittle::detail {

inline constexpr double kInf = std::numeric_limits<double>::infinity();

/// NaN for an empty sample.
inline double median(std::vector<double> v) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/// The top 53 bits of one draw, as a double in [0, 1).
inline double unit(std::mt19937_64& rng) { return unitInterval(rng()); }

}  // namespace brittle::detail
