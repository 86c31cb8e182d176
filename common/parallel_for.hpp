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
#include <algorithm>
#include <atomic>
#include <exception>
#include <mutex>
#include <system_error>
#include <thread>
#include <type_traits>
#include <vector>

namespace pp5 {

inline int parallel_workers(int count, int threads) {
  return std::max(1, std::min(threads, count));
}

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
  std::vector<std::thread> pool;
  pool.reserve(static_cast<std::size_t>(n - 1));
  for (int t = 1; t < n; ++t) {
    // A thread the host cannot start is work the others take over.
    try {
      pool.emplace_back(worker, t);
    } catch (const std::system_error&) {
      break;
    }
  }
  worker(0);
  for (auto& t : pool) t.join();
  if (error) std::rethrow_exception(error);
}

}  // namespace pp5
