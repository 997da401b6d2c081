// Timing.h — wall-clock seconds for reports, progress lines and benchmarks.
//
// Monotonic (steady) time only: the system clock can jump, and a stage timing must not go
// negative. Timings are reported, never used to decide a result.
#pragma once

#include <chrono>

namespace brittle {

using SteadyClock = std::chrono::steady_clock;

/// Seconds from `start` to `end`.
inline double secondsBetween(SteadyClock::time_point start, SteadyClock::time_point end) {
  return std::chrono::duration<double>(end - start).count();
}

/// Seconds from `start` to now.
inline double secondsSince(SteadyClock::time_point start) { return secondsBetween(start, SteadyClock::now()); }

/// A stopwatch started at construction: seconds() reads it, lap() reads it and restarts it.
class Stopwatch {
 public:
  Stopwatch() : mStart(SteadyClock::now()) {}
  double seconds() const { return secondsSince(mStart); }
  double lap() {
    const auto now = SteadyClock::now();
    const double s = secondsBetween(mStart, now);
    mStart = now;
    return s;
  }
  void restart() { mStart = SteadyClock::now(); }
  SteadyClock::time_point start() const { return mStart; }

 private:
  SteadyClock::time_point mStart;
};

}  // namespace brittle
