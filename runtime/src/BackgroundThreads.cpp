#include "BackgroundThreads.h"

#include <atomic>
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

BackgroundThreads::BackgroundThreads(int threads) {
  for (int i = 0; i < threads; ++i) {
    mThreads.emplace_back([this] {
      if (becomeBackgroundThread()) ++mIdleThreads;
      run();
    });
  }
}

bool BackgroundThreads::idlePriority() const {
  return !mThreads.empty() && mIdleThreads.load() == static_cast<int>(mThreads.size());
}

BackgroundThreads::~BackgroundThreads() {
  {
    std::unique_lock lock(mMutex);
    mStop = true;
    mQueue.clear();  // not needed any more: their results die with the World
  }
  mWork.notify_all();
  for (std::thread& t : mThreads) t.join();
}

void BackgroundThreads::submit(std::function<void()> job) {
  {
    std::lock_guard lock(mMutex);
    mQueue.push_back(std::move(job));
  }
  mWork.notify_one();
  mIdleWait.notify_all();  // a host in wait() takes it too
}

void BackgroundThreads::execute(std::function<void()>& job) {
  std::exception_ptr error;
  try {
    job();
  } catch (...) {
    error = std::current_exception();
  }
  {
    std::lock_guard lock(mMutex);
    if (error && !mError) mError = error;
    --mRunning;
  }
  mIdleWait.notify_all();
}

void BackgroundThreads::run() {
  for (;;) {
    std::function<void()> job;
    {
      std::unique_lock lock(mMutex);
      mWork.wait(lock, [&] { return mStop || !mQueue.empty(); });
      if (mStop) return;
      job = std::move(mQueue.front());
      mQueue.pop_front();
      ++mRunning;
    }
    execute(job);
  }
}

void BackgroundThreads::wait() {
  for (;;) {
    std::function<void()> job;
    {
      std::unique_lock lock(mMutex);
      mIdleWait.wait(lock, [&] { return !mQueue.empty() || mRunning == 0; });
      if (mQueue.empty()) {  // and nothing running: done
        if (mError) std::rethrow_exception(std::exchange(mError, nullptr));
        return;
      }
      job = std::move(mQueue.front());
      mQueue.pop_front();
      ++mRunning;
    }
    execute(job);
  }
}

}  // namespace brittle::detail
