#pragma once
/// \file
/// Dense verification of a timed trajectory before it leaves the server, and the quality
/// figures a response reports.

#include <string>

#include "chasles/collision/collision_checker.h"
#include "chasles/optimizers/time_parameterization.h"
#include "chasles/optimizers/timed_trajectory.h"

namespace chasles {

struct VerificationOptions {
  double max_joint_step = 0.005;   ///< resample so no joint moves more than this between checks [rad]
  /// Also resample so consecutive checked states are no more than this apart in time [s]; 0 = no
  /// time bound (a robot standing still is then checked once per piece). Multi-robot
  /// verification sets it, since other robots move while one stands.
  double max_time_step = 0.0;
  double endpoint_tolerance = 1e-6;  ///< |q(0) − start|∞, |q(T) − goal|∞ and piece-to-piece jumps [rad]
  double limit_tolerance = 1e-9;   ///< relative slack on velocity/acceleration/jerk/effort limits
  /// Expected velocity at the start / end [rad/s]; empty = at rest. Checked to
  /// 1e-6·max(1, v_max) per joint, as is velocity continuity between pieces.
  Eigen::VectorXd start_velocity, end_velocity;
};

struct VerificationReport {
  bool ok = false;
  std::string reason;              ///< empty when ok, else what failed and where (time, joint)
  int states_checked = 0;
  double max_velocity_ratio = 0.0;     ///< max over the trajectory and joints of |q̇ᵢ|/vᵢ (exact)
  double max_acceleration_ratio = 0.0; ///< max of |q̈ᵢ|/aᵢ (exact)
  double max_jerk_ratio = 0.0;         ///< max of |q⃛ᵢ|/jᵢ (exact); 0 without jerk limits
  double max_effort_ratio = 0.0;       ///< max of |τᵢ|/τmaxᵢ at the checked states; 0 without effort limits
};

/// Checks, in order, stopping at the first failure:
/// 1. structure: every piece has num_dofs rows, finite coefficients, a finite duration >= 0,
///    starts when the previous one ends (1e-9 s relative), and continues its position (within
///    endpoint_tolerance) and velocity; with max_jerk set also its acceleration, and the
///    acceleration is zero at an end at rest (a step there would be an infinite jerk);
/// 2. q(0) vs start, q(T) vs goal, q̇(0) and q̇(T) vs the expected velocities;
/// 3. piece by piece in time order, exactly at the extrema of each polynomial: position limits
///    (to 1e-12 relative), velocity, acceleration and (when limited) jerk limits;
/// 4. states spaced so no joint moves more than max_joint_step between consecutive ones
///    (m = ⌈maxᵢ max|q̇ᵢ|·duration / step⌉ per piece, or ⌈duration / max_time_step⌉ if more): collisions (self + scene) and, with
///    max_effort on a robot with inertia, the inverse-dynamics torques.
/// `reason` says what failed and where, e.g.
/// `collision at t = 1.234 s between link 'panda_link5' and 'shelf_top'`,
/// `self-collision at t = 0.5 s between link 'link1' and link 'link4'`,
/// `joint 3 'panda_joint4' velocity 2.1 rad/s exceeds limit 2 rad/s at t = 0.5 s`,
/// `joint 0 'joint1' position 3.2 is outside its limits [-3.14159, 3.14159] at t = 1 s`,
/// `trajectory ends 0.001 rad from the goal configuration (tolerance 1e-06 rad) at t = 4.8 s`,
/// `trajectory is empty`. Joints are numbered from 0 in configuration order.
/// \throws Error(kInvalidArgument) for options that are not finite with max_joint_step > 0 and
///         tolerances >= 0, limits that fail Validate(robot().num_dofs()), start/goal or
///         expected velocity sizes, or max_effort on a robot without inertia.
VerificationReport VerifyTrajectory(const TimedTrajectory& trajectory, const Eigen::VectorXd& start,
                                    const Eigen::VectorXd& goal, const CollisionChecker& checker,
                                    const KinematicLimits& limits,
                                    const VerificationOptions& options = {});

/// Quality figures of a trajectory (what a response reports besides the verification).
struct TrajectoryQuality {
  double duration = 0.0;                ///< [s]
  double max_velocity_ratio = 0.0;      ///< max |q̇ᵢ|/vᵢ (exact)
  double max_acceleration_ratio = 0.0;  ///< max |q̈ᵢ|/aᵢ (exact)
  double max_jerk_ratio = 0.0;          ///< max |q⃛ᵢ|/jᵢ (exact, inside pieces); 0 without jerk limits
  double max_jerk = 0.0;                ///< max |q⃛ᵢ| inside pieces [rad/s³] (steps between pieces not counted)
  double max_effort_ratio = 0.0;        ///< max |τᵢ|/τmaxᵢ at the sampled states; 0 without effort limits
  /// Largest distance [rad] (Euclidean in joint space) between the trajectory and the input
  /// path, both ways: from sampled states to the nearest point of the path's polyline, and from
  /// each waypoint to the nearest sampled state.
  double max_deviation = 0.0;
  /// Smallest distance between the robot and the scene's obstacles at the sampled states [m];
  /// +inf when the scene has none (self-distance not included).
  double min_clearance = 0.0;
  double jerk_integral = 0.0;           ///< ∫‖q⃛‖² dt over the pieces (exact) [rad²/s⁵]
};

/// Measures `trajectory` against the limits and the input `path` (may be empty: deviation 0),
/// sampling states every `max_joint_step` of joint motion (at most 2000 states in all) for the
/// sampled figures. `checker` may be null (clearance and effort then 0).
TrajectoryQuality MeasureTrajectory(const TimedTrajectory& trajectory, const KinematicLimits& limits,
                                    const JointPath& path, const CollisionChecker* checker,
                                    double max_joint_step = 0.01);

}  // namespace chasles
