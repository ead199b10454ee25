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
VerificationReport VerifyTrajectory(const TimedTrajectory& trajectory, const Eigen::VectorXd& start,
                                    const Eigen::VectorXd& goal, const CollisionChecker& checker,
                                    const KinematicLimits& limits,
                                    const VerificationOptions& options = {});

}  // namespace chasles
