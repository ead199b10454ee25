#pragma once
/// \file
/// Smoothing a path into a clamped B-spline trajectory, optimised with NLopt.

#include <functional>
#include <string>

#include <Eigen/Core>

#include "chasles/collision/collision_checker.h"
#include "chasles/optimizers/optimizer_report.h"
#include "chasles/optimizers/time_parameterization.h"
#include "chasles/optimizers/timed_trajectory.h"

namespace chasles {

struct SplineOptions {
  int degree = 3;                ///< 3 (C² trajectory) or 5 (C⁴)
  int control_points = 0;        ///< 0 = chosen from the path; else >= degree + 1
  /// w >= 0 in the objective T + w·∫‖q⃛‖² dt [s⁶/rad²].
  double jerk_weight = 0.0;
  /// Required distance between links and obstacles at the sampled states [m], >= 0; used only
  /// with a checker whose scene has obstacles.
  double clearance = 0.01;
  /// Control points stay within this distance (per joint) of their initial fit [rad], > 0.
  double max_deviation = 0.1;
  std::string algorithm = "slsqp";  ///< "slsqp" (NLOPT_LD_SLSQP) or "mma" (NLOPT_LD_MMA)
  int max_evaluations = 2000;    ///< >= 1
  double time_budget = 5.0;      ///< [s], > 0
  std::function<bool()> stop;    ///< optional: polled each evaluation; true ends the solve
};

struct SplineResult {
  TimedTrajectory trajectory;    ///< polynomial pieces of the spline; empty unless report.ok
  OptimizerReport report;
};

/// Fits a clamped B-spline in time to `initial` (usually the time-optimal parameterisation of
/// the path), then optimises its control points and knot-span durations for time + w·∫‖q⃛‖²
/// under velocity, acceleration (and jerk) limits on the derivative control points (so they
/// hold everywhere by the convex-hull property) and clearance at sampled states. Start and end
/// states are those of `initial`.
/// \throws Error(kInvalidArgument) naming the option for a degree other than 3 or 5, too few
///   control points, negative or non-finite weights, non-positive limits, an unknown
///   algorithm, or an empty initial trajectory.
SplineResult SmoothWithBSpline(const TimedTrajectory& initial, const KinematicLimits& limits,
                               const SplineOptions& options, const CollisionChecker* checker = nullptr);

}  // namespace chasles
