#pragma once
/// \file
/// The planning pipeline: validate → plan → shortcut → time-parameterise → verify.
/// The same code serves the gRPC server, the benchmarks and the tests.

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "chasles/collision/collision_checker.h"
#include "chasles/optimizers/time_parameterization.h"
#include "chasles/optimizers/timed_trajectory.h"
#include "chasles/optimizers/verification.h"
#include "chasles/pipeline/trajectory_stage.h"
#include "chasles/planners/planner.h"
#include "chasles/planners/registry.h"
#include "chasles/planners/termination.h"

namespace chasles {

/// A pose goal, solved by inverse kinematics into collision-free goal states before planning.
struct PoseGoalSpec {
  int link = -1;                        ///< link index in the robot
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();  ///< target in the base frame
  double position_tolerance = 1e-4;     ///< [m], in (0, 0.1]
  double orientation_tolerance = 1e-3;  ///< [rad], in (0, 0.5]
  int max_goal_states = 4;              ///< in [1, 64]
  double ik_time_budget = 0.2;          ///< [s], > 0
};

struct IkRequest;  // chasles/robot/inverse_kinematics.h

/// Sets `ik`'s link, target, tolerances and max_solutions (max_goal_states) from `goal`, and its
/// time budget: goal.ik_time_budget, no more than `seconds_left` of the call, at least 1 ms.
/// Seed, initial guess and the accept/stop callbacks are the caller's.
void SetPoseGoalIk(const PoseGoalSpec& goal, double seconds_left, IkRequest* ik);

/// One planning query in domain types. Defaults match the proto documentation.
struct PlanQuery {
  /// robot + scene; with path constraints (CollisionChecker::WithPathConstraints) every stage
  /// keeps them: the planners plan on them, shortcuts and timing are checked, and verification
  /// certifies them along the trajectory.
  std::shared_ptr<const CollisionChecker> checker;
  Eigen::VectorXd start;
  Eigen::VectorXd goal;                ///< joint goal; ignored when pose_goal is set
  std::optional<PoseGoalSpec> pose_goal;  ///< set: the goal is a link pose (IK before planning)
  double goal_tolerance = 1e-3;       ///< [rad], in [0, 0.1]
  Eigen::Vector3d gravity = Eigen::Vector3d(0.0, 0.0, -9.81);  ///< for the returned torques [m/s²]
  std::string planner_id = "rrt_connect";
  ParameterValues parameters;         ///< unresolved; validated against the planner's spec
  std::uint64_t seed = 1;
  double collision_resolution = 0.005;  ///< [rad], in [1e-4, 0.1]
  TrajectorySpec trajectory;          ///< limits and post-processing (gravity: set from `gravity`)
  double sample_period = 0.01;        ///< [s], in [1e-4, 1]
  /// true: no samples when the trajectory has a knots form (degree <= 2; the caller returns
  /// knots instead); a trajectory of higher degree is still sampled.
  bool knots_replace_samples = false;
  SampleCap sample_cap;               ///< checked before sampling (server flags set it)
  int shortcut_attempts = 100;        ///< -1 = off; never applied to a car's path (its shape is kept)
  /// Shortcutting stops after this many consecutive attempts that each shorten the path by less
  /// than 1% (ShortcutOptions::stall_attempts), and while it is on, candidates that would
  /// shorten the path by less than 0.5% are not checked (ShortcutOptions::min_gain); 0 = every
  /// attempt runs and is checked. The server sets 0 when the request names its shortcut_attempts.
  int shortcut_stall = 10;
  /// When the trajectory fails dense verification: the replanning repair's own budget [s],
  /// counted from when it starts (the planning budget may be spent), cut by the deadline.
  double repair_budget = 0.5;

  /// \throws Error(kInvalidArgument/kNotFound) naming the field (proto field names), e.g.
  /// `start.positions[2] = nan must be finite`, `goal.tolerance = 0.5 must be within [0, 0.1]`.
  void Validate(const PlannerRegistry& registry) const;
};

/// Expected outcomes of a query (contract violations throw Error instead).
enum class PlanOutcomeCode {
  kSuccess,
  kNoPathWithinBudget,
  kStartInCollision,
  kGoalInCollision,
  kGoalUnreachable,   ///< pose goal: no collision-free IK solution within its budget
  kVerificationFailed,
  kApproximateOnly,
  kCancelled,
  kDeadlineExceeded,
  kLocalMinimum,      ///< a descent planner (potential field) stopped in a local minimum
  kInfeasibleLimits,  ///< the trajectory limits cannot be met (max_effort below what gravity needs)
  kStartViolatesConstraints,  ///< the start breaks a path constraint of the checker
  kGoalViolatesConstraints,   ///< the joint goal breaks a path constraint of the checker
  kNoPathOnLattice,  ///< a search planner exhausted its lattice: no path at this resolution
};
const char* ToString(PlanOutcomeCode code);

struct StageSeconds {
  double validate = 0, plan = 0, shortcut = 0, parameterize = 0, optimize = 0, verify = 0, total = 0;
  double quality = 0;  ///< the trajectory's quality figures (MeasureTrajectory: min_clearance bound, deviation)
  double sample = 0;   ///< samples at sample_period, with torques
  double repair = 0;   ///< repairs of a trajectory that failed verification (retiming, replanning, re-timing)
};

struct PlanOutcome {
  PlanOutcomeCode code = PlanOutcomeCode::kNoPathWithinBudget;
  std::string message;
  JointPath raw_path;                  ///< as the planner returned it
  JointPath path;                      ///< after shortcutting (start … goal, exact)
  TimedTrajectory trajectory;          ///< empty unless kSuccess
  std::vector<TrajectorySample> samples;  ///< at sample_period, last one at the end exactly;
                                          ///< `effort` filled when the robot has inertia
  Eigen::VectorXd goal;                ///< the goal the trajectory ends at (a pose goal's IK solution)
  double goal_manipulability = 0.0;    ///< pose goal: √det(J Jᵀ) of the link at `goal`
  KinematicLimits limits;              ///< the limits the trajectory respects
  VerificationReport verification;
  TrajectoryQuality quality;           ///< of the returned trajectory (kSuccess)
  OptimizerSummary optimizer;          ///< what the post-processing did
  /// When the first trajectory failed dense verification: what failed and each repair tried
  /// (retiming without blends; replanning the segments that collide at a finer check).
  VerificationRepair repair;
  StageSeconds seconds;
  std::uint64_t graph_states = 0;
  std::uint64_t state_checks = 0;      ///< all stages
  double suboptimality_bound = 0.0;    ///< the planner's proven cost bound (weighted A*: ε); 0 = none
};

class PlanningPipeline {
 public:
  explicit PlanningPipeline(const PlannerRegistry& registry) : registry_(registry) {}
  /// Runs the query. \throws Error for invalid input (after query.Validate()).
  PlanOutcome Plan(const PlanQuery& query, const Termination& termination) const;

 private:
  const PlannerRegistry& registry_;
};

}  // namespace chasles
