#pragma once
/// \file
/// The Planner interface (modelled on OMPL's base::Planner): Setup, Solve, Clear, typed
/// parameters with ranges, and a result with an outcome enum.

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "chasles/collision/collision_checker.h"
#include "chasles/robot/joint_path.h"
#include "chasles/planners/termination.h"

namespace chasles {

enum class ParameterType { kDouble, kInt, kBool };

/// One typed, ranged planner parameter as listed by ListPlanners.
struct ParameterSpec {
  std::string name;
  std::string description;  ///< includes the unit
  ParameterType type = ParameterType::kDouble;
  double default_value = 0.0;
  double min = 0.0;  ///< inclusive
  double max = 0.0;  ///< inclusive
  /// Also settable per joint as `name[i]` (i = configuration index), e.g. `resolution[3]`;
  /// the planner checks i against the robot and lets `name[i]` override `name` for joint i.
  bool per_joint = false;
};

struct PlannerSpec {
  std::string id;           ///< e.g. "rrt_connect"
  std::string description;
  bool optimizing = false;  ///< anytime: improves the path until its termination
  std::vector<ParameterSpec> parameters;
  /// The robot kinds the planner plans for; others are refused (CheckRobotKind).
  std::vector<RobotKind> robot_kinds = {RobotKind::kArm, RobotKind::kPlanar, RobotKind::kFreeFlyer};
  /// Why the other kinds are refused (completes "planner 'x' does not plan for <kind> robots: …").
  std::string refusal_reason = "its motions ignore a car's minimum turning radius";
  const ParameterSpec* Find(const std::string& name) const;
  bool Supports(RobotKind kind) const;
};

/// \throws Error(kFailedPrecondition) when `spec` does not plan for robot's kind, e.g.
/// `planner 'astar' does not plan for dubins_car robots (robot 'car'): its lattice moves ignore a
/// car's minimum turning radius; planners for dubins_car: rrt, rrt_connect, rrt_star`.
/// `alternatives` lists the registry's planners for that kind (may be empty).
void CheckRobotKind(const PlannerSpec& spec, const RobotModel& robot, const std::vector<std::string>& alternatives = {});

/// Parameter values by name; missing ones take their defaults.
using ParameterValues = std::map<std::string, double>;

/// Checks every value against `spec` and fills in defaults.
/// \throws Error(kInvalidArgument), e.g.
///   `planner.parameters['range'] = -1 must be within [0, 100] (planner 'rrt')`,
///   `planner.parameters['foo'] is not a parameter of planner 'rrt' (known: range, goal_bias)`,
///   `planner.parameters['max_nearest'] = 2.5 must be an integer`.
/// Per-joint values (`resolution[3]` for a per_joint parameter) are checked against the same
/// type and range and kept under their indexed name.
ParameterValues ResolveParameters(const PlannerSpec& spec, const ParameterValues& values);

/// Everything a planner needs for one query.
struct PlanningProblem {
  std::shared_ptr<const CollisionChecker> checker;
  Eigen::VectorXd start;
  Eigen::VectorXd goal;
  /// More acceptable goal states (e.g. several IK solutions of a pose goal); the path ends
  /// exactly at `goal` or at one of these.
  std::vector<Eigen::VectorXd> additional_goals;
  double goal_tolerance = 1e-6;  ///< max-norm distance at which the goal counts as reached [rad]
  double max_step = 0.005;       ///< motion-check resolution, max joint step [rad]
  std::uint64_t seed = 1;        ///< the same seed gives the same path (see docs for anytime planners)
  ParameterValues parameters;    ///< resolved (ResolveParameters) values
};

/// Expected outcomes: never exceptions.
enum class PlanStatus {
  kExactSolution,
  kApproximateSolution,  ///< ends short of the goal; not returned as a trajectory
  kNoSolution,           ///< no path found before termination (budget)
  kInvalidStart,         ///< start in collision or outside limits
  kInvalidGoal,          ///< goal in collision or outside limits
  kCancelled,
  kDeadlineExceeded,
  kLocalMinimum,         ///< a descent planner stopped in a local minimum of its potential;
                         ///< `path` is empty (no wrong path is returned), the message says where
  kLatticeExhausted,     ///< a search planner (A*, wavefront) searched every lattice node it can
                         ///< reach from the start without reaching the goal: no path at this
                         ///< resolution (not "out of time"); the message gives nodes and resolution
};
const char* ToString(PlanStatus status);

struct PlannerResult {
  PlanStatus status = PlanStatus::kNoSolution;
  std::string message;
  JointPath path;                 ///< start … goal (exact endpoints) for kExactSolution; with
                                  ///< additional goals it ends exactly at the one reached
  std::uint64_t graph_states = 0; ///< vertices in the planner's tree/graph
  std::uint64_t state_checks = 0; ///< state validity checks (motion checks count their states)
  double solve_seconds = 0.0;
  /// Proven bound on cost / optimal cost in the planner's own search space (weighted A*: ε);
  /// 0 = no bound claimed.
  double suboptimality_bound = 0.0;
  /// The path's segments are chords of curves the robot must follow (a car's turns): later
  /// stages must not shortcut or otherwise reshape it.
  bool keep_path_shape = false;
};

class Planner {
 public:
  virtual ~Planner() = default;
  virtual const PlannerSpec& spec() const = 0;
  /// Prepares for `problem`. \throws Error on invalid parameters.
  virtual void Setup(const PlanningProblem& problem) = 0;
  /// Plans until a solution (non-optimizing) or until `termination` stops it.
  virtual PlannerResult Solve(const Termination& termination) = 0;
  /// Forgets all planning data; Setup must be called again.
  virtual void Clear() = 0;
};

}  // namespace chasles
