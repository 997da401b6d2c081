// BenchSupport.h — what the benchmarks share: test bodies and statistics.
#pragma once

#include <algorithm>
#include <vector>

#include "brittle/core/Timing.h"
#include "brittle/precompute/BaseShapes.h"

namespace brittle::bench {

/// A closed box of the given full extents (m), centred on the origin (12 triangles).
inline TriangleMesh boxSurface(double sx, double sy, double sz) {
  BaseShapeDefinition d;
  d.name = "box";
  d.kind = BaseShapeKind::Box;
  d.sizeM = Eigen::Vector3d(sx, sy, sz);
  return makeBaseShape(d).value();  // a box with positive extents always builds
}

/// The p-quantile (p in [0, 1]) of v, nearest rank; 0 for an empty v.
inline double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[static_cast<size_t>(std::min<double>(static_cast<double>(v.size() - 1), p * static_cast<double>(v.size() - 1) + 0.5))];
}

/// The largest relative difference of a from b over three components (b the reference).
inline double maxRelative(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return ((a - b).array().abs() / b.array().abs()).maxCoeff();
}

/// The median wall time of `repeats` calls of f (s).
template <typename F>
double medianSeconds(int repeats, F&& f) {
  std::vector<double> t;
  for (int i = 0; i < repeats; ++i) {
    const auto start = SteadyClock::now();
    f();
    t.push_back(secondsSince(start));
  }
  return percentile(t, 0.5);
}

}  // namespace brittle::bench
