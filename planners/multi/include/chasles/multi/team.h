#pragma once
/// \file
/// Several robots in one world: a composite RobotModel (so one CollisionChecker checks robot
/// against robot, scene and itself), their trajectories side by side on one time line, and the
/// joint verification of a coordinated set.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "chasles/collision/collision_checker.h"
#include "chasles/optimizers/time_parameterization.h"
#include "chasles/optimizers/timed_trajectory.h"
#include "chasles/robot/robot_model.h"

namespace chasles {

/// One robot placed in the world.
struct PlacedRobot {
  std::string name;                          ///< link/joint prefix: "<name>/<link>"; non-empty, unique
  std::shared_ptr<const RobotModel> model;
  Eigen::Isometry3d base_pose = Eigen::Isometry3d::Identity();  ///< its root link frame in the world
  /// Non-empty: the robot stands at this configuration for good; its joints become fixed joints,
  /// so it is an obstacle of the composite with no configuration entries.
  Eigen::VectorXd frozen_at;
};

struct CompositionOptions {
  /// Check each robot's links against its own other links (its ACM applies). Off: only pairs of
  /// links of different robots are checked (the pair checkers of moving obstacles, where each
  /// robot's own self-collision is checked separately).
  bool self_collisions = true;
};

/// A model whose configuration is the movable robots' configurations concatenated in order.
/// Links: a geometry-free root "world", then each robot's links renamed "<name>/<link>"; joints
/// renamed "<name>/<joint>", each robot's root fixed to "world" at its base pose by the fixed
/// joint "<name>/base" ("<name>/base_2", … if the robot has a joint "base" of its own); a frozen
/// robot's moving joints become fixed joints at frozen_at (origin · motion(axis, q)). The
/// configuration is the movable robots' own configurations concatenated in list order; joint
/// limits, geometry and inertia are the robots' own. The model is named "team". Allowed collisions: every pair within one robot that its
/// own ACM allows (or every pair within one robot when !self_collisions); pairs of links of
/// different robots are always checked. Motion model: the movable robot's when there is exactly
/// one; kArm when several movable robots are all arms, planar bodies or free flyers.
/// \throws Error(kInvalidArgument) for an empty list, empty or duplicate names, a null model,
///         a non-finite base pose or one whose rotation is not a rotation matrix (to 1e-6),
///         a frozen configuration of the wrong size or outside limits (messages name
///         `robots[k] '<name>'`);
///         Error(kFailedPrecondition) when several movable robots include a car.
std::shared_ptr<const RobotModel> ComposeRobots(const std::vector<PlacedRobot>& robots,
                                                const CompositionOptions& options = {});

/// Offset of each robot's first configuration entry in the composite, one per robot in list
/// order (a frozen robot has no entries: its offset is the next robot's), then the total:
/// robots.size() + 1 values. \throws Error(kInvalidArgument) for a null model.
std::vector<int> CompositeOffsets(const std::vector<PlacedRobot>& robots);

/// The robots' trajectories on one time line, all from t = 0: the piece boundaries are the union
/// of every trajectory's (boundaries within 1e-12·max(1 s, T) of each other are one); on each
/// piece every robot's polynomial is re-expanded about the piece's start and padded to the
/// highest degree. A trajectory that has ended holds its end position (its Evaluate at its
/// duration) at rest. Rows in order; the end position is every robot's end position.
/// \throws Error(kInvalidArgument) for an empty list or an empty trajectory.
TimedTrajectory ComposeTrajectories(const std::vector<TimedTrajectory>& trajectories);

/// Per-robot limits concatenated in order (max_velocity, max_acceleration; jerk and effort are
/// not supported by coordination and must be empty). Gravity is the first robot's.
/// \throws Error(kInvalidArgument) for an empty list, jerk or effort limits, or
///         max_acceleration and max_velocity of different sizes (naming `limits[k]`).
KinematicLimits ComposeLimits(const std::vector<KinematicLimits>& limits);

/// The largest robot-to-robot distance VerifyTeam reports [m].
constexpr double kMaxReportedRobotDistance = 10.0;

struct TeamVerificationOptions {
  double time_step = 1e-3;       ///< [s] largest time step between checked team states
  double max_joint_step = 0.005; ///< [rad] largest joint step of any robot between checked states
  /// min_robot_distance is measured at instants this far apart [s] (more apart when the motion
  /// is long: at most max_distance_instants instants), and at the end.
  double distance_period = 0.01;
  int max_distance_instants = 2000;
  bool measure_robot_distance = true;  ///< false: min_robot_distance is left 0 (a second pass)
};

struct TeamVerificationReport {
  bool ok = false;
  std::string reason;  ///< empty when ok; names robots ("<name>/<link>"), time and joint
  std::uint64_t states_checked = 0;
  double max_velocity_ratio = 0.0;
  double max_acceleration_ratio = 0.0;
  /// Smallest distance [m] between the collision shapes of two different robots (frozen ones
  /// included) at the distance instants (TeamVerificationOptions), capped at
  /// kMaxReportedRobotDistance; the cap when the team has one robot. Measured only when ok.
  double min_robot_distance = 0.0;
  /// As VerificationReport: "certified" (the team's continuous motion) or "discrete", and why.
  std::string collision_guarantee;
  std::string collision_guarantee_reason;
};

/// Verifies a coordinated set: each robot's limits exactly, starts and goals, and the team's
/// motion against the scene, each robot itself and every other robot (VerifyTrajectory of the
/// composed trajectory): certified along the continuous motion when team_checker certifies
/// motions, else every team state at most time_step and max_joint_step apart. `team_checker` is the composite of the same robots (self_collisions on)
/// over the scene; trajectories, starts, goals and limits are per robot in its order. An empty
/// trajectory is a failed report. A contact between two robots is reported as a
/// self-collision of the composite, naming both links ("left/link2", "right/link1").
/// \throws Error(kInvalidArgument) for option values that are not finite and > 0, lists of
///         different lengths, per-robot sizes that differ from the trajectory's joints, or
///         joints in all that differ from the team checker's robot.
TeamVerificationReport VerifyTeam(const CollisionChecker& team_checker,
                                  const std::vector<TimedTrajectory>& trajectories,
                                  const std::vector<Eigen::VectorXd>& starts,
                                  const std::vector<Eigen::VectorXd>& goals,
                                  const std::vector<KinematicLimits>& limits,
                                  const TeamVerificationOptions& options = {});

}  // namespace chasles
