#pragma once
/// \file
/// Multi-robot coordination: conflict-free timed trajectories for several robots sharing a
/// workspace, by prioritized space-time planning, composite configuration-space planning,
/// decoupled paths with velocity tuning, or one robot after another; jointly verified.

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "chasles/collision/scene.h"
#include "chasles/multi/fleet_lattice.h"
#include "chasles/multi/team.h"
#include "chasles/multi/velocity_obstacles.h"
#include "chasles/pipeline/plan_pipeline.h"
#include "chasles/planners/registry.h"
#include "chasles/planners/termination.h"

namespace chasles {

/// kVelocityObstacles: one planar base steered among moving discs (velocity_obstacles.h); never
/// part of kAuto.
enum class CoordinationMethod { kAuto, kPrioritized, kComposite, kVelocityTuning, kSequential, kFleet, kVelocityObstacles };
/// "auto", "prioritized", "composite", "velocity_tuning", "sequential", "fleet", "velocity_obstacles".
const char* ToString(CoordinationMethod method);

/// One robot of a team.
struct TeamRobotSpec {
  PlacedRobot placement;                  ///< name, model, base pose (frozen_at unused)
  Eigen::VectorXd start;
  Eigen::VectorXd goal;                   ///< joint goal; ignored when pose_goal is set
  std::optional<PoseGoalSpec> pose_goal;  ///< in the robot's base frame; first collision-free IK solution
  int priority = 0;                       ///< larger plans first; ties keep the given order
  Eigen::VectorXd max_velocity;           ///< empty = the model's; else > 0, capped at the model's
  Eigen::VectorXd max_acceleration;       ///< empty = 2 × the velocity limits
};

/// A trajectory committed in a workcell, as a moving obstacle: the robot is at
/// trajectory(t − begin) for t in [begin, begin + duration], at its end until `until`, and absent
/// outside [begin, until]. Times are on the query's time line (t = 0 = the team's start).
struct CommittedMotion {
  std::string id;                  ///< reservation id, for messages
  PlacedRobot placement;           ///< its robot (frozen_at unused)
  TimedTrajectory trajectory;
  double begin = 0.0;              ///< [s]
  double until = 0.0;              ///< [s] >= begin + duration
};

struct CoordinationQuery {
  std::shared_ptr<const Scene> scene;
  std::vector<TeamRobotSpec> robots;   ///< 1 to max_robots
  int max_robots = 1000;               ///< the server's cap (--max-team-robots)
  CoordinationMethod method = CoordinationMethod::kAuto;
  std::string planner_id = "rrt_connect";
  ParameterValues parameters;
  double time_budget = 30.0;           ///< [s] (the termination given to Coordinate also applies)
  std::uint64_t seed = 1;
  double collision_resolution = 0.005; ///< [rad]
  double time_step = 1e-3;             ///< [s] joint verification
  double sample_period = 0.01;         ///< [s]
  /// true: no samples for trajectories with a knots form (degree <= 2; the caller returns knots)
  bool knots_replace_samples = false;
  SampleCap sample_cap{1000000, 64ull << 20, "sample_period"};  ///< per robot; checked before sampling
  double robot_padding = 0.0;          ///< [m] kept between robots
  int max_reorderings = 0;             ///< 0 = 2 × robots
  std::vector<CommittedMotion> committed;  ///< workcell reservations and moving obstacles to avoid
  /// VELOCITY_OBSTACLES: the committed motions as discs in the plane, to steer by (the result is
  /// verified against `committed` itself).
  std::vector<MovingDisc> moving_discs;
  /// FLEET: lattice spacing [m]; 0 = FleetResolution of the footprints and robot_padding.
  double fleet_resolution = 0.0;
  /// FLEET: the scene's content id and a cache of lattices under it (both optional: without
  /// them every request builds its lattice).
  std::string scene_id;
  FleetLatticeCache* lattice_cache = nullptr;

