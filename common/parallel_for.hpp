#pragma once
// The host's thread pool: independent pieces of work (one Renderer board's regions, one
// region of a field readout) spread over a few host threads. Host speed only: the simulated
// results never depend on it.
//
// Contract:
//  - body(i) runs exactly once for every i in [0, count) that is started, on at most
//    parallel_workers(count, threads) threads, the calling thread one of them; indices are
//    taken in increasing order, each by whichever thread is free first. A body that takes
//    two ints is called as body(i, worker), worker in [0, parallel_workers(count, threads)):
//    no two calls with the same worker overlap, so per-worker state needs no lock.
//  - If a body throws, no further index is started; once every running body has returned,
//    the exception is rethrown on the calling thread (the first one thrown, if several are).
//    An exception never escapes a worker thread, so it never terminates the process.
//  - The other threads are kept host threads (host_threads_start): made on first use and
//    kept for the next call, so a run of many frames pays neither a thread's start nor a
//    new thread's first allocations (page faults in a malloc arena of its own) per frame. A
//    call made while every kept thread is busy (a nested call, or calls from several
//    threads) gets new ones, so it never waits for another call's work.
#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <exception>
#include <functional>
#include <mutex>
#include <type_traits>

namespace pp5 {

inline int parallel_workers(int count, int threads) {
  return std::max(1, std::min(threads, count));
}

// Runs job() and then done() on a kept host thread that is idle, or on a new one (kept
// afterwards); the thread is idle again before done() is called. False when no thread is
// idle and none can be made (neither is then called). Defined in common/parallel_for.cpp.
bool host_threads_start(std::function<void()> job, std::function<void()> done);
// Host threads kept so far (idle or busy): for tests.
int host_threads_kept();

template <class Body>
void parallel_for(int count, int threads, Body&& body) {
  std::atomic<int> next{0};
  std::atomic<bool> failed{false};
  std::exception_ptr error;
  std::mutex error_mutex;
  auto worker = [&](int w) {
    for (int i = next++; i < count && !failed; i = next++) {
      try {
        if constexpr (std::is_invocable_v<Body&, int, int>) {
          body(i, w);
        } else {
          body(i);
        }
      } catch (...) {
        const std::lock_guard<std::mutex> lock(error_mutex);
        if (!error) error = std::current_exception();
        failed = true;
      }
    }
  };
  const int n = parallel_workers(count, threads);
  std::mutex running_mutex;
  std::condition_variable finished;
  int running = 0;
  for (int t = 1; t < n; ++t) {
    {
      const std::lock_guard<std::mutex> lock(running_mutex);
      ++running;
    }
    // done() signals under the lock, so this frame outlives its last use by a helper.
    const bool started = host_threads_start([&worker, t] { worker(t); },
                                            [&running_mutex, &running, &finished] {
                                              const std::lock_guard<std::mutex> lock(running_mutex);
                                              --running;
                                              finished.notify_all();
                                            });
    if (!started) {  // a thread the host cannot start is work the others take over
      const std::lock_guard<std::mutex> lock(running_mutex);
      --running;
      break;
    }
  }
  worker(0);
  {
    std::unique_lock<std::mutex> lock(running_mutex);
    finished.wait(lock, [&running] { return running == 0; });
  }
  if (error) std::rethrow_exception(error);
}

}  // namespace pp5
