#include "chasles/pipeline/plan_pipeline.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <sstream>

#include "chasles/optimizers/shortcut.h"
#include "chasles/robot/dynamics.h"
#include "chasles/robot/error.h"
#include "chasles/robot/inverse_kinematics.h"
#include "chasles/robot/kinematics.h"
#include "field_checks.h"

namespace chasles {
namespace {

using detail::CheckOpenRange;
using detail::CheckRange;

using Clock = std::chrono::steady_clock;

double SecondsSince(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

std::string DescribeContact(const CollisionResult& c) {
  if (!c.violation.empty()) return "it breaks " + c.violation;
  return c.self_collision ? "link '" + c.link_a + "' touches link '" + c.other + "'"
                          : "link '" + c.link_a + "' touches '" + c.other + "'" + VoxelText(c);
}

/// Indices k of the segments path[k] → path[k + 1] that are not free: certified when the checker
/// certifies motions, else checked at `step`. Adds the states evaluated to *state_checks.
std::vector<std::size_t> CollidingSegments(const JointPath& path, const CollisionChecker& checker, double step,
                                           std::uint64_t* state_checks) {
  std::vector<std::size_t> colliding;
  CheckCounters counters;
  for (std::size_t k = 0; k + 1 < path.size(); ++k) {
    const bool free = checker.IsMotionFree(path[k], path[k + 1], step, &counters);
    if (!free) colliding.push_back(k);
  }
  *state_checks += counters.state_checks;
  return colliding;
}

/// `path` with each segment listed in `colliding` (ascending) replaced by an RRT-Connect path
/// between its ends planned at `step` (segment k seeded seed + k), ending exactly at the next
/// waypoint. Adds the planners' counts to *out; empty with *failed naming the segment (and
/// `how` it was found colliding) when one finds no path.
JointPath ReplanSegments(const PlannerRegistry& registry, const PlanQuery& query, const JointPath& path,
                         const std::vector<std::size_t>& colliding, double step, std::uint64_t seed,
                         const std::string& how, const Termination& termination, PlanOutcome* out,
                         std::string* failed) {
  JointPath replanned;
  std::size_t next = 0;  // first waypoint of `path` not yet copied
  for (std::size_t k : colliding) {
    replanned.insert(replanned.end(), path.begin() + static_cast<std::ptrdiff_t>(next),
                     path.begin() + static_cast<std::ptrdiff_t>(k));
    std::unique_ptr<Planner> planner = registry.Create("rrt_connect");
    PlanningProblem segment;
    segment.checker = query.checker;
    segment.start = path[k];
    segment.goal = path[k + 1];
    segment.goal_tolerance = 0.0;
    segment.max_step = step;
    segment.seed = seed + k;
    planner->Setup(segment);
    const PlannerResult result = planner->Solve(termination);
    out->graph_states += result.graph_states;
    out->state_checks += result.state_checks;
    if (result.status != PlanStatus::kExactSolution || result.path.empty()) {
      *failed = "replanning segment path[" + std::to_string(k) + "] → path[" + std::to_string(k + 1) + "] " + how +
                " found no path: " + result.message;
      return {};
    }
    replanned.insert(replanned.end(), result.path.begin(), result.path.end() - 1);
    replanned.push_back(path[k + 1]);  // the segment ends exactly where the path goes on
    next = k + 2;
  }
  replanned.insert(replanned.end(), path.begin() + static_cast<std::ptrdiff_t>(next), path.end());
  return replanned;
}

/// "path[3] → path[4], path[7] → path[8]" (the first four, then "…").
std::string DescribeSegments(const std::vector<std::size_t>& segments) {
  std::string text;
  for (std::size_t j = 0; j < segments.size() && j < 4; ++j) {
    text += (j ? ", path[" : "path[") + std::to_string(segments[j]) + "] → path[" + std::to_string(segments[j] + 1) + "]";
  }
  if (segments.size() > 4) text += ", …";
  return text;
}

/// Phase 1's outcome: the goal states (the joint goal, or collision-free IK solutions of the
/// pose goal, nearest to the start first), or the code and message that end the query.
struct Ends {
  std::vector<Eigen::VectorXd> goals;
  std::optional<PlanOutcomeCode> code;
  std::string message;
};

Ends CheckEnds(const PlanQuery& query, const Termination& termination, PlanOutcome* out) {
  const CollisionChecker& checker = *query.checker;
  Ends ends;
  // True, with the outcome set, when `q` (the start or the goal) is in collision.
  const auto in_collision = [&](const Eigen::VectorXd& q, PlanOutcomeCode code, const char* what) {
    const CollisionResult contact = checker.Check(q);
    out->state_checks += 1;
    if (!contact.in_collision) return false;
    if (!contact.violation.empty()) {
      ends.code = code == PlanOutcomeCode::kStartInCollision ? PlanOutcomeCode::kStartViolatesConstraints
                                                             : PlanOutcomeCode::kGoalViolatesConstraints;
      ends.message = std::string(what) + " breaks " + contact.violation;
      return true;
    }
    ends.code = code;
    ends.message = std::string(what) + " is in collision: " + DescribeContact(contact);
    return true;
  };
  if (in_collision(query.start, PlanOutcomeCode::kStartInCollision, "start")) return ends;
  if (query.pose_goal) {
    const PoseGoalSpec& pose = *query.pose_goal;
    IkRequest ik;
    SetPoseGoalIk(pose, termination.SecondsLeft(), &ik);
    ik.seed = query.seed;
    ik.initial_guess = query.start;
    ik.accept = [&checker](const Eigen::VectorXd& q) { return checker.IsValid(q); };
    ik.stop = [&termination] { return termination.ShouldStop(); };
    const IkResult solved = SolveIk(checker.robot(), ik);
    if (solved.solutions.empty()) {
      ends.code = PlanOutcomeCode::kGoalUnreachable;
      ends.message = "pose goal for link '" + checker.robot().links()[pose.link].name +
                     "' has no collision-free IK solution: " + solved.message;
      return ends;
    }
    ends.goals = solved.solutions;
    std::stable_sort(ends.goals.begin(), ends.goals.end(), [&query](const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
      return (a - query.start).norm() < (b - query.start).norm();
    });
    return ends;
  }
  if (in_collision(query.goal, PlanOutcomeCode::kGoalInCollision, "goal")) return ends;
  ends.goals.push_back(query.goal);
  return ends;
}

/// Phase 2: the query's planner from the start to the first goal state (the others as further goals).
PlannerResult PlanPath(const PlannerRegistry& registry, const PlanQuery& query, const std::vector<Eigen::VectorXd>& goals,
                       const Termination& termination) {
  std::unique_ptr<Planner> planner = registry.Create(query.planner_id);
  PlanningProblem problem;
  problem.checker = query.checker;
  problem.start = query.start;
  problem.goal = goals.front();
  problem.additional_goals.assign(goals.begin() + 1, goals.end());
  problem.goal_tolerance = query.goal_tolerance;
  problem.max_step = query.collision_resolution;
  problem.seed = query.seed;
  problem.parameters = query.parameters;
  planner->Setup(problem);
  return planner->Solve(termination);
}

/// The outcome a planner's status ends the query with; none for an exact solution.
std::optional<PlanOutcomeCode> PlanFailure(PlanStatus status) {
  switch (status) {
    case PlanStatus::kExactSolution: return std::nullopt;
    case PlanStatus::kApproximateSolution: return PlanOutcomeCode::kApproximateOnly;
    case PlanStatus::kCancelled: return PlanOutcomeCode::kCancelled;
    case PlanStatus::kDeadlineExceeded: return PlanOutcomeCode::kDeadlineExceeded;
    case PlanStatus::kInvalidStart: return PlanOutcomeCode::kStartInCollision;
    case PlanStatus::kInvalidGoal: return PlanOutcomeCode::kGoalInCollision;
    case PlanStatus::kNoSolution: return PlanOutcomeCode::kNoPathWithinBudget;
    case PlanStatus::kLocalMinimum: return PlanOutcomeCode::kLocalMinimum;
    case PlanStatus::kLatticeExhausted: return PlanOutcomeCode::kNoPathOnLattice;
  }
  return PlanOutcomeCode::kNoPathWithinBudget;
}

/// Phase 3: the path shortened with the query's shortcut settings, its checks counted.
JointPath Shorten(const JointPath& path, const PlanQuery& query, double max_step, const Termination& termination,
                  std::uint64_t* state_checks) {
  ShortcutOptions options;
  options.max_attempts = query.shortcut_attempts;
  options.max_step = max_step;
  options.seed = query.seed;
  options.stall_attempts = query.shortcut_stall;
  options.stall_improvement = 0.01;
  // With the stall rule on, a candidate gaining less than half its threshold is not checked
  // (on the bench's Panda scenes: 43 % fewer shortcut states, same path lengths and durations).
  options.min_gain = query.shortcut_stall > 0 ? 0.005 : 0.0;
  // The time budget is the planner's; only the deadline or a cancellation cuts this short.
  options.stop = [&termination] {
    const StopReason reason = termination.Reason();
    return reason == StopReason::kCancelled || reason == StopReason::kDeadline;
  };
  CheckCounters counters;
  JointPath shorter = ShortcutPath(path, *query.checker, options, &counters);
  *state_checks += counters.state_checks;
  return shorter;
}

/// Phase 5b: repairs a path whose segments collide between the states the planner checked:
/// re-checks each segment finer (certified when the checker certifies motions, else at a quarter
/// of the verification step), replans each colliding one with RRT-Connect at that step between
/// its ends, shortens at that step and times again; up to three rounds, the step halved each
/// round. `timed` and `out` (its path and repair record) take the result.
void RepairByReplanning(const PlannerRegistry& registry, const PlanQuery& query, const TrajectorySpec& spec,
                        double verify_step, bool shortcut, const Termination& termination, TrajectoryStageResult* timed,
                        PlanOutcome* out) {
  const CollisionChecker& checker = *query.checker;
  const auto t_repair = Clock::now();
  const Termination repair_termination = termination.WithFreshBudget(std::chrono::duration<double>(query.repair_budget));
  const std::vector<std::string> ids = registry.Ids();
  const bool rrt = std::find(ids.begin(), ids.end(), "rrt_connect") != ids.end() &&
                   registry.Spec("rrt_connect").Supports(checker.robot().kind());
  double step = verify_step / 4.0;
  JointPath path = out->path;
  for (int round = 0; round < 3 && rrt && timed->code == TrajectoryStageCode::kVerificationFailed; ++round) {
    if (repair_termination.ShouldStop()) {
      out->repair.actions.push_back("replanning stopped: " + std::string(repair_termination.Reason() == StopReason::kBudget
                                                                             ? "its budget of " + FormatNumber(query.repair_budget) + " s was spent"
                                                                             : "the call ended"));
      break;
    }
    const std::string how = checker.certifies_motion() ? std::string("certified") : "at " + FormatNumber(step) + " rad";
    const std::vector<std::size_t> colliding = CollidingSegments(path, checker, step, &out->state_checks);
    if (colliding.empty()) {
      out->repair.actions.push_back("re-checked the path's " + std::to_string(path.size() - 1) + " segments " + how +
                                   ": all free, so replanning cannot help");
      break;
    }
    std::string failed;
    const JointPath replanned =
        ReplanSegments(registry, query, path, colliding, step, query.seed + 7919u * static_cast<std::uint64_t>(round + 1),
                       how, repair_termination, out, &failed);
    if (replanned.empty()) {
      out->repair.actions.push_back(failed);
      break;
    }
    path = shortcut ? Shorten(replanned, query, step, termination, &out->state_checks) : replanned;
    *timed = RunTrajectoryStage(path, checker, spec, verify_step, termination);
    std::string action = "replanned " + std::to_string(colliding.size()) + " segment" +
                         std::string(colliding.size() == 1 ? " that collides " : "s that collide ") + how + " (" +
                         DescribeSegments(colliding) + ") with RRT-Connect at " + FormatNumber(step) + " rad" + (shortcut ? ", shortened" : "") +
                         ", " + std::to_string(path.size()) + " waypoints: ";
    if (timed->code == TrajectoryStageCode::kSuccess) {
      action += "verified";
      out->repair.repaired = true;
      out->path = path;
    } else {
      action += "failed verification (" +
                (timed->repair.attempted() ? timed->repair.failure : timed->message) + ")";
    }
    out->repair.actions.push_back(std::move(action));
    for (std::string& nested : timed->repair.actions) out->repair.actions.push_back(std::move(nested));
    if (timed->code == TrajectoryStageCode::kInfeasibleLimits) break;
    step /= 2.0;
  }
  if (!rrt) {
    out->repair.actions.push_back("no segment replanned: RRT-Connect does not plan for a " +
                                 std::string(ToString(checker.robot().kind())) + " robot");
  }
  out->repair.seconds += SecondsSince(t_repair);
}

}  // namespace

void SetPoseGoalIk(const PoseGoalSpec& goal, double seconds_left, IkRequest* ik) {
  ik->link = goal.link;
  ik->target = goal.pose;
  ik->position_tolerance = goal.position_tolerance;
  ik->orientation_tolerance = goal.orientation_tolerance;
  ik->max_solutions = goal.max_goal_states;
  ik->time_budget = std::max(1e-3, std::min(goal.ik_time_budget, seconds_left));
}

const char* ToString(PlanOutcomeCode code) {
  switch (code) {
    case PlanOutcomeCode::kSuccess: return "SUCCESS";
    case PlanOutcomeCode::kNoPathWithinBudget: return "NO_PATH_WITHIN_BUDGET";
    case PlanOutcomeCode::kStartInCollision: return "START_IN_COLLISION";
    case PlanOutcomeCode::kGoalInCollision: return "GOAL_IN_COLLISION";
    case PlanOutcomeCode::kStartViolatesConstraints: return "START_VIOLATES_CONSTRAINTS";
    case PlanOutcomeCode::kGoalViolatesConstraints: return "GOAL_VIOLATES_CONSTRAINTS";
    case PlanOutcomeCode::kGoalUnreachable: return "GOAL_UNREACHABLE";
    case PlanOutcomeCode::kVerificationFailed: return "VERIFICATION_FAILED";
    case PlanOutcomeCode::kApproximateOnly: return "APPROXIMATE_ONLY";
    case PlanOutcomeCode::kCancelled: return "CANCELLED";
    case PlanOutcomeCode::kDeadlineExceeded: return "DEADLINE_EXCEEDED";
    case PlanOutcomeCode::kLocalMinimum: return "LOCAL_MINIMUM";
    case PlanOutcomeCode::kNoPathOnLattice: return "NO_PATH_ON_LATTICE";
    case PlanOutcomeCode::kInfeasibleLimits: return "INFEASIBLE_LIMITS";
  }
  return "UNKNOWN";
}

void PlanQuery::Validate(const PlannerRegistry& registry) const {
  if (!checker) ThrowInvalid("robot/scene: no collision checker was built for the query");
  const RobotModel& robot = checker->robot();
  const int n = robot.num_dofs();
  robot.ValidateConfiguration(start, "start.positions");
  if (pose_goal) {
    const PoseGoalSpec& p = *pose_goal;
    if (p.link < 0 || p.link >= robot.num_links()) {
      ThrowInvalid("pose_goal.link = " + std::to_string(p.link) + " is not a link of robot '" + robot.name() + "'");
    }
    if (!p.pose.matrix().allFinite()) ThrowInvalid("pose_goal.pose must be finite");
    CheckOpenRange(p.position_tolerance, 0.1, "pose_goal.position_tolerance");
    CheckOpenRange(p.orientation_tolerance, 0.5, "pose_goal.orientation_tolerance");
    CheckOpenRange(p.ik_time_budget, 600.0, "pose_goal.ik_time_budget");
    if (p.max_goal_states < 1 || p.max_goal_states > 64) {
      ThrowInvalid("pose_goal.max_goal_states = " + std::to_string(p.max_goal_states) + " must be within [1, 64]");
    }
  } else {
    robot.ValidateConfiguration(goal, "goal.positions");
  }
  if (!gravity.allFinite()) ThrowInvalid("gravity must be finite");
  CheckRange(goal_tolerance, 0.0, 0.1, "goal.tolerance");
  const PlannerSpec& spec = registry.Spec(planner_id);  // throws NotFound
  ResolveParameters(spec, parameters);                   // throws InvalidArgument
  if (!spec.Supports(robot.kind())) {
    std::vector<std::string> alternatives;
    for (const PlannerSpec& other : registry.List()) {
      if (other.Supports(robot.kind())) alternatives.push_back(other.id);
    }
    CheckRobotKind(spec, robot, alternatives);  // throws FailedPrecondition
  }
  if (pose_goal && robot.kind() != RobotKind::kArm) {
    throw Error(ErrorCode::kFailedPrecondition,
                std::string("pose_goal: pose goals need inverse kinematics of an arm; robot '") + robot.name() +
                    "' is a " + ToString(robot.kind()) + " robot — give its goal configuration in goal.positions");
  }
  CheckRange(collision_resolution, 1e-4, 0.1, "collision_resolution");
  CheckRange(sample_period, 1e-4, 1.0, "trajectory.sample_period");
  CheckRange(repair_budget, 0.0, 600.0, "repair_budget");
  if (shortcut_attempts < -1) {
    ThrowInvalid("trajectory.shortcut_attempts = " + std::to_string(shortcut_attempts) + " must be >= -1");
  }
  TrajectorySpec resolved = trajectory;
  resolved.gravity = gravity;
  ResolveLimits(robot, resolved);  // throws naming trajectory.<field>
  (void)n;
}

PlanOutcome PlanningPipeline::Plan(const PlanQuery& query, const Termination& termination) const {
  const auto t_start = Clock::now();
  PlanOutcome out;
  const auto finish = [&](PlanOutcomeCode code, std::string message) {
    out.code = code;
    out.message = std::move(message);
    out.seconds.total = SecondsSince(t_start);
    return std::move(out);  // every call is `return finish(...)`: the samples are moved, not copied
  };

  // 1. Validate: contract violations throw; a colliding start or goal is an outcome.
  query.Validate(registry_);
  const CollisionChecker& checker = *query.checker;
  {
    TrajectorySpec spec = query.trajectory;
    spec.gravity = query.gravity;
    out.limits = ResolveLimits(checker.robot(), spec);
  }
  Ends ends = CheckEnds(query, termination, &out);
  out.seconds.validate = SecondsSince(t_start);
  if (ends.code) return finish(*ends.code, std::move(ends.message));

  // 2. Plan a geometric path.
  auto t = Clock::now();
  const PlannerResult planned = PlanPath(registry_, query, ends.goals, termination);
  out.seconds.plan = SecondsSince(t);
  out.graph_states = planned.graph_states;
  out.state_checks += planned.state_checks;
  out.raw_path = planned.path;
  if (const std::optional<PlanOutcomeCode> failed = PlanFailure(planned.status)) return finish(*failed, planned.message);
  out.goal = planned.path.back();  // exactly one of the goal states
  out.suboptimality_bound = planned.suboptimality_bound;

  // 3. Shorten.
  t = Clock::now();
  const bool shortcut = query.shortcut_attempts >= 0 && !planned.keep_path_shape;
  out.path = shortcut ? Shorten(planned.path, query, query.collision_resolution, termination, &out.state_checks)
                      : planned.path;
  out.seconds.shortcut = SecondsSince(t);

  // 4–5. Time-parameterise (and optimise), then verify densely before anything leaves.
  TrajectorySpec spec = query.trajectory;
  spec.gravity = query.gravity;
  const double verify_step = std::min(0.005, query.collision_resolution);
  TrajectoryStageResult timed = RunTrajectoryStage(out.path, checker, spec, verify_step, termination);
  out.repair = timed.repair;
  out.seconds.parameterize = timed.parameterize_seconds;
  out.seconds.optimize = timed.optimize_seconds;
  out.seconds.verify = timed.verify_seconds;

  // 5b. Repair a path whose segments collide between the states the planner checked.
  if (timed.code == TrajectoryStageCode::kVerificationFailed && !planned.keep_path_shape) {
    RepairByReplanning(registry_, query, spec, verify_step, shortcut, termination, &timed, &out);
  }
  out.seconds.repair = out.repair.seconds;
  out.limits = timed.limits;
  out.verification = timed.verification;
  out.optimizer = timed.optimizer;
  out.state_checks += static_cast<std::uint64_t>(out.verification.states_checked);
  if (timed.code == TrajectoryStageCode::kInfeasibleLimits) {
    return finish(PlanOutcomeCode::kInfeasibleLimits, timed.message);
  }
  if (timed.code != TrajectoryStageCode::kSuccess) {
    return finish(PlanOutcomeCode::kVerificationFailed,
                  "the trajectory failed dense verification: " + out.repair.Describe());
  }

  // 6. What leaves: the trajectory, its quality figures and samples.
  out.trajectory = std::move(timed.trajectory);
  out.quality = timed.quality;
  out.seconds.quality = timed.quality_seconds;
  const auto t_sample = Clock::now();
  if (!query.knots_replace_samples || out.trajectory.degree() > 2) {
    out.samples = SampleTrajectory(out.trajectory, checker.robot(), query.sample_period, query.gravity, query.sample_cap);
  }
  out.seconds.sample = SecondsSince(t_sample);
  const RobotModel& robot = checker.robot();
  if (query.pose_goal) {
    out.goal_manipulability = Manipulability(SpaceJacobian(robot, out.goal, query.pose_goal->link));
  }
  std::ostringstream message;
  message << planned.message << "; " << out.path.size() << " waypoints after shortcutting; "
          << ToString(out.optimizer.used) << " trajectory of " << out.trajectory.duration() << " s, verified at "
          << out.verification.states_checked << " states";
  if (out.optimizer.fell_back) message << "; " << out.optimizer.message;
  if (out.repair.repaired) message << "; repaired after verification found " << out.repair.failure;
  return finish(PlanOutcomeCode::kSuccess, message.str());
}

}  // namespace chasles
