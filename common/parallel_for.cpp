#include "common/parallel_for.hpp"

#include <pthread.h>

#include <condition_variable>
#include <deque>
#include <memory>
#include <mutex>
#include <system_error>
#include <thread>
#include <vector>

namespace pp5 {

namespace {

// The kept threads. Each waits for a job of its own; after the job it puts itself back on
// the idle list and then calls done. Never destroyed: a kept thread blocked on its condition
// variable at exit ends with the process (joining it from a static destructor could wait
// on a job still running on another thread at exit).
class HostThreads {
 public:
  bool start(std::function<void()> job, std::function<void()> done) {
    Helper* h = nullptr;
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      if (!idle_.empty()) {
        h = idle_.back();
        idle_.pop_back();
      }
    }
    if (h == nullptr) {
      auto made = std::make_unique<Helper>();
      try {
        Helper* raw = made.get();
        made->thread = std::thread([this, raw] { loop(*raw); });
      } catch (const std::system_error&) {
        return false;
      }
      h = made.get();
      const std::lock_guard<std::mutex> lock(mutex_);
      all_.push_back(std::move(made));
    }
    {
      const std::lock_guard<std::mutex> lock(h->mutex);
      h->job = std::move(job);
      h->done = std::move(done);
      h->has_job = true;
    }
    h->wake.notify_one();
    return true;
  }
  int kept() {
    const std::lock_guard<std::mutex> lock(mutex_);
    return static_cast<int>(all_.size());
  }

 private:
  struct Helper {
    std::thread thread;
    std::mutex mutex;
    std::condition_variable wake;
    bool has_job = false;
    std::function<void()> job, done;
  };
  void loop(Helper& h) {
    for (;;) {
      std::function<void()> job, done;
      {
        std::unique_lock<std::mutex> lock(h.mutex);
        h.wake.wait(lock, [&h] { return h.has_job; });
        job = std::move(h.job);
        done = std::move(h.done);
        h.has_job = false;
      }
      job();  // parallel_for's worker catches what its bodies throw
      job = nullptr;
      {
        const std::lock_guard<std::mutex> lock(mutex_);
        idle_.push_back(&h);
      }
      done();
    }
  }
  std::mutex mutex_;
  std::vector<std::unique_ptr<Helper>> all_;
  std::vector<Helper*> idle_;
};

HostThreads* g_threads = nullptr;
std::once_flag g_threads_once;

HostThreads& host_threads() {
  std::call_once(g_threads_once, [] {
    g_threads = new HostThreads();
    // A child of fork() has none of the parent's threads: it starts a set of its own (the
    // parent's, whose locks a parent thread may have held at the fork, is left alone).
    pthread_atfork(nullptr, nullptr, [] { g_threads = new HostThreads(); });
  });
  return *g_threads;
}

}  // namespace

bool host_threads_start(std::function<void()> job, std::function<void()> done) {
  return host_threads().start(std::move(job), std::move(done));
}

int host_threads_kept() { return host_threads().kept(); }

}  // namespace pp5
