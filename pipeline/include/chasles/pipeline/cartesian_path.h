#pragma once
/// \file
/// Cartesian moves: a link driven along straight lines in task space (MoveIt's
/// computeCartesianPath). The poses between the link's start pose and each waypoint are
/// interpolated (position linearly, orientation along the geodesic of SO(3)); each is solved by
/// inverse kinematics from the previous state only, so the path stays on one branch; a step that
/// jumps, leaves the limits or collides ends the path there, and the fraction achieved says how
/// far it got. The path is then timed like any other (the server's CartesianPath RPC).

#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "chasles/collision/collision_checker.h"
#include "chasles/optimizers/timed_trajectory.h"
#include "chasles/robot/joint_path.h"

namespace chasles {

/// What a Cartesian move asks. Units: metres and radians; poses in the robot's base frame.
struct CartesianSpec {
  int link = -1;                                ///< the link whose frame moves along the lines
  std::vector<Eigen::Isometry3d> waypoints;     ///< >= 1, in order, from the start's link pose
  double max_step = 0.01;                       ///< [m] link translation per state, in [1e-4, 0.5]
  double max_rotation_step = 0.05;              ///< [rad] link rotation per state, in [1e-3, 1]
  /// [rad] largest change of any joint between consecutive states, in (0, 2π]: a larger one
  /// (a branch flip, a pass near a singularity) ends the path.
  double max_joint_jump = 0.2;
  /// MoveIt's relative test: the path ends before the first step whose joint distance (Euclidean)
  /// exceeds this times the mean step; 0 = off; else >= 1.
  double jump_threshold = 0.0;
  /// [m] how far the link may stray from the line between consecutive states (the joints move
  /// linearly between them), measured at 7 points of a step: a step that strays more is split at
  /// its middle pose, up to 8 times; in [1e-5, 0.1].
  double line_tolerance = 5e-4;
  double position_tolerance = 1e-4;             ///< [m] per state, in (0, 0.01]
  double orientation_tolerance = 1e-3;          ///< [rad] per state, in (0, 0.1]
  bool check_collisions = true;                 ///< false: MoveIt's avoid_collisions = false
  double collision_resolution = 0.005;          ///< [rad] steps of the discrete fallback check

  /// \throws Error(kInvalidArgument) naming the field (proto field names), e.g.
  ///         `max_step = 0 must be within [0.0001, 0.5]`, `waypoints[2].position.x = nan must be finite`.
  void Validate(const RobotModel& robot) const;
};

/// Why a Cartesian path ended.
enum class CartesianStop {
  kComplete,         ///< every waypoint reached
  kStartInvalid,     ///< the start collides (fraction 0)
  kUnreachable,      ///< no inverse-kinematics solution near the previous state
  kJointJump,        ///< a step moved a joint more than max_joint_jump
  kRelativeJump,     ///< a step exceeded jump_threshold × the mean step
  kCollision,        ///< a step's motion collides
  kCancelled,        ///< the caller's stop said so
};
const char* ToString(CartesianStop stop);  ///< "COMPLETE", "START_INVALID", …

struct CartesianPathResult {
  JointPath path;            ///< start first; consecutive states one step (or part of one) apart
  CartesianStop stop = CartesianStop::kComplete;
  std::string message;       ///< where and why the path ended (empty when complete)
  double fraction = 0.0;     ///< steps achieved / steps of the whole move, in [0, 1]
  int steps = 0;             ///< interpolation steps of the whole move
  int waypoints_reached = 0; ///< waypoints whose last step was achieved
  /// The poses of the states against their targets (each within the tolerances).
  double max_position_error = 0.0;     ///< [m]
  double max_orientation_error = 0.0;  ///< [rad]
  /// Between consecutive states the joints move linearly: the link's distance from the
  /// commanded line, measured at 7 points of every step (not a bound; at most line_tolerance
  /// unless a step was split 8 times).
  double max_line_deviation = 0.0;           ///< [m]
  double max_line_rotation_deviation = 0.0;  ///< [rad]
};

/// Drives `spec.link` from its pose at `start` through `spec.waypoints` in straight lines.
/// Every state is within the joint limits and the IK tolerances; every step's motion is
/// certified collision-free (IsMotionCertified; the discrete check at collision_resolution where
/// the checker cannot certify) unless check_collisions is off. `stop` is polled every step.
/// \throws Error(kInvalidArgument) for an invalid spec or start (named).
CartesianPathResult ComputeCartesianPath(const CollisionChecker& checker, const Eigen::VectorXd& start,
                                         const CartesianSpec& spec, const std::function<bool()>& stop = {});

/// [m] The largest distance of spec.link from the commanded lines (the start's link pose through
/// every waypoint) over `trajectory`, at states 1 ms apart (at most 100000) and its end.
double TrajectoryLineDeviation(const RobotModel& robot, const CartesianSpec& spec, const Eigen::VectorXd& start,
                               const TimedTrajectory& trajectory);

/// The link pose at fraction u ∈ [0, 1] from a to b: position linearly, orientation along the
/// shortest rotation (a.R · Exp(u · Log(a.Rᵀ b.R))).
Eigen::Isometry3d InterpolatePose(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b, double u);

}  // namespace chasles
