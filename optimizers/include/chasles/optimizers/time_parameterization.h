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
  /// \throws Error(kInvalidArgument), e.g. `max_velocity[2] = -1 must be > 0`.
  void Validate(int num_dofs) const;
};

/// Times each segment a→b with the exact minimum-time rest-to-rest profile along the line:
/// with Δ = b − a, V = minᵢ vᵢ/|Δᵢ| and A = minᵢ aᵢ/|Δᵢ|, the duration is 1/V + V/A when
/// V² ≤ A (trapezoid) and 2/√A otherwise (triangle). Every joint then stays within its
/// velocity and acceleration limits at every instant. Zero-length segments are dropped.
/// Precondition: path.size() >= 1; limits validated.
TimedTrajectory ParameterizeRestToRest(const JointPath& path, const KinematicLimits& limits);

}  // namespace chasles
