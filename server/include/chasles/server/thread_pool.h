#pragma once
/// \file
/// The server's own bounded worker pool: planning never runs on a gRPC reactor thread.

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace chasles {

/// A fixed number of workers and a bounded FIFO queue. Thread-safe.
class ThreadPool {
 public:
  /// `threads` workers (0 = hardware threads, at least 1); at most `max_queued` waiting jobs.
  explicit ThreadPool(int threads, std::size_t max_queued = 1024);
  /// Runs the jobs already queued, then joins the workers.
  ~ThreadPool();
  ThreadPool(const ThreadPool&) = delete;
  ThreadPool& operator=(const ThreadPool&) = delete;

  /// Queues `job`. Returns false (and drops it) when the queue is full or the pool is stopping.
  bool Submit(std::function<void()> job);
  int num_threads() const { return static_cast<int>(workers_.size()); }

 private:
  void Run();

  const std::size_t max_queued_;
  std::mutex mutex_;
  std::condition_variable ready_;
  std::deque<std::function<void()>> jobs_;
  bool stopping_ = false;
  std::vector<std::thread> workers_;
};

}  // namespace chasles
