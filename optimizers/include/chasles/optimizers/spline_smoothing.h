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
  /// K: 0 = one knot span per phase (piece) of the initial trajectory, 8 to 30 spans, plus the
  /// degree; else within [degree + 1, 500]. With K < 6 (cubic only) an end at rest fixes its
  /// velocity but not its acceleration, so max_jerk then needs K >= 6. The solve grows
  /// roughly with K³: ~20 control points of 7 joints take ~0.3 s.
  int control_points = 0;
  /// w >= 0 in the objective T + w·∫‖q⃛‖² dt [s⁶/rad²].
  double jerk_weight = 0.0;
  /// Required distance between links and obstacles [m], >= 0; used only with a checker whose
  /// scene has obstacles. Where the initial trajectory itself comes closer (within one knot
  /// span of the corresponding time), its own distance there is required instead.
  double clearance = 0.01;
  /// Control points stay within this distance (per joint) of their initial fit [rad], > 0.
  double max_deviation = 0.1;
  /// "slsqp" (NLOPT_LD_SLSQP) or "mma" (NLOPT_LD_MMA). SLSQP converges in tens to a few hundred
  /// evaluations here; MMA's dual over hundreds of constraints makes it far slower, mostly
  /// ending at the evaluation or time budget.
  std::string algorithm = "slsqp";
  int max_evaluations = 2000;    ///< objective evaluations in all, >= 1
  double time_budget = 5.0;      ///< [s] of wall time in all, > 0
  std::function<bool()> stop;    ///< optional: polled each evaluation; true ends the solve (not ok)
};

struct SplineResult {
  TimedTrajectory trajectory;    ///< polynomial pieces of the spline; empty unless report.ok
  OptimizerReport report;
};

/// Fits a clamped B-spline in time to `initial` (usually the time-optimal parameterisation of
/// the path), then optimises its control points and knot-span durations for time + w·∫‖q⃛‖².
///
/// Formulation. Degree p, K control points, m = K − p knot spans of durations Δⱼ > 0 (the
/// variables, with the free control points). Start and end states are those of `initial`:
/// positions exact; an end at rest has zero velocity and, with K >= 6, zero acceleration
/// (three equal control points); a moving end keeps its velocity. The derivative control points (hodographs) bound
/// the derivatives everywhere (convex hull), so |C⁽ʳ⁾ᵢ| <= (1 − 1e-5)·limit for velocity,
/// acceleration and, when max_jerk is set, jerk make the limits exact. Control points stay
/// within max_deviation of the fit and within the robot's joint limits (with a checker), so
/// positions do too. With obstacles, the smallest link–obstacle distance (ObstacleProximity,
/// gradient n̂ᵀ·J_v) is constrained at states sampled every 0.05 rad of joint travel; the
/// result is then checked at states 0.002 rad and 1 ms apart, and a state that comes too
/// close becomes a sample of another solve from the best point (up to 4 solves).
/// The objective ΣΔⱼ + w·∫‖q⃛‖² is exact per span; all gradients are analytic.
///
/// The warm start is a least-squares fit of the control points to `initial` on uniform spans,
/// slowed so its hodographs meet the limits. NLopt stops at xtol_rel 1e-7, max_evaluations or
/// time_budget; the best point seen that meets the limits (after slowing down by at most
/// 0.1 %, 1e-9 with a moving end) and the clearance is returned: one polynomial piece per span
/// (power basis, each from the spline at its own span start), ending exactly at the goal.
/// report.time_scale says how much it was slowed. The result must pass VerifyTrajectory with
/// the same limits (and the checker, when given) — torque limits (max_effort) are not
/// constraints of the spline but are verified there.
///
/// report.ok = false, with an empty trajectory and the reason in report.message, when the
/// solve was stopped, NLopt failed, no point met the limits and the clearance, or the result
/// fails the verification (the caller then falls back to an exact parameterisation). The
/// result is deterministic for the same input unless time_budget ends the solve.
///
/// A trajectory of zero duration is returned as it is (ok).
/// \throws Error(kInvalidArgument) naming the option for a degree other than 3 or 5, too few
///   (or more than 500) control points, fewer than 6 with max_jerk set, negative or
///   non-finite weights, clearance or
///   max_deviation, an unknown algorithm, max_evaluations < 1, a time_budget not > 0, limits
///   that fail Validate, an empty initial trajectory or one with non-finite coefficients, a
///   checker for a robot with a different number of joints, or max_effort with a checker
///   whose robot has no inertia.
SplineResult SmoothWithBSpline(const TimedTrajectory& initial, const KinematicLimits& limits,
                               const SplineOptions& options, const CollisionChecker* checker = nullptr);

}  // namespace chasles
