// The World's background threads (runtime/src/BackgroundThreads.h): jobs run beside the host at
// idle priority on threads named brittle-bg, all of them at once when there are threads for them; without threads, only when
// the host waits; a job's exception reaches the waiting host once; a host can stop waiting for a
// starved job; jobs not started are dropped; jobs running are cancelled at their next cancellation
// point (Cancellation.h), and threads without a flag never are.
#include "BackgroundThreads.h"
#include "Cancellation.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <limits>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>

#if defined(__linux__)
#include <sched.h>
#include <sys/prctl.h>

#include <cstring>
#endif

namespace brittle::detail {
namespace {

// Each of `count` jobs waits until all have started: they can only all return if they run at the
// same time. The timeout turns a pool that runs them one by one into a failure, not a hang.
TEST(BackgroundThreads, RunsAJobPerThreadAtOnceOffTheHostsThreadAtIdlePriority) {
  constexpr int kThreads = 3;
  BackgroundThreads pool(kThreads);
  EXPECT_EQ(pool.threadCount(), kThreads);
  std::mutex m;
  std::condition_variable cv;
  int started = 0;
  std::atomic<int> together{0}, offHost{0}, idle{0}, named{0};
  const std::thread::id host = std::this_thread::get_id();
  for (int i = 0; i < kThreads; ++i) {
    pool.submit([&] {
      if (std::this_thread::get_id() != host) ++offHost;
#if defined(__linux__) && defined(SCHED_IDLE)
      if (sched_getscheduler(0) == SCHED_IDLE) ++idle;
      char name[16] = {};
      prctl(PR_GET_NAME, name, 0, 0, 0);
      if (std::strcmp(name, "brittle-bg") == 0) ++named;
#endif
      std::unique_lock lock(m);
      ++started;
      cv.notify_all();
      if (cv.wait_for(lock, std::chrono::seconds(20), [&] { return started == kThreads; })) ++together;
    });
  }
  // Not helped by the host: the jobs must meet on the pool's own threads before it waits.
  {
    std::unique_lock lock(m);
    EXPECT_TRUE(cv.wait_for(lock, std::chrono::seconds(20), [&] { return started == kThreads; }));
  }
  pool.wait();
  EXPECT_EQ(together.load(), kThreads);
  EXPECT_EQ(offHost.load(), kThreads);
#if defined(__linux__) && defined(SCHED_IDLE)
  EXPECT_TRUE(pool.idlePriority());
  EXPECT_EQ(idle.load(), kThreads);
  EXPECT_EQ(named.load(), kThreads);  // what profilers show, and how HotPathAllocationTest tells them apart
#endif
}

TEST(BackgroundThreads, WithoutThreadsJobsRunWhenTheHostWaitsOnItsThread) {
  BackgroundThreads pool(0);
  const std::thread::id host = std::this_thread::get_id();
  std::atomic<int> ran{0}, onHost{0};
  for (int i = 0; i < 4; ++i) {
    pool.submit([&] {
      ++ran;
      if (std::this_thread::get_id() == host) ++onHost;
    });
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  EXPECT_EQ(ran.load(), 0);
  pool.wait();
  EXPECT_EQ(ran.load(), 4);
  EXPECT_EQ(onHost.load(), 4);
}

TEST(BackgroundThreads, AJobsExceptionReachesTheWaitingHostOnce) {
  for (int threads : {0, 2}) {
    BackgroundThreads pool(threads);
    std::atomic<int> others{0};
    pool.submit([] { throw std::runtime_error("a failing job"); });
    for (int i = 0; i < 3; ++i) pool.submit([&] { ++others; });
    EXPECT_THROW(pool.wait(), std::runtime_error) << threads << " threads";
    pool.wait();  // reported once
    EXPECT_EQ(others.load(), 3) << threads << " threads";  // the other jobs ran all the same
  }
}

// Later jobs (a piece's later check and escalation) run on all threads but one: with two threads
// and two long Later jobs queued, a Now job still starts at once, and the second Later job waits
// until the first is done.
TEST(BackgroundThreads, LaterJobsLeaveAThreadForTheJobsOfNow) {
  BackgroundThreads pool(2);
  std::mutex m;
  std::condition_variable cv;
  int laterRunning = 0, laterMost = 0;
  bool release = false, nowRan = false;
  auto later = [&] {
    std::unique_lock lock(m);
    laterMost = std::max(laterMost, ++laterRunning);
    cv.notify_all();
    cv.wait_for(lock, std::chrono::seconds(20), [&] { return release; });
    --laterRunning;
  };
  pool.submit(later, BackgroundThreads::Urgency::Later);
  pool.submit(later, BackgroundThreads::Urgency::Later);
  {
    std::unique_lock lock(m);
    ASSERT_TRUE(cv.wait_for(lock, std::chrono::seconds(20), [&] { return laterRunning == 1; }));
  }
  pool.submit([&] {
    std::lock_guard lock(m);
    nowRan = true;
    cv.notify_all();
  });
  {
    std::unique_lock lock(m);
    EXPECT_TRUE(cv.wait_for(lock, std::chrono::seconds(20), [&] { return nowRan; }));  // beside the running Later job
    EXPECT_EQ(laterRunning, 1);  // the second Later job has not started
    EXPECT_EQ(laterMost, 1);
    release = true;
    cv.notify_all();
  }
  pool.wait();  // the host, waiting, may take the second beside the first: no limit for it
  EXPECT_EQ(laterRunning, 0);
  EXPECT_TRUE(nowRan);
}

// A running job that gets no CPU (blocked here, as a thread at idle priority is while other work
// keeps every core busy): a host waiting with untilStarved runs what is queued itself, then stops
// waiting and is told so while the job is still blocked; a plain wait then waits for it. With a
// plain wait alone (before untilStarved) the host waited until the job's 30 s timeout.
TEST(BackgroundThreads, AHostStopsWaitingForAStarvedJobWhenItAsks) {
  BackgroundThreads pool(1);
  std::mutex m;
  std::condition_variable cv;
  bool inside = false, release = false;
  std::atomic<bool> done{false}, queuedRanOnHost{false};
  const std::thread::id host = std::this_thread::get_id();
  pool.submit([&] {
    std::unique_lock lock(m);
    inside = true;
    cv.notify_all();
    cv.wait_for(lock, std::chrono::seconds(30), [&] { return release; });
    done = true;
  });
  {
    std::unique_lock lock(m);
    ASSERT_TRUE(cv.wait_for(lock, std::chrono::seconds(20), [&] { return inside; }));
  }
  pool.submit([&] { queuedRanOnHost = std::this_thread::get_id() == host; });  // the one thread is busy
  const auto start = std::chrono::steady_clock::now();
  EXPECT_FALSE(pool.wait(/*untilStarved=*/true));
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(10));
  EXPECT_TRUE(queuedRanOnHost.load());
  EXPECT_FALSE(done.load());
  {
    std::lock_guard lock(m);
    release = true;
  }
  cv.notify_all();
  EXPECT_TRUE(pool.wait());
  EXPECT_TRUE(done.load());
}

// A job an impact waits for (Urgency::First: the body of a piece struck before it was made) goes
// ahead of every queued job, Now and Later; each kind keeps its order.
TEST(BackgroundThreads, FirstJobsGoAheadOfEveryQueuedJob) {
  BackgroundThreads pool(0);  // no threads: the host runs them in queue order when it waits
  std::vector<std::string> order;
  pool.submit([&] { order.push_back("now 1"); });
  pool.submit([&] { order.push_back("later"); }, BackgroundThreads::Urgency::Later);
  pool.submit([&] { order.push_back("now 2"); });
  pool.submit([&] { order.push_back("first 1"); }, BackgroundThreads::Urgency::First);
  pool.submit([&] { order.push_back("first 2"); }, BackgroundThreads::Urgency::First);
  pool.wait();
  EXPECT_EQ(order, (std::vector<std::string>{"first 1", "first 2", "now 1", "now 2", "later"}));
}

// Later jobs run earliest due first (a later break's checks, due sooner, before an earlier
// break's escalations), equal due times in submission order, no due time (NaN or none) last; Now
// jobs keep their submission order whatever time they are given.
TEST(BackgroundThreads, LaterJobsRunEarliestDueFirst) {
  BackgroundThreads pool(0);
  std::vector<std::string> order;
  using U = BackgroundThreads::Urgency;
  pool.submit([&] { order.push_back("escalation of break 1, due 2.1"); }, U::Later, 2.1);
  pool.submit([&] { order.push_back("no due time"); }, U::Later, std::numeric_limits<double>::quiet_NaN());
  pool.submit([&] { order.push_back("check of break 2, due 0.5"); }, U::Later, 0.5);
  pool.submit([&] { order.push_back("analysis of break 2, due 0.5"); }, U::Later, 0.5);
  pool.submit([&] { order.push_back("later check of break 1, due 0.35"); }, U::Later, 0.35);
  pool.submit([&] { order.push_back("now, due 9"); }, U::Now, 9.0);
  pool.submit([&] { order.push_back("now, due 1"); }, U::Now, 1.0);
  pool.wait();
  EXPECT_EQ(order, (std::vector<std::string>{"now, due 9", "now, due 1", "later check of break 1, due 0.35",
                                             "check of break 2, due 0.5", "analysis of break 2, due 0.5",
                                             "escalation of break 1, due 2.1", "no due time"}));
}

TEST(BackgroundThreads, JobsNotStartedAreDroppedWithThePool) {
  std::atomic<int> ran{0};
  {
    BackgroundThreads pool(0);
    for (int i = 0; i < 3; ++i) pool.submit([&] { ++ran; });
  }
  EXPECT_EQ(ran.load(), 0);
  // A running job is waited for; the one behind it is dropped.
  std::atomic<bool> release{false}, running{false};
  std::thread releaser;
  {
    BackgroundThreads pool(1);
    pool.submit([&] {
      running = true;
      while (!release) std::this_thread::yield();
      ++ran;
    });
    while (!running) std::this_thread::yield();
    pool.submit([&] { ran += 10; });
    // Released only once the pool's destructor has dropped the second job and waits for the first.
    releaser = std::thread([&] {
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
      release = true;
    });
  }
  releaser.join();
  EXPECT_EQ(ran.load(), 1);
}

// A job that would run for a minute unless cancelled: the pool's destructor stops it at its next
// cancellation point, and the job behind it never starts. Cancelled is the job's own end, not an
// error a host's wait() would rethrow.
TEST(BackgroundThreads, ARunningJobStopsAtItsNextCancellationPointWhenThePoolIsDestroyed) {
  std::atomic<bool> running{false};
  std::atomic<int> points{0}, finished{0}, behind{0};
  const auto start = std::chrono::steady_clock::now();
  {
    BackgroundThreads pool(1);
    pool.submit([&] {
      running = true;
      while (std::chrono::steady_clock::now() - start < std::chrono::seconds(60)) {
        cancellationPoint();
        ++points;
        std::this_thread::sleep_for(std::chrono::microseconds(100));
      }
      ++finished;
    });
    pool.submit([&] { ++behind; });
    while (!running) std::this_thread::yield();
  }
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(30));  // not run to its end
  EXPECT_EQ(finished.load(), 0);
  EXPECT_EQ(behind.load(), 0);
}

// cancel() returns at once, leaves the jobs' owner's flag set (the World's, which its submitted
// impacts read too) and drops what is queued; the host's own thread is never cancelled, even while
// its jobs are.
TEST(BackgroundThreads, CancelSetsTheOwnersFlagAndNeverCancelsTheHost) {
  std::atomic<bool> closing{false}, running{false}, stopped{false};
  std::atomic<int> behind{0};
  BackgroundThreads pool(1, &closing);
  pool.submit([&] {
    running = true;
    try {
      for (;;) {
        cancellationPoint();
        std::this_thread::yield();
      }
    } catch (const Cancelled&) {
      stopped = true;
      throw;
    }
  });
  pool.submit([&] { ++behind; });
  while (!running) std::this_thread::yield();
  EXPECT_FALSE(closing.load());
  pool.cancel();
  EXPECT_TRUE(closing.load());
  EXPECT_NO_THROW(cancellationPoint());  // this thread has no flag
  {
    const CancelScope scope(tCancelFlag, &closing);  // as a World's impact task on a worker
    EXPECT_THROW(cancellationPoint(), Cancelled);
  }
  EXPECT_NO_THROW(cancellationPoint());  // the scope restored the thread's flag
  const auto start = std::chrono::steady_clock::now();
  while (!stopped && std::chrono::steady_clock::now() - start < std::chrono::seconds(20)) std::this_thread::yield();
  EXPECT_TRUE(stopped.load());
  EXPECT_TRUE(pool.wait());  // no error: a cancelled job is dropped, not failed
  EXPECT_EQ(behind.load(), 0);
}

}  // namespace
}  // namespace brittle::detail
