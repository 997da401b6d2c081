// ThreadClock.h — whether a thread at idle priority is getting any CPU: its CPU clock read against
// the wall clock. Private to the runtime; OnceValue.h (a waiter behind a starved maker makes its own
// copy) and BackgroundThreads.h (a host waiting for starved jobs stops waiting) share it.
//
// A thread at normal priority on a loaded machine gets about its fair share over a few slices
// (≥ 1/2 of a core with one competitor per core); one at idle priority (SCHED_IDLE) there gets next
// to none. So a watcher looks every kStarvedSlice and calls the watched thread starved once it has
// had less than kStarvedShare of a core since the watch began. Misjudging a slow thread as starved
// costs CPU only: the watcher does the work itself, or goes on to what the work was for.
#pragma once

#include <pthread.h>
#include <time.h>

#include <chrono>

namespace brittle::detail {

inline constexpr std::chrono::microseconds kStarvedSlice{2000};
inline constexpr double kStarvedShare = 0.25;

/// The calling thread's CPU clock (CLOCK_MONOTONIC where it cannot be had: never starved-looking).
inline clockid_t threadCpuClock(pthread_t thread = pthread_self()) {
  clockid_t clock{};
  if (pthread_getcpuclockid(thread, &clock) != 0) return CLOCK_MONOTONIC;
  return clock;
}

/// Seconds on `clock`; −1 when it cannot be read.
inline double clockSeconds(clockid_t clock) {
  timespec t{};
  if (clock_gettime(clock, &t) != 0) return -1.0;
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

/// Whether `cpu` seconds of CPU over `wall` seconds is a starved thread's (or the clock was not
/// readable: `cpuStart` < 0).
inline bool starved(double cpuStart, double cpu, double wall) { return !(cpuStart >= 0.0 && cpu >= kStarvedShare * wall); }

}  // namespace brittle::detail
