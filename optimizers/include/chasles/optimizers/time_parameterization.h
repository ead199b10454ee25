#pragma once
/// \file
/// Exact time parameterisation of joint-space paths: rest-to-rest along each straight segment
/// (the fallback every optimiser can land on), and the time-optimal parameterisation with
/// bounded-deviation blends at the corners.

#include <string>

#include <Eigen/Core>

#include "chasles/collision/collision_checker.h"
#include "chasles/optimizers/timed_trajectory.h"

namespace chasles {

/// Per-joint limits the trajectory must respect.
struct KinematicLimits {
  Eigen::VectorXd max_velocity;      ///< > 0 [rad/s] per joint
  Eigen::VectorXd max_acceleration;  ///< > 0 [rad/s²] per joint
  Eigen::VectorXd max_jerk;          ///< empty = unlimited; else > 0 [rad/s³] per joint
  /// Empty = unlimited; else > 0 [N·m] or [N] per joint, on the inverse-dynamics torque
  /// (a robot with inertia only), computed with `gravity`.
  Eigen::VectorXd max_effort;
  Eigen::Vector3d gravity = Eigen::Vector3d(0.0, 0.0, -9.81);  ///< base frame [m/s²], for efforts
  /// Checks sizes (== num_dofs), finiteness and positivity of every limit that is set.
  /// \throws Error(kInvalidArgument), e.g. `max_velocity[2] = -1 must be > 0`,
  ///         `max_acceleration has 6 values, robot has 7 joints`.
  void Validate(int num_dofs) const;
};

/// Times each segment a→b with the exact minimum-time rest-to-rest profile along the line, so
/// the robot stops at every waypoint. With Δ = b − a, V = minᵢ vᵢ/|Δᵢ| and A = minᵢ aᵢ/|Δᵢ|,
/// the duration is 1/V + V/A when V² ≤ A (trapezoid) and 2/√A otherwise (triangle). With
/// max_jerk set (J = minᵢ jᵢ/|Δᵢ|), each segment is the minimum-time jerk-limited profile
/// (up to seven phases of constant jerk ±J or 0, cubic pieces) instead. Every joint stays
/// within its limits at every instant. Zero-length segments (exactly repeated waypoints) are
/// dropped. A path of one waypoint, or of identical ones, gives one zero-duration piece there.
/// max_effort is not considered here (see ParameterizeTimeOptimal).
/// \throws Error(kInvalidArgument) for an empty path, waypoints of different sizes or with
///         non-finite values, or limits that fail Validate(path[0].size()).
TimedTrajectory ParameterizeRestToRest(const JointPath& path, const KinematicLimits& limits);

struct TimeOptimalOptions {
  /// How close the trajectory must pass to every interior waypoint [rad] (Euclidean in joint
  /// space): the corner is cut by a parabolic blend (constant acceleration) that starts and
  /// ends on the adjacent segments and stays in their convex hull. 0 = stop at every corner.
  double max_deviation = 0.05;
  /// Velocity at the start / end [rad/s]; empty = at rest. Non-zero: it must point along the
  /// first segment (start) / the last segment (end) and respect the velocity limits.
  Eigen::VectorXd start_velocity, end_velocity;
  /// With a checker: every blend is checked for collisions — certified along its continuous
  /// motion when checker->certifies_motion() (as VerifyTrajectory does), else at states this
  /// joint step apart [rad]; a blend that collides (or is not certified) is redone with a
  /// quarter of the deviation (down to a stop at the corner).
  double max_joint_step = 0.005;
};

struct TimeOptimalReport {
  int blends = 0;             ///< corners passed without stopping
  int blends_tightened = 0;   ///< blends redone with a smaller deviation after a collision
  /// max_effort bound: backward/forward passes of the torque-limited parameterisation, and its
  /// grid's intervals (both 0 when the velocity/acceleration-optimal trajectory met the torques).
  int effort_passes = 0;
  int effort_grid_intervals = 0;
  std::string message;        ///< summary
};

/// Minimum-time parameterisation of the path with blended corners under per-joint velocity and
/// acceleration limits (and torque limits with max_effort on a robot with inertia).
///
/// Each segment k has path-speed and path-acceleration limits Vₖ = minᵢ vᵢ/|dₖᵢ| and
/// Aₖ = minᵢ aᵢ/|dₖᵢ| (dₖ its unit direction). A corner passed at speed u takes a parabolic
/// blend of duration u·c (c = maxᵢ |Δdᵢ|/aᵢ) that cuts the corner by u²·|Δd|·c/8 ≤
/// max_deviation. Corner speeds are the largest a forward and a backward pass allow; each
/// straight part is bang–coast–bang between them. Reversals (d₂ = −d₁) blend into a smooth
/// turn on the segment itself; duplicate waypoints are dropped. Velocities, accelerations and
/// positions within limits are exact (the pieces are quadratic in time). A straight
/// rest-to-rest path gives exactly the duration 1/V + V/A (or 2/√A).
///
/// max_effort: when the velocity/acceleration-optimal trajectory's torques (friction included,
/// checked every 0.005 rad of joint motion and at piece ends) stay within 0.999 of every limit,
/// it stands. Otherwise the same geometric path — its straight parts and blends — is timed again
/// with the torque in the parameterisation: reachability analysis over a grid of 0.0025 rad of
/// path (torque τ = M q′ s̈ + (M q″ + C q′) ṡ² + g linear in (s̈, ṡ²), Coulomb friction exact
/// where a joint keeps its direction, viscous damping by a linear bound that never understates
/// it, limits at both ends of every grid interval with a margin for the curvature between them,
/// and checked at every interval's ends and midpoint). The result has one quadratic (straight)
/// or quartic (blend) piece per grid interval and rides the binding limit; its duration is
/// 0.2–0.4 % (median) over an independent reference solver on random Panda paths
/// (tests/optimizers/effort_reference.h; `chasles-bench --section effort`).
/// max_jerk must be empty: this profile's acceleration steps have unbounded jerk.
///
/// \throws Error(kInvalidArgument) for an invalid path or limits (as ParameterizeRestToRest),
///   max_jerk set, max_deviation or max_joint_step not finite and >= 0 / > 0, a start/end
///   velocity of the wrong size, not along its segment, over a limit, too fast to stop within
///   the path, or non-zero on a path with no motion; max_effort on a robot without inertia.
/// \throws Error(kFailedPrecondition) when max_effort cannot be met: the robot cannot hold a
///   configuration of the path against gravity, or no speed profile along the path joins the
///   boundary speeds within the limits.
TimedTrajectory ParameterizeTimeOptimal(const JointPath& path, const KinematicLimits& limits,
                                        const TimeOptimalOptions& options = {},
                                        const CollisionChecker* checker = nullptr,
                                        TimeOptimalReport* report = nullptr);

}  // namespace chasles
