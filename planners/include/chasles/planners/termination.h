#pragma once
/// \file
/// Termination: when a planner or optimiser must stop. Composes the request's time budget,
/// the gRPC deadline and client cancellation; can be triggered from another thread.

#include <atomic>
#include <chrono>
#include <memory>

namespace chasles {

/// Why work stopped early.
enum class StopReason { kNone, kBudget, kDeadline, kCancelled };

/// Cheap to copy; copies share the cancellation flag. Thread-safe.
class Termination {
 public:
  using Clock = std::chrono::steady_clock;

  /// Never stops by itself (until Cancel()).
  Termination();
  /// Stops at `budget_end` (reported kBudget), at `deadline` (reported kDeadline), or on Cancel().
  Termination(Clock::time_point budget_end, Clock::time_point deadline);
  /// A termination that is already triggered (used by the planner contract test).
  static Termination AlreadyStopped();
  /// Stops after `budget` from now.
  static Termination After(std::chrono::duration<double> budget);

  /// A copy that also stops after `budget` from now (kBudget), sharing this one's cancellation
  /// and deadline: a stage's share of a request's budget.
  Termination WithBudget(std::chrono::duration<double> budget) const;
  /// A copy whose budget ends `budget` from now even when this one's budget has ended, sharing
  /// its cancellation and deadline: work a request still owes after spending its budget (the
  /// repair of a trajectory that failed verification).
  Termination WithFreshBudget(std::chrono::duration<double> budget) const;
  /// Triggers cancellation for every copy, from any thread.
  void Cancel() const { cancelled_->store(true, std::memory_order_relaxed); }
  bool ShouldStop() const { return Reason() != StopReason::kNone; }
  StopReason Reason() const;
  /// Seconds left before the earliest of budget end and deadline (0 if past, can be +inf).
  double SecondsLeft() const;

 private:
  Clock::time_point budget_end_;
  Clock::time_point deadline_;
  std::shared_ptr<std::atomic<bool>> cancelled_;
};

}  // namespace chasles
