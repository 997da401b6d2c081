// BackgroundThreads.h — the World's background work (placement, the fragments' new bodies) on
// threads of its own, at the operating system's lowest priority. Private to the runtime.
//
// Why not oneTBB's workers: oneTBB starts one worker fewer than the cores, counting the host's
// thread, and that one worker also runs the impacts. A host that sleeps between its frames (the
// paced player) left its core idle while fragments waited for their bodies on the one worker: the
// pane scene's frames waited up to 10–15 ms for them. More oneTBB workers would use that core, but
// they also compete with a host's synchronous impact() for the two cores (the slab's impact in
// `bench impact`: 3.75 → 4.96 ms median, p99 6 → 10–13 ms, with two workers). Threads at idle
// priority (Linux SCHED_IDLE; elsewhere the normal priority) run only on a core nothing else
// wants: a sleeping host's, or a worker's between impacts. An impact that needs a body being made
// here waits for it, which frees its own core for the maker; where other work keeps every core busy
// the maker gets none, and the impact then makes the body itself (OnceValue.h).
//
// Jobs run in submission order as threads free up, those that can wait (Urgency::Later: a piece's
// later check and escalation) after every other queued one and on all threads but one, so that a
// new break's first bodies never queue behind them or find every thread busy with them (the pane
// scene with every later body escalated to a P2 check: max frame 24–31 ms and p99 12–23 ms when
// they shared one queue). Jobs an impact waits for (Urgency::First: the body of a piece struck
// before it was made, World::submitImpact) go ahead of every other queued one. What jobs compute
// does not depend on which thread runs them or when (each writes only its own result), so
// fractures are the same bits.
#pragma once

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <deque>
#include <exception>
#include <functional>
#include <limits>
#include <map>
#include <mutex>
#include <thread>
#include <vector>

#include "ThreadClock.h"

namespace brittle::detail {

class BackgroundThreads {
 public:
  /// `threads` threads (0: none; jobs then run only when the host waits for them, in wait()). Their
  /// jobs are cancelled (Cancellation.h) through `cancel` when it is given (the owner's flag, which
  /// must outlive this object), else through a flag of their own.
  explicit BackgroundThreads(int threads, std::atomic<bool>* cancel = nullptr);
  /// cancel(), then joins the threads: a running job ends at its next cancellation point.
  ~BackgroundThreads();
  BackgroundThreads(const BackgroundThreads&) = delete;
  BackgroundThreads& operator=(const BackgroundThreads&) = delete;

  enum class Urgency { First, Now, Later };
  /// Later jobs run earliest `dueS` first (the host's time from which their result is used; ties in
  /// submission order): a 13-break history queues each break's escalations (due 2 s after it)
  /// before the next break's checks and analyses (due 0.25 s after that one), and an impact at a
  /// version's due time waits for it. The other urgencies run in submission order.
  void submit(std::function<void()> job, Urgency urgency = Urgency::Now,
              double dueS = std::numeric_limits<double>::infinity());
  /// Runs queued jobs on the calling thread too (a host waiting on a loading screen helps), until
  /// none is queued or running: true. With `untilStarved`, it also stops once none is queued and
  /// the threads running jobs are starved (together under kStarvedShare of a core since the host
  /// began to wait for them, ThreadClock.h): false, and the jobs run on. A host that waits only for
  /// values it can make itself (World::waitUntilPrepared: OnceValue.h) then makes them instead of
  /// waiting for as long as other work keeps every core busy. Rethrows the first exception a job
  /// threw since the last wait.
  bool wait(bool untilStarved = false);
  /// Drops the jobs not started, sets the cancellation flag (the running jobs throw Cancelled at
  /// their next cancellationPoint() and are dropped) and lets the threads end; submit() queues
  /// for nobody from then on. Returns at once.
  void cancel();
  /// Whether every thread has lowered itself to idle priority (false where the system refused or
  /// has none, and until each has started).
  bool idlePriority() const;
  int threadCount() const { return static_cast<int>(mThreads.size()); }

 private:
  void run();
  void execute(std::function<void()>& job, bool later);  // runs it, keeps its exception, counts it done
  double threadsCpuSeconds() const;  // the threads' CPU time together; −1 when a clock cannot be read

  std::mutex mMutex;
  std::condition_variable mWork, mIdleWait;
  std::deque<std::function<void()>> mFirstQueue, mQueue;
  std::multimap<double, std::function<void()>> mLaterQueue;  // by due time; equal keys in insertion order
  int mRunning = 0;
  int mRunningLater = 0;  // of mRunning, Later jobs; at most laterThreads() on the threads
  int laterThreads() const { return std::max(1, static_cast<int>(mThreads.size()) - 1); }
  // The next job a thread (or the host in wait(), with no limit) takes, under mMutex; false if none.
  // `later`: a Later job taken by a thread (counted in mRunningLater).
  bool take(std::function<void()>& job, bool& later, bool host);
  bool mStop = false;
  std::atomic<int> mIdleThreads{0};
  std::exception_ptr mError;
  std::atomic<bool> mOwnCancel{false};
  std::atomic<bool>* mCancel = &mOwnCancel;
  std::vector<std::thread> mThreads;
  std::vector<clockid_t> mClocks;  // each thread's CPU clock, set by the constructor
};

}  // namespace brittle::detail
