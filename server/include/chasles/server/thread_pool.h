#pragma once
/// \file
/// The server's own worker pool with fair queueing: planning never runs on a gRPC reactor
/// thread, no client can starve another, and long anytime work cannot hold every worker.

#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "chasles/server/request_record.h"

namespace chasles {

/// How a pool schedules. Defaults suit a planning server.
struct PoolOptions {
  int threads = 0;                          ///< workers; 0 = hardware threads (at least 1)
  std::size_t max_queued = 1024;            ///< waiting jobs over all clients
  std::size_t max_queued_per_client = 256;  ///< waiting jobs of one client
  /// Share of the workers that long jobs may hold at once, in (0, 1]. At least one worker may
  /// always run a long job; with more than one worker at least one is kept for short jobs
  /// whenever the share is below 1.
  double long_share = 0.5;
  /// Workers that long jobs may hold at once, from `threads` and `long_share`.
  int MaxLongWorkers(int workers) const;
};

/// Who submitted a job and how long it may hold a worker.
struct JobTicket {
  std::string client;         ///< fairness key: authenticated identity, else the peer address
  bool long_running = false;  ///< its budget exceeds the server's long-budget threshold
};

/// Why Submit refused a job.
enum class SubmitResult { kQueued, kQueueFull, kClientQueueFull, kStopping };

/// A fixed number of workers and per-client FIFO queues served round-robin: a worker takes the
/// next runnable job of the next client in turn, so a client with many queued jobs delays each
/// other client by at most one job per worker. A long job is runnable only while fewer than
/// `MaxLongWorkers` long jobs run; a client's short job may overtake its own waiting long job.
/// Thread-safe.
class ThreadPool {
 public:
  explicit ThreadPool(const PoolOptions& options);
  /// `threads` workers (0 = hardware threads), at most `max_queued` waiting jobs, one client.
  explicit ThreadPool(int threads, std::size_t max_queued = 1024);
  /// Runs the jobs already queued, then joins the workers.
  ~ThreadPool();
  ThreadPool(const ThreadPool&) = delete;
  ThreadPool& operator=(const ThreadPool&) = delete;

  /// Queues `job` for `ticket.client`; returns why not when it does not (and drops the job).
  SubmitResult TrySubmit(std::function<void()> job, const JobTicket& ticket);
  /// Queues `job` as a short job of an anonymous client. Returns false when refused.
  bool Submit(std::function<void()> job, const JobTicket& ticket = {}) {
    return TrySubmit(std::move(job), ticket) == SubmitResult::kQueued;
  }
  int num_threads() const { return static_cast<int>(workers_.size()); }
  int max_long_workers() const { return max_long_; }
  SchedulerStats stats() const;

 private:
  struct Job {
    std::function<void()> run;
    bool long_running = false;
  };
  void Run();
  /// Takes the next runnable job in round-robin order; false when none is runnable.
  bool TakeNext(Job* job);

  const PoolOptions options_;
  int max_long_ = 1;
  mutable std::mutex mutex_;
  std::condition_variable ready_;
  std::map<std::string, std::deque<Job>> queues_;  ///< per client; only non-empty queues
  std::deque<std::string> turn_;                   ///< clients with queued jobs, next first
  std::size_t queued_ = 0;
  int running_ = 0;
  int long_running_ = 0;
  bool stopping_ = false;
  std::vector<std::thread> workers_;
};

}  // namespace chasles
