#pragma once
/// \file
/// Minimum-time (plus jerk) trajectories by direct collocation, solved with Ipopt.

#include <functional>

#include <Eigen/Core>

#include "chasles/collision/collision_checker.h"
#include "chasles/optimizers/optimizer_report.h"
#include "chasles/optimizers/time_parameterization.h"
#include "chasles/optimizers/timed_trajectory.h"

namespace chasles {

struct CollocationOptions {
  int knots = 100;              ///< K >= 2 knots, K − 1 intervals with their own durations
  /// w >= 0 in the objective T + w·∫‖q⃛‖² dt [s⁶/rad²]; 0 = minimum time only.
  double jerk_weight = 0.0;
  /// Required distance between every link and every obstacle at each knot and each interval
  /// midpoint [m], >= 0; used only with a checker whose scene has obstacles.
  double clearance = 0.01;
  int max_iterations = 500;     ///< Ipopt max_iter, >= 1
  double tolerance = 1e-8;      ///< Ipopt tol, > 0
  double time_budget = 5.0;     ///< [s] of solver time (Ipopt max_cpu_time), > 0
  /// Optional: polled every iteration; true stops the solve (the result is then not ok).
  std::function<bool()> stop;
};

struct CollocationResult {
  TimedTrajectory trajectory;   ///< cubic pieces (constant jerk per interval); empty unless report.ok
  OptimizerReport report;
};

/// Direct collocation on the triple integrator q⃛ = u with states (q, q̇, q̈) at K knots,
/// piecewise-constant jerk u and a free duration hₖ per interval, so each interval is an
/// exact cubic (Hermite–Simpson collocation is exact for it). The start and end states
/// (position, velocity) are those of `warm_start`, which also initialises every variable.
/// Constraints: position, velocity and acceleration limits at the knots, jerk limits on u,
/// torque limits via inverse dynamics at the knots (max_effort, robot with inertia), and the
/// clearance at knots and midpoints (distances and point Jacobians). After the solve the
/// trajectory is slowed uniformly if needed (OptimizerReport::time_scale) so the limits hold
/// between knots exactly too.
/// \throws Error(kInvalidArgument) naming the option for knots < 2, negative or non-finite
///   weights/clearance, max_iterations < 1, tolerance/time_budget not > 0, an empty
///   warm start, or limits that fail Validate.
CollocationResult OptimizeByCollocation(const TimedTrajectory& warm_start, const KinematicLimits& limits,
                                        const CollocationOptions& options,
                                        const CollisionChecker* checker = nullptr);

}  // namespace chasles