  /// \throws Error(kInvalidArgument) naming the field (proto names: `robots[1].name`,
  ///         `robots[0].start.positions has 6 values, robot 'left' has 7 joints`, …), duplicate
  ///         names, sizes, non-finite values, limits; Error(kNotFound) for an unknown planner.
  void Validate(const PlannerRegistry& registry) const;
};

enum class CoordinationCode {
  kSuccess,
  kNoSolution,         ///< no method succeeded within the budget (attempts say why)
  kStartInCollision,   ///< one robot's start against the scene or itself
  kGoalInCollision,
  kGoalUnreachable,    ///< pose goal without a collision-free IK solution
  kStartsInConflict,   ///< two robots' starts (or a start and a committed motion) collide
  kGoalsInConflict,    ///< two robots' goals collide (or a goal and a committed motion's hold)
  kVerificationFailed, ///< the joint verification failed (nothing is returned)
  kCancelled,
  kDeadlineExceeded,
};
const char* ToString(CoordinationCode code);

struct MethodAttemptReport {
  CoordinationMethod method = CoordinationMethod::kAuto;
  bool succeeded = false;
  std::string message;
  double seconds = 0.0;
  double makespan = 0.0;
};

/// FLEET: robot `robot` leaves path[leave_index] only once robot `waits_for` has reached its
/// path[arrival_index] (RobotPlan::path: the lattice nodes it moves through).
struct FleetWait {
  int robot = 0;
  int leave_index = 0;
  int waits_for = 0;
  int arrival_index = 0;
  double x = 0.0, y = 0.0;  ///< [m] the node `robot` enters
};

/// FLEET: the lattice and the discrete plan behind the trajectories.
struct FleetSummary {
  double resolution = 0.0;  ///< [m]
  int width = 0, height = 0, free_nodes = 0;
  int makespan_steps = 0;
  std::int64_t sum_of_costs = 0, sum_of_lower_bounds = 0;
  double lattice_seconds = 0.0, search_seconds = 0.0, schedule_seconds = 0.0;
  bool lattice_cached = false;
  std::vector<FleetWait> dependencies;
};

struct RobotPlan {
  std::string name;
  TimedTrajectory trajectory;  ///< from t = 0 to `duration` (waits included)
  std::vector<TrajectorySample> samples;
  double duration = 0.0;       ///< [s] until it stands at its goal for good
  double start_delay = 0.0;
  double wait_time = 0.0;
  JointPath path;
  Eigen::VectorXd goal;
  KinematicLimits limits;
};

struct CoordinationOutcome {
  CoordinationCode code = CoordinationCode::kNoSolution;
  std::string message;
  std::vector<RobotPlan> robots;   ///< request order (kSuccess)
  double makespan = 0.0;
  double sum_of_durations = 0.0;
  CoordinationMethod method = CoordinationMethod::kAuto;  ///< whose result is returned
  std::vector<MethodAttemptReport> attempts;
  std::vector<std::string> order;  ///< priority order used
  int reorderings = 0;
  TeamVerificationReport verification;
  double seconds = 0.0;
  std::optional<FleetSummary> fleet;  ///< set when FLEET's result is returned
};

/// The first time two motions collide (robot against robot, `padding` [m] around both robots),
/// or "" when they never do: states at times no more than time_step [s] and max_joint_step [rad]
/// (of either robot) apart over the overlap of [begin, until] of the two. The message names the
/// motions' ids, their links and the time. Names of the two placements must differ.
std::string FindMotionConflict(const CommittedMotion& a, const CommittedMotion& b, double padding,
                               double time_step = 1e-3, double max_joint_step = 0.005);

/// The rule for names clients give robots of a team, workcells and fleet sessions: 1 to 64
/// characters of [A-Za-z0-9_.-]. \throws Error(kInvalidArgument) "`field` = 'name' must be 1 to
/// 64 characters of [A-Za-z0-9_.-]".
void CheckName(const std::string& field, const std::string& name);

/// Runs the query: validation, starts/goals (scene, self, pairwise: the named conflict
/// outcomes), the method(s), then VerifyTeam of the result (nothing unverified is returned).
/// \throws Error for invalid input (Validate).
CoordinationOutcome Coordinate(const CoordinationQuery& query, const PlannerRegistry& registry,
                               const Termination& termination);

}  // namespace chasles
