#include "chasles/planners/termination.h"

#include <algorithm>
#include <limits>

namespace chasles {

Termination::Termination()
    : budget_end_(Clock::time_point::max()),
      deadline_(Clock::time_point::max()),
      cancelled_(std::make_shared<std::atomic<bool>>(false)) {}

Termination::Termination(Clock::time_point budget_end, Clock::time_point deadline)
    : budget_end_(budget_end),
      deadline_(deadline),
      cancelled_(std::make_shared<std::atomic<bool>>(false)) {}

Termination Termination::AlreadyStopped() {
  Termination t;
  t.Cancel();
  return t;
}

Termination Termination::After(std::chrono::duration<double> budget) {
  return Termination(Clock::now() + std::chrono::duration_cast<Clock::duration>(budget),
                     Clock::time_point::max());
}

Termination Termination::WithBudget(std::chrono::duration<double> budget) const {
  Termination t = *this;
  const double seconds = std::min(budget.count(), 1e7);  // far enough; avoids time_point overflow
  const Clock::time_point end =
      Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(std::max(0.0, seconds)));
  t.budget_end_ = std::min(budget_end_, end);
  return t;
}

Termination Termination::WithFreshBudget(std::chrono::duration<double> budget) const {
  Termination t = *this;
  t.budget_end_ = Clock::time_point::max();
  return t.WithBudget(budget);
}

StopReason Termination::Reason() const {
  if (cancelled_->load(std::memory_order_relaxed)) return StopReason::kCancelled;
  if (budget_end_ == Clock::time_point::max() && deadline_ == Clock::time_point::max()) {
    return StopReason::kNone;
  }
  const auto now = Clock::now();
  // The deadline is reported first when both have passed: it is the caller's hard limit.
  if (now >= deadline_) return StopReason::kDeadline;
  if (now >= budget_end_) return StopReason::kBudget;
  return StopReason::kNone;
}

double Termination::SecondsLeft() const {
  const auto end = std::min(budget_end_, deadline_);
  if (end == Clock::time_point::max()) return std::numeric_limits<double>::infinity();
  const double left = std::chrono::duration<double>(end - Clock::now()).count();
  return std::max(0.0, left);
}

}  // namespace chasles
