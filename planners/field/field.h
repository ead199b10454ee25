#pragma once
// Private to planners/field: the two planners' factories and the helpers they share.

#include <cstdint>
#include <memory>
#include <random>
#include <string>

#include <Eigen/Core>

#include "chasles/planners/planner.h"
#include "chasles/robot/error.h"

namespace chasles::field {

PlannerSpec PotentialFieldSpec();
std::unique_ptr<Planner> MakePotentialFieldPlanner(const PlannerSpec& spec);
PlannerSpec WavefrontSpec();
std::unique_ptr<Planner> MakeWavefrontPlanner(const PlannerSpec& spec);

/// Validates one motion as OmplPlanner's MotionChecker does: certified when the checker
/// certifies motions, otherwise discrete at `max_step`. Adds the evaluated states to *checks.
inline bool MotionValid(const CollisionChecker& checker, const Eigen::VectorXd& a, const Eigen::VectorXd& b,
                        double max_step, std::uint64_t* checks) {
  CheckCounters counters;
  const bool ok = checker.certifies_motion() ? checker.IsMotionCertified(a, b, &counters)
                                             : checker.IsMotionValid(a, b, max_step, &counters);
  *checks += counters.state_checks;
  return ok;
}

inline bool StateValid(const CollisionChecker& checker, const Eigen::VectorXd& q, std::uint64_t* checks) {
  ++*checks;
  return checker.IsValid(q);
}

/// "(0.1, -2.3)": a configuration for messages.
inline std::string FormatConfig(const Eigen::VectorXd& q) {
  std::string s = "(";
  for (int i = 0; i < q.size(); ++i) s += (i == 0 ? "" : ", ") + FormatNumber(q[i]);
  return s + ")";
}

/// Fills status and message when `termination` stopped for the client (cancellation, deadline)
/// and returns true; returns false for no stop or the planner's own budget (its caller words
/// that outcome).
inline bool StoppedByClient(const Termination& termination, const std::string& id, PlannerResult* result) {
  switch (termination.Reason()) {
    case StopReason::kCancelled:
      result->status = PlanStatus::kCancelled;
      result->message = "cancelled by the client";
      return true;
    case StopReason::kDeadline:
      result->status = PlanStatus::kDeadlineExceeded;
      result->message = "the gRPC deadline passed before " + id + " found a path";
      return true;
    default:
      return false;
  }
}

/// Reports kInvalidStart / kInvalidGoal (and returns false) when an endpoint is invalid.
inline bool EndpointsValid(const PlanningProblem& problem, const Eigen::VectorXd& goal, const std::string& id,
                           PlannerResult* result, std::uint64_t* checks) {
  if (!StateValid(*problem.checker, problem.start, checks)) {
    result->status = PlanStatus::kInvalidStart;
    result->message = id + ": the start " + FormatConfig(problem.start) + " is in collision or outside the joint limits";
    return false;
  }
  if (!StateValid(*problem.checker, goal, checks)) {
    result->status = PlanStatus::kInvalidGoal;
    result->message = id + ": the goal " + FormatConfig(goal) + " is in collision or outside the joint limits";
    return false;
  }
  return true;
}

/// A portable, reproducible uniform stream: std::mt19937_64's output is fixed by the standard,
/// the standard distributions are not, so draws map its 53 high bits to [0, 1) here.
class UniformStream {
 public:
  explicit UniformStream(std::uint64_t seed) : engine_(seed) {}
  double Next01() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }
  double Next(double lo, double hi) { return lo + (hi - lo) * Next01(); }

 private:
  std::mt19937_64 engine_;
};

}  // namespace chasles::field
