#pragma once
/// \file
/// Dense verification of a timed trajectory before it leaves the server.

#include <string>

#include "chasles/collision/collision_checker.h"
#include "chasles/optimizers/time_parameterization.h"
#include "chasles/optimizers/timed_trajectory.h"

namespace chasles {

struct VerificationOptions {
  double max_joint_step = 0.005;   ///< resample so no joint moves more than this between checks [rad]
  double endpoint_tolerance = 1e-6;  ///< |q(0) − start|∞ and |q(T) − goal|∞ bound [rad]
  double limit_tolerance = 1e-9;   ///< relative slack on velocity/acceleration limits
};

struct VerificationReport {
  bool ok = false;
  std::string reason;              ///< empty when ok, else what failed and where (time, joint)
  int states_checked = 0;
  double max_velocity_ratio = 0.0;     ///< max over samples and joints of |q̇ᵢ|/vᵢ
  double max_acceleration_ratio = 0.0; ///< max over samples and joints of |q̈ᵢ|/aᵢ
};

/// Resamples `trajectory` so that consecutive states differ by at most max_joint_step in every
/// joint, and checks each state for collisions (self + scene) and position limits, the
/// velocities/accelerations against `limits` (evaluated on the exact profile at every sample
/// and at every phase boundary), and the endpoints against start and goal.
///
/// In order: every segment's structure (sizes, finite non-negative profile numbers, a profile
/// that covers s ∈ [0, 1] to 1e-9, t0 continuous to 1e-9 s, each segment starting within
/// endpoint_tolerance of where the previous one ends); q(0) vs start and q(T) vs goal; then
/// segment by segment in time order: q̇ and q̈ at both ends of every phase (both one-sided
/// values at each boundary), and m + 1 states at s = k/m with m = ⌈maxᵢ|Δᵢ| / max_joint_step⌉,
/// each evaluated at its exact time on the profile: position limits, q̇/q̈ limits, then
/// checker.IsValid (a contact is named with checker.Check). Stops at the first failure.
/// `reason` says what failed and where, e.g.
/// `collision at t = 1.234 s between link 'panda_link5' and 'shelf_top'`,
/// `self-collision at t = 0.5 s between link 'link1' and link 'link4'`,
/// `joint 3 'panda_joint4' velocity 2.1 rad/s exceeds limit 2 rad/s at t = 0.5 s`,
/// `joint 0 'joint1' position 3.2 is outside its limits [-3.14159, 3.14159] at t = 1 s`,
/// `trajectory ends 0.001 rad from the goal configuration (tolerance 1e-06 rad) at t = 4.8 s`,
/// `trajectory is empty`. Joints are numbered from 0 in configuration order.
/// \throws Error(kInvalidArgument) for options that are not finite with max_joint_step > 0 and
///         tolerances >= 0, limits that fail Validate(robot().num_dofs()), or start/goal sizes.
VerificationReport VerifyTrajectory(const TimedTrajectory& trajectory, const Eigen::VectorXd& start,
                                    const Eigen::VectorXd& goal, const CollisionChecker& checker,
                                    const KinematicLimits& limits,
                                    const VerificationOptions& options = {});

}  // namespace chasles
