// Cancellation.h — stopping background work nobody wants any more. Private to the runtime.
//
// Why: a World being destroyed waited for the background jobs running on its threads: destroyed
// right after placing the default vase, for its preparation (the factorisation of K and the stress
// bounds), 1.7 s on the host's thread; right after a break, 40–60 ms for a fragment's body
// (docs/realtime.md, "A World destroyed without waiting"). Long computations now call
// cancellationPoint() between steps of a few ms at most. On a thread whose work was cancelled it
// throws Cancelled, which unwinds the job up to BackgroundThreads, which drops it. Cancelled is not
// a std::exception, so the handlers that turn a failure into a typed error let it pass: a value
// being made stays unmade (OnceValue.h) instead of becoming an error. Threads without a flag (the
// host's, oneTBB's workers outside a World's jobs, the bake's) are never cancelled, and a flag is set
// only when its World closes, so no fracture changes.
#pragma once

#include <atomic>

namespace brittle::detail {

/// What cancellationPoint() throws; caught only where a job starts (BackgroundThreads, a World's
/// impact task).
struct Cancelled {};

/// The calling thread's cancellation flag (null: it is never cancelled).
inline thread_local const std::atomic<bool>* tCancelFlag = nullptr;

/// Throws Cancelled when the calling thread's flag is set. A relaxed load of a thread-local
/// pointer and of the flag: cheap enough for a loop's every few hundred iterations.
inline void cancellationPoint() {
  const std::atomic<bool>* flag = tCancelFlag;
  if (flag != nullptr && flag->load(std::memory_order_relaxed)) throw Cancelled{};
}

/// Sets the calling thread's flag for its lifetime, then restores the one before.
class CancelScope {
 public:
  explicit CancelScope(const std::atomic<bool>* flag) : mPrevious(tCancelFlag) { tCancelFlag = flag; }
  ~CancelScope() { tCancelFlag = mPrevious; }
  CancelScope(const CancelScope&) = delete;
  CancelScope& operator=(const CancelScope&) = delete;

 private:
  const std::atomic<bool>* mPrevious;
};

}  // namespace brittle::detail
