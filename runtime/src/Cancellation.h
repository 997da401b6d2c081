// Cancellation.h — stopping background work nobody wants any more. Private to the runtime.
//
// Why: a World being destroyed waited for the background jobs running on its threads: destroyed
// while the default vase was prepared (the factorisation of K, H, the stress bounds), 1.1–1.4 s on
// the host's thread; after a timed break, up to 0.5 s for a piece's later version
// (docs/realtime.md, "A World destroyed without waiting"). Long computations now call
// cancellationPoint() between steps of a few ms at most. On a thread whose work was cancelled it
// throws Cancelled, which unwinds the job up to BackgroundThreads, which drops it. Cancelled is not
// a std::exception, so the handlers that turn a failure into a typed error let it pass: a value
// being made stays unmade (OnceValue.h) instead of becoming an error. Threads without a flag (the
// host's, oneTBB's workers outside a World's jobs, the bake's) are never cancelled, and a flag is set
// only when its World closes or for a body nobody can use any more (a removed or broken fragment's
// versions, BodySource::abandon), so no fracture changes.
#pragma once

#include <atomic>

namespace brittle::detail {

// An invariant the flags rely on: a thread waiting inside a oneTBB parallel loop may run other
// tasks of its arena under its own flags. That is safe because a background thread's implicit
// arena holds only its own job's tasks, the World's arena only that World's impacts (whose only flag
// is that World's), and no parallel loop's body has a cancellation point. A point put inside one
// would need the loop isolated (tbb::this_task_arena::isolate).

/// What cancellationPoint() throws; caught only where a job starts (BackgroundThreads, a World's
/// impact task).
struct Cancelled {};

/// The calling thread's cancellation flags (null: none): its World's (set when the World closes)
/// and the job's own (a body nobody can use any more: BodySource::abandon).
inline thread_local const std::atomic<bool>* tCancelFlag = nullptr;
inline thread_local const std::atomic<bool>* tJobCancelFlag = nullptr;

/// Throws Cancelled when one of the calling thread's flags is set. Relaxed loads of thread-local
/// pointers and of the flags: cheap enough for a loop's every few hundred iterations.
inline void cancellationPoint() {
  const std::atomic<bool>* world = tCancelFlag;
  const std::atomic<bool>* job = tJobCancelFlag;
  if ((world != nullptr && world->load(std::memory_order_relaxed)) || (job != nullptr && job->load(std::memory_order_relaxed))) {
    throw Cancelled{};
  }
}

/// Sets one of the calling thread's flags (`slot`: tCancelFlag or tJobCancelFlag) to `flag` for
/// its lifetime, then restores the one before.
class CancelScope {
 public:
  CancelScope(const std::atomic<bool>*& slot, const std::atomic<bool>* flag) : mSlot(slot), mPrevious(slot) { slot = flag; }
  ~CancelScope() { mSlot = mPrevious; }
  CancelScope(const CancelScope&) = delete;
  CancelScope& operator=(const CancelScope&) = delete;

 private:
  const std::atomic<bool>*& mSlot;
  const std::atomic<bool>* mPrevious;
};

}  // namespace brittle::detail
