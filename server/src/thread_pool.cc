#include "chasles/server/thread_pool.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace chasles {

int PoolOptions::MaxLongWorkers(int workers) const {
  if (workers <= 1) return 1;
  const int share = static_cast<int>(std::floor(long_share * workers + 1e-9));
  if (long_share >= 1.0) return workers;
  return std::clamp(share, 1, workers - 1);
}

namespace {

PoolOptions WithThreads(int threads, std::size_t max_queued) {
  PoolOptions options;
  options.threads = threads;
  options.max_queued = max_queued;
  options.max_queued_per_client = max_queued;
  return options;
}

}  // namespace

ThreadPool::ThreadPool(int threads, std::size_t max_queued) : ThreadPool(WithThreads(threads, max_queued)) {}

ThreadPool::ThreadPool(const PoolOptions& options) : options_(options) {
  int threads = options.threads;
  if (threads <= 0) threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  max_long_ = options.MaxLongWorkers(threads);
  workers_.reserve(threads);
  for (int i = 0; i < threads; ++i) workers_.emplace_back([this] { Run(); });
}

ThreadPool::~ThreadPool() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  ready_.notify_all();
  for (std::thread& worker : workers_) worker.join();
}

SubmitResult ThreadPool::TrySubmit(std::function<void()> job, const JobTicket& ticket) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (stopping_) return SubmitResult::kStopping;
    if (queued_ >= options_.max_queued) return SubmitResult::kQueueFull;
    std::deque<Job>& queue = queues_[ticket.client];
    if (queue.size() >= options_.max_queued_per_client) {
      if (queue.empty()) queues_.erase(ticket.client);
      return SubmitResult::kClientQueueFull;
    }
    if (queue.empty()) turn_.push_back(ticket.client);
    queue.push_back(Job{std::move(job), ticket.long_running});
    ++queued_;
  }
  ready_.notify_one();
  return SubmitResult::kQueued;
}

SchedulerStats ThreadPool::stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  SchedulerStats stats;
  stats.queued = queued_;
  stats.workers_busy = static_cast<std::uint64_t>(running_);
  stats.in_flight = queued_ + static_cast<std::uint64_t>(running_);
  stats.workers = workers_.size();
  return stats;
}

bool ThreadPool::TakeNext(Job* job) {
  const bool long_allowed = long_running_ < max_long_;
  for (std::size_t k = 0; k < turn_.size(); ++k) {
    auto queue_it = queues_.find(turn_[k]);
    std::deque<Job>& queue = queue_it->second;
    auto it = std::find_if(queue.begin(), queue.end(),
                           [long_allowed](const Job& candidate) { return long_allowed || !candidate.long_running; });
    if (it == queue.end()) continue;
    *job = std::move(*it);
    queue.erase(it);
    --queued_;
    // This client has had its turn: it goes to the back (or leaves when it has nothing left).
    std::string client = std::move(turn_[k]);
    turn_.erase(turn_.begin() + static_cast<std::ptrdiff_t>(k));
    if (queue.empty()) {
      queues_.erase(queue_it);
    } else {
      turn_.push_back(std::move(client));
    }
    return true;
  }
  return false;
}

void ThreadPool::Run() {
  for (;;) {
    Job job;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      ready_.wait(lock, [&] { return (stopping_ && queued_ == 0) || TakeNext(&job); });
      if (!job.run) return;  // stopping and drained
      ++running_;
      if (job.long_running) ++long_running_;
    }
    job.run();
    {
      std::lock_guard<std::mutex> lock(mutex_);
      --running_;
      if (job.long_running) --long_running_;
    }
    // A finished long job can make a waiting long job runnable; wake every worker to look.
    if (job.long_running) ready_.notify_all();
  }
}

}  // namespace chasles
