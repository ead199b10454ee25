#pragma once
/// \file
/// Exact minimum-time rest-to-rest parameterisation along each straight segment of a path.

#include <Eigen/Core>

#include "chasles/optimizers/timed_trajectory.h"

namespace chasles {

/// Per-joint limits the trajectory must respect.
struct KinematicLimits {
  Eigen::VectorXd max_velocity;      ///< > 0 [rad/s] per joint
  Eigen::VectorXd max_acceleration;  ///< > 0 [rad/s²] per joint
  /// Checks sizes (== num_dofs), finiteness and positivity.
  /// \throws Error(kInvalidArgument), e.g. `max_velocity[2] = -1 must be > 0`,
  ///         `max_acceleration has 6 values, robot has 7 joints`.
  void Validate(int num_dofs) const;
};

/// Times each segment a→b with the exact minimum-time rest-to-rest profile along the line:
/// with Δ = b − a, V = minᵢ vᵢ/|Δᵢ| and A = minᵢ aᵢ/|Δᵢ|, the duration is 1/V + V/A when
/// V² ≤ A (trapezoid) and 2/√A otherwise (triangle). Every joint then stays within its
/// velocity and acceleration limits at every instant. Zero-length segments (exactly repeated
/// waypoints) are dropped; segment k+1 starts where segment k ends (t0 and waypoint exact).
/// A path of one waypoint, or of identical ones, gives one zero-duration segment a = b = that
/// waypoint (so Sample() returns a single sample there), never an empty trajectory.
/// \throws Error(kInvalidArgument) for an empty path, waypoints of different sizes or with
///         non-finite values, or limits that fail Validate(path[0].size()).
TimedTrajectory ParameterizeRestToRest(const JointPath& path, const KinematicLimits& limits);

}  // namespace chasles
