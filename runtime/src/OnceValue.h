// OnceValue.h — a value made once, on first use, by whichever thread asks first (as std::call_once
// makes it), except that a thread that asks while the value is being made on a starved thread makes
// a copy of its own instead of waiting for it. Private to the runtime: a Body's lazily built members,
// a BodySource's body and the per-entry caches (SharedSlots.h) are made of it.
//
// Why: the World makes bodies and static corrections on background threads at the system's lowest
// priority (BackgroundThreads.h: SCHED_IDLE), which run only on a core nothing else wants. An impact
// that needs one of them waits for it, which frees its own core for the maker. But on a machine whose
// cores other work keeps busy (other processes, or the host's own threads) the maker gets no core at
// all, and the impact waited for as long as the load lasted: a priority inversion. A plate struck
// right after it was placed, with two host threads spinning, waited 2.4–6.0 s for its static
// correction in 4 of 9 rounds; now 0.12–0.64 s (docs/realtime.md). A waiter now watches the maker's thread's CPU time: while
// it advances by at least a quarter of the time waited, the waiter keeps waiting; once it does not,
// the waiter makes the value itself, at its own priority. What a maker computes is a pure function of
// what it captured (the same bits on any thread), so whichever copy is published first, the value
// is the same and fractures do not change; the other copy is dropped.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <optional>
#include <utility>

#include "ThreadClock.h"

namespace brittle::detail {

template <class T>
class OnceValue {
 public:
  /// The value: make() (returning a T) on the first call; a later caller waits for it, or, when the
  /// thread making it is starved (below kStarvedShare of a core since the caller began to wait,
  /// looked at every kSlice), calls make() itself. make() may run on several threads at once, so
  /// it must not change what it captured. `published()` is called once, when the value is published and before any caller
  /// can see it; `settled()` once, by the last thread to leave make() after that (to release what
  /// make() held). Both run under the value's lock. An exception from make() leaves the value
  /// unmade and reaches that caller; a caller still waiting then makes it.
  template <class Make, class Settled, class Published>
  const T& get(Make&& make, Settled&& settled, Published&& published) const {
    if (mReady.load(std::memory_order_acquire)) return *mValue;
    std::unique_lock<std::mutex> lock(mMutex);
    // The maker watched, and its CPU clock and the wall clock when this caller began to watch it.
    clockid_t watched{};
    double cpuStart = 0.0;
    auto wallStart = std::chrono::steady_clock::now();
    bool watching = false;
    while (!mReady.load(std::memory_order_relaxed)) {
      if (mRunners == 0) {
        run(lock, make, settled, published);
        break;
      }
      if (!watching || watched != mMakerClock) {  // a maker started since: watch it from now
        watched = mMakerClock;
        cpuStart = clockSeconds(watched);
        wallStart = std::chrono::steady_clock::now();
        watching = true;
      }
      mDone.wait_for(lock, kSlice);
      if (mReady.load(std::memory_order_relaxed) || mRunners == 0 || watched != mMakerClock) continue;
      const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wallStart).count();
      if (starved(cpuStart, clockSeconds(watched) - cpuStart, wall)) {  // since it was watched (or its clock unreadable)
        run(lock, make, settled, published);
        break;
      }
    }
    return *mValue;
  }
  template <class Make, class Settled>
  const T& get(Make&& make, Settled&& settled) const {
    return get(std::forward<Make>(make), std::forward<Settled>(settled), [] {});
  }
  template <class Make>
  const T& get(Make&& make) const {
    return get(std::forward<Make>(make), [] {}, [] {});
  }

  /// Publishes `value` unless a value is published already; never waits. Whether it was published.
  bool install(T value) const {
    std::lock_guard<std::mutex> lock(mMutex);
    if (mReady.load(std::memory_order_relaxed)) return false;
    mValue.emplace(std::move(value));
    mReady.store(true, std::memory_order_release);
    mDone.notify_all();
    return true;
  }

  /// Whether get() would return at once.
  bool ready() const { return mReady.load(std::memory_order_acquire); }

  /// How often a waiter looks at the maker's progress (ThreadClock.h says how it judges it).
  static constexpr std::chrono::microseconds kSlice = kStarvedSlice;

 private:
  // Runs make() on this thread with `lock` released; publishes its value unless another copy was
  // published first. Called with `lock` held; returns with it held.
  template <class Make, class Settled, class Published>
  void run(std::unique_lock<std::mutex>& lock, Make& make, Settled& settled, Published& published) const {
    ++mRunners;
    mMakerClock = threadCpuClock();  // waiters watch the newest maker
    lock.unlock();
    std::optional<T> made;
    try {
      made.emplace(make());
    } catch (...) {
      lock.lock();
      if (--mRunners == 0 && mReady.load(std::memory_order_relaxed)) settled();  // another copy was published
      mDone.notify_all();
      throw;
    }
    lock.lock();
    const bool first = !mReady.load(std::memory_order_relaxed);
    if (first) {
      mValue.emplace(std::move(*made));
      published();
    }
    if (--mRunners == 0) settled();  // the value is published: by this copy or an earlier one
    if (first) mReady.store(true, std::memory_order_release);
    mDone.notify_all();
  }

  mutable std::mutex mMutex;
  mutable std::condition_variable mDone;
  mutable std::optional<T> mValue;
  mutable std::atomic<bool> mReady{false};
  mutable int mRunners = 0;              // threads inside make(), under mMutex
  mutable clockid_t mMakerClock{};       // the newest of them's CPU clock, under mMutex
};

}  // namespace brittle::detail
