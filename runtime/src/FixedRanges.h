// FixedRanges.h — a loop over [0, n) split into a fixed number of ranges, run on the caller's
// oneTBB arena. Private to the runtime.
//
// The split depends on n and the range count only, never on the thread count, so work that is
// summed within a range (and combined in range order by the caller) gives the same bits on any
// number of threads: the stress scan, the static correction, stress recovery and the fragments'
// volume moments all rely on it.
#pragma once

#include <Eigen/Core>
#include <oneapi/tbb/parallel_for.h>

namespace brittle::detail {

/// f(c, begin, end) for each range c < ranges, [begin, end) = [n c / ranges, n (c + 1) / ranges).
template <class F>
void forFixedRanges(Eigen::Index n, int ranges, F&& f) {
  tbb::parallel_for(0, ranges, [&](int c) { f(c, n * c / ranges, n * (c + 1) / ranges); });
}

}  // namespace brittle::detail
