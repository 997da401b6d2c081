#include "BackgroundThreads.h"

#include "Cancellation.h"

#include <atomic>
#include <chrono>
#include <cmath>
#include <utility>

#if defined(__linux__)
#include <pthread.h>
#include <sched.h>
#endif

namespace brittle::detail {
namespace {

// The calling thread named "brittle-bg" (what profilers and debuggers show, and how the
// allocation test tells these threads from an impact's), then at the lowest scheduling class: it
// runs when no other thread of the system wants the core. Lowering a thread's own priority needs
// no privilege.
bool becomeBackgroundThread() {
#if defined(__linux__)
  pthread_setname_np(pthread_self(), "brittle-bg");
#endif
#if defined(__linux__) && defined(SCHED_IDLE)
  sched_param param{};
  param.sched_priority = 0;
  return pthread_setschedparam(pthread_self(), SCHED_IDLE, &param) == 0;
#else
  return false;
#endif
}

}  // namespace

BackgroundThreads::BackgroundThreads(int threads, std::atomic<bool>* cancel) {
  if (cancel != nullptr) mCancel = cancel;
  for (int i = 0; i < threads; ++i) {
    mThreads.emplace_back([this] {
      tCancelFlag = mCancel;  // this thread's jobs end when it is set
      if (becomeBackgroundThread()) ++mIdleThreads;
      run();
    });
    mClocks.push_back(threadCpuClock(mThreads.back().native_handle()));
  }
}

double BackgroundThreads::threadsCpuSeconds() const {
  double sum = 0.0;
  for (clockid_t clock : mClocks) {
    const double s = clockSeconds(clock);
    if (s < 0.0) return -1.0;
    sum += s;
  }
  return sum;
}

bool BackgroundThreads::idlePriority() const {
  return !mThreads.empty() && mIdleThreads.load() == static_cast<int>(mThreads.size());
}

void BackgroundThreads::cancel() {
  std::deque<std::function<void()>> dropped[2];  // destroyed after the lock: their captures may be large
  std::multimap<double, std::function<void()>> droppedLater;
  {
    std::unique_lock lock(mMutex);
    mStop = true;
    dropped[0].swap(mFirstQueue);  // not needed any more: their results die with the World
    dropped[1].swap(mQueue);
    droppedLater.swap(mLaterQueue);
    mCancel->store(true, std::memory_order_relaxed);
  }
  mWork.notify_all();
  mIdleWait.notify_all();
}

BackgroundThreads::~BackgroundThreads() {
  cancel();
  for (std::thread& t : mThreads) t.join();
}

void BackgroundThreads::submit(std::function<void()> job, Urgency urgency, double dueS) {
  {
    std::lock_guard lock(mMutex);
    if (urgency == Urgency::Later) {
      mLaterQueue.emplace(std::isnan(dueS) ? std::numeric_limits<double>::infinity() : dueS, std::move(job));
    } else {
      (urgency == Urgency::First ? mFirstQueue : mQueue).push_back(std::move(job));
    }
  }
  mWork.notify_one();
  mIdleWait.notify_all();  // a host in wait() takes it too
}

bool BackgroundThreads::take(std::function<void()>& job, bool& later, bool host) {
  later = mFirstQueue.empty() && mQueue.empty();
  if (later && (mLaterQueue.empty() || (!host && mRunningLater >= laterThreads()))) return false;
  if (later) {
    job = std::move(mLaterQueue.begin()->second);  // the earliest due
    mLaterQueue.erase(mLaterQueue.begin());
  } else {
    std::deque<std::function<void()>>& queue = !mFirstQueue.empty() ? mFirstQueue : mQueue;
    job = std::move(queue.front());
    queue.pop_front();
  }
  ++mRunning;
  later = later && !host;  // the host's own are not the threads' to count
  if (later) ++mRunningLater;
  return true;
}

void BackgroundThreads::execute(std::function<void()>& job, bool later) {
  std::exception_ptr error;
  try {
    job();
  } catch (const Cancelled&) {
    // dropped: cancel() was called, and nobody wants its result
  } catch (...) {
    error = std::current_exception();
  }
  {
    std::lock_guard lock(mMutex);
    if (error && !mError) mError = error;
    --mRunning;
    if (later) --mRunningLater;
  }
  if (later) mWork.notify_one();  // a Later job waiting for a thread may start
  mIdleWait.notify_all();
}

void BackgroundThreads::run() {
  for (;;) {
    std::function<void()> job;
    bool later = false;
    {
      std::unique_lock lock(mMutex);
      mWork.wait(lock, [&] { return mStop || take(job, later, /*host=*/false); });
      if (mStop) return;
    }
    execute(job, later);
  }
}

bool BackgroundThreads::wait(bool untilStarved) {
  // With untilStarved: the running jobs' threads watched from when the host began to wait for
  // them; the watch starts again when a job starts or ends.
  int watchedRunning = -1;
  double cpuStart = 0.0;
  auto wallStart = std::chrono::steady_clock::now();
  for (;;) {
    std::function<void()> job;
    bool later = false;
    {
      std::unique_lock lock(mMutex);
      const auto actionable = [&] {
        return !mFirstQueue.empty() || !mQueue.empty() || !mLaterQueue.empty() || mRunning == 0;
      };
      if (!untilStarved) mIdleWait.wait(lock, actionable);
      while (!actionable()) {
        if (watchedRunning != mRunning) {
          watchedRunning = mRunning;
          cpuStart = threadsCpuSeconds();
          wallStart = std::chrono::steady_clock::now();
        }
        mIdleWait.wait_for(lock, kStarvedSlice);
        if (actionable() || watchedRunning != mRunning) continue;
        const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wallStart).count();
        if (starved(cpuStart, threadsCpuSeconds() - cpuStart, wall)) {
          if (mError) std::rethrow_exception(std::exchange(mError, nullptr));
          return false;
        }
      }
      if (!take(job, later, /*host=*/true)) {  // nothing queued and nothing running: done
        if (mError) std::rethrow_exception(std::exchange(mError, nullptr));
        return true;
      }
    }
    execute(job, later);
    watchedRunning = -1;
  }
}

}  // namespace brittle::detail
