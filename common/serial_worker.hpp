#pragma once
// One helper thread that runs jobs one at a time, in the order they were submitted, while the
// caller goes on: a run of frames executes a frame's pixels on one (Session::run_frames), and
// encodes a frame's images on another (pp5sim animate's outputs). Host speed only: a job's
// result is the same whichever thread runs it.
//
// Contract:
//  - submit(job) returns job's result (or the exception it threw) through a future; jobs run
//    in submission order, never two at once, so jobs that share state need no lock.
//  - The destructor lets the job running finish and drops those not started (their futures
//    report a broken promise): whoever stopped waiting for them (an error, a cancelled run)
//    loses nothing it still uses, since nothing a dropped job refers to is touched.
//  - Without a helper thread (none could be made), submit runs the job itself, at once.
#include <condition_variable>
#include <deque>
#include <functional>
#include <future>
#include <mutex>
#include <system_error>
#include <thread>
#include <utility>

namespace pp5 {

template <class Result>
class SerialWorker {
 public:
  SerialWorker() {
    try {
      thread_ = std::thread([this] { loop(); });
    } catch (const std::system_error&) {
      // No helper thread: submit runs each job itself.
    }
  }
  SerialWorker(const SerialWorker&) = delete;
  SerialWorker& operator=(const SerialWorker&) = delete;
  ~SerialWorker() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    wake_.notify_all();
    if (thread_.joinable()) thread_.join();
  }
  std::future<Result> submit(std::function<Result()> job) {
    std::packaged_task<Result()> task(std::move(job));
    std::future<Result> out = task.get_future();
    if (!thread_.joinable()) {
      task();
      return out;
    }
    {
      std::lock_guard<std::mutex> lock(mutex_);
      jobs_.push_back(std::move(task));
    }
    wake_.notify_one();
    return out;
  }

 private:
  void loop() {
    for (;;) {
      std::packaged_task<Result()> task;
      {
        std::unique_lock<std::mutex> lock(mutex_);
        wake_.wait(lock, [this] { return stop_ || !jobs_.empty(); });
        if (stop_) return;
        task = std::move(jobs_.front());
        jobs_.pop_front();
      }
      task();
    }
  }
  std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<std::packaged_task<Result()>> jobs_;
  bool stop_ = false;
  std::thread thread_;  // last: it starts once the rest exists
};

}  // namespace pp5
