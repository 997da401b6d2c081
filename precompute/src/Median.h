// Median.h — the median the sizing code reports (ModelSizing.cpp, FragmentSizing.cpp); internal to
// precompute. NaN for an empty sample.
#pragma once

#include <algorithm>
#include <limits>
#include <vector>

namespace brittle {

inline double median(std::vector<double> v) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

}  // namespace brittle
