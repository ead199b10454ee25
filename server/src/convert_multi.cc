#include "chasles/server/convert_multi.h"

#include <cmath>
#include <utility>

#include "chasles/robot/error.h"
#include "chasles/server/convert.h"
#include "chasles/server/groups.h"

namespace chasles {
namespace {

std::string Indexed(const std::string& field, int index) { return field + "[" + std::to_string(index) + "]"; }

Eigen::VectorXd OptionalLimits(const google::protobuf::RepeatedField<double>& values) {
  Eigen::VectorXd out(values.size());
  for (int i = 0; i < values.size(); ++i) out[i] = values[i];
  return out;
}

/// 0 = fallback, else within [lo, hi].
double Defaulted(double value, double fallback, double lo, double hi, const std::string& field) {
  if (value == 0.0) return fallback;
  if (!std::isfinite(value) || value < lo || value > hi) {
    ThrowInvalid(field + " = " + FormatNumber(value) + " must be within [" + FormatNumber(lo) + ", " + FormatNumber(hi) +
                 "] (0 = " + FormatNumber(fallback) + ")");
  }
  return value;
}

}  // namespace

void CheckTeamSize(const v1::CoordinateRequest& request, int max_robots) {
  if (request.robots_size() == 0 || request.robots_size() > max_robots) {
    ThrowInvalid("robots has " + std::to_string(request.robots_size()) + " entries; a team has 1 to " +
                 std::to_string(max_robots) + " robots on this server (chasles-server --max-team-robots)");
  }
}

bool KnotsFor(const v1::CoordinateRequest& request) {
  return request.knots_only() || request.robots_size() > kMaxTeamForSamplesByDefault;
}

CoordinationQuery CoordinationQueryFromProto(const v1::CoordinateRequest& request, std::shared_ptr<const Scene> scene,
                                             const TeamRobotResolver& resolve, const PlannerRegistry& registry,
                                             std::vector<std::string>* warnings, int max_robots) {
  CoordinationQuery query;
  const double bounds_tolerance = BoundsToleranceFromProto(request.bounds_tolerance());
  query.scene = std::move(scene);
  query.max_robots = max_robots;
  CheckTeamSize(request, max_robots);
  for (int k = 0; k < request.robots_size(); ++k) {
    const v1::TeamRobot& r = request.robots(k);
    const std::string field = Indexed("robots", k);
    TeamRobotSpec spec;
    spec.placement.name = r.name();
    spec.placement.model = resolve(r, field);
    const RobotModel& model = *spec.placement.model;
    if (r.has_base_pose()) spec.placement.base_pose = PoseFromProto(r.base_pose(), field + ".base_pose");
    spec.start =
        ConfigurationFromProto(r.start().positions(), model, field + ".start.positions", bounds_tolerance, warnings);
    if (r.target_case() == v1::TeamRobot::kPoseGoal) {
      spec.pose_goal = PoseGoalFromProto(r.pose_goal(), model, field + ".pose_goal");
    } else {
      spec.goal =
          ConfigurationFromProto(r.goal().positions(), model, field + ".goal.positions", bounds_tolerance, warnings);
    }
    spec.priority = r.priority();
    spec.max_velocity = OptionalLimits(r.max_velocity());
    spec.max_acceleration = OptionalLimits(r.max_acceleration());
    if (spec.max_velocity.size() > 0) {
      if (spec.max_velocity.size() != model.num_dofs()) {
        ThrowInvalid(field + ".max_velocity has " + std::to_string(spec.max_velocity.size()) + " values, robot '" +
                     r.name() + "' has " + std::to_string(model.num_dofs()) + " joints");
      }
      // Capped at the model's limits as documented (ResolveLimits checks > 0 first).
      for (Eigen::Index i = 0; i < spec.max_velocity.size(); ++i) {
        if (spec.max_velocity[i] > model.velocity_limits()[i]) spec.max_velocity[i] = model.velocity_limits()[i];
      }
    }
    query.robots.push_back(std::move(spec));
  }
  switch (request.method()) {
    case v1::CoordinateRequest::METHOD_UNSPECIFIED:
    case v1::CoordinateRequest::AUTO: query.method = CoordinationMethod::kAuto; break;
    case v1::CoordinateRequest::PRIORITIZED: query.method = CoordinationMethod::kPrioritized; break;
    case v1::CoordinateRequest::COMPOSITE: query.method = CoordinationMethod::kComposite; break;
    case v1::CoordinateRequest::VELOCITY_TUNING: query.method = CoordinationMethod::kVelocityTuning; break;
    case v1::CoordinateRequest::SEQUENTIAL: query.method = CoordinationMethod::kSequential; break;
    case v1::CoordinateRequest::FLEET: query.method = CoordinationMethod::kFleet; break;
    default:
      ThrowInvalid("method = " + std::to_string(static_cast<int>(request.method())) +
                   " is not a method (AUTO, PRIORITIZED, COMPOSITE, VELOCITY_TUNING, SEQUENTIAL, FLEET)");
  }
  query.planner_id = request.planner().planner_id().empty() ? "rrt_connect" : request.planner().planner_id();
  query.parameters = PlannerParametersFromProto(request.planner(), registry.Spec(query.planner_id), "planner");
  const double budget = request.time_budget() == 0.0 ? 30.0 : request.time_budget();
  if (!(std::isfinite(budget) && budget > 0.0 && budget <= 600.0)) {
    ThrowInvalid("time_budget = " + FormatNumber(request.time_budget()) + " must be within (0, 600] s (0 = 30 s)");
  }
  query.time_budget = budget;
  query.seed = request.seed() == 0 ? 1 : request.seed();
  query.collision_resolution = Defaulted(request.collision_resolution(), 0.005, 1e-4, 0.1, "collision_resolution");
  query.time_step = Defaulted(request.time_step(), 1e-3, 1e-4, 0.01, "time_step");
  query.sample_period = Defaulted(request.sample_period(), 0.01, 1e-4, 1.0, "sample_period");
  query.fleet_resolution = request.fleet_resolution();
  query.knots_replace_samples = KnotsFor(request) && request.sample_period() == 0.0;
  if (!std::isfinite(request.robot_padding()) || request.robot_padding() < 0.0 || request.robot_padding() > 0.5) {
    ThrowInvalid("robot_padding = " + FormatNumber(request.robot_padding()) + " must be within [0, 0.5] m");
  }
  query.robot_padding = request.robot_padding();
  query.max_reorderings = static_cast<int>(std::min<std::uint32_t>(request.max_reorderings(), 1000));
  return query;
}

CoordinationQuery WorkcellPlanQuery(const v1::PlanRequest& request, std::shared_ptr<const RobotModel> robot,
                                    std::shared_ptr<const Scene> scene, const PlannerRegistry& registry,
                                    std::vector<std::string>* warnings) {
  const RobotModel& model = *robot;
  const v1::TrajectoryOptions& options = request.trajectory();
  const std::string with = request.has_workcell() ? "workcell" : "moving_obstacles";
  const auto refuse = [&with](const std::string& what) {
    ThrowInvalid(what + " is not supported with " + with + ": such a plan is a sequence of exact moves and waits "
                        "checked against the committed trajectories and moving obstacles");
  };
  if (options.post_processing() != v1::TrajectoryOptions::POST_PROCESSING_UNSPECIFIED &&
      options.post_processing() != v1::TrajectoryOptions::TOPP) {
    refuse("trajectory.post_processing = " + v1::TrajectoryOptions::PostProcessing_Name(options.post_processing()));
  }
  if (options.max_jerk_size() > 0) refuse("trajectory.max_jerk");
  if (options.max_effort_size() > 0) refuse("trajectory.max_effort");
  const std::string name = request.workcell().robot_name().empty() ? "robot" : request.workcell().robot_name();

  CoordinationQuery query;
  query.scene = std::move(scene);
  TeamRobotSpec spec;
  spec.placement.name = name;
  spec.placement.model = std::move(robot);
  if (request.workcell().has_base_pose()) {
    spec.placement.base_pose = PoseFromProto(request.workcell().base_pose(), "workcell.base_pose");
  }
  const double bounds_tolerance = BoundsToleranceFromProto(request.bounds_tolerance());
  spec.start = ConfigurationFromProto(request.start().positions(), model, "start.positions", bounds_tolerance, warnings);
  if (request.target_case() == v1::PlanRequest::kPoseGoal) {
    spec.pose_goal = PoseGoalFromProto(request.pose_goal(), model, "pose_goal");
  } else {
    spec.goal = ConfigurationFromProto(request.goal().positions(), model, "goal.positions", bounds_tolerance, warnings);
  }
  spec.max_velocity = OptionalLimits(options.max_velocity());
  if (spec.max_velocity.size() == model.num_dofs()) spec.max_velocity = spec.max_velocity.cwiseMin(model.velocity_limits());
  spec.max_acceleration = OptionalLimits(options.max_acceleration());
  query.robots.push_back(std::move(spec));
  query.method = CoordinationMethod::kPrioritized;
  query.planner_id = request.planner().planner_id().empty() ? "rrt_connect" : request.planner().planner_id();
  query.parameters = PlannerParametersFromProto(request.planner(), registry.Spec(query.planner_id), "planner");
  const double budget = request.time_budget() == 0.0 ? 5.0 : request.time_budget();
  if (!(std::isfinite(budget) && budget > 0.0 && budget <= 600.0)) {
    ThrowInvalid("time_budget = " + FormatNumber(request.time_budget()) + " must be within (0, 600] s (0 = 5 s)");
  }
  query.time_budget = budget;
  query.seed = request.seed() == 0 ? 1 : request.seed();
  query.collision_resolution = Defaulted(request.collision_resolution(), 0.005, 1e-4, 0.1, "collision_resolution");
  query.sample_period = Defaulted(options.sample_period(), 0.01, 1e-4, 1.0, "trajectory.sample_period");
  return query;
}

std::vector<MovingObstacle> MovingObstaclesFromProto(const google::protobuf::RepeatedPtrField<v1::MovingObstacle>& obstacles,
                                                     int max_obstacles) {
  if (obstacles.size() > max_obstacles) {
    ThrowInvalid("moving_obstacles has " + std::to_string(obstacles.size()) + " entries, more than the cap of " +
                 std::to_string(max_obstacles));
  }
  std::vector<MovingObstacle> out;
  for (int i = 0; i < obstacles.size(); ++i) {
    const v1::MovingObstacle& proto = obstacles.Get(i);
    const std::string field = Indexed("moving_obstacles", i);
    MovingObstacle obstacle;
    obstacle.name = proto.name().empty() ? "obstacle" + std::to_string(i) : proto.name();
    obstacle.shapes = MovingObstacleShapesFromProto(proto, field);
    for (int k = 0; k < proto.waypoints_size(); ++k) {
      obstacle.times.push_back(proto.waypoints(k).time());
      obstacle.poses.push_back(PoseFromProto(proto.waypoints(k).pose(), Indexed(field + ".waypoints", k) + ".pose"));
    }
    obstacle.Validate(field);
    out.push_back(std::move(obstacle));
  }
  return out;
}

v1::PlanOutcome CoordinationCodeToProto(CoordinationCode code) {
  switch (code) {
    case CoordinationCode::kSuccess: return v1::SUCCESS;
    case CoordinationCode::kNoSolution: return v1::NO_PATH_WITHIN_BUDGET;
    case CoordinationCode::kStartInCollision: return v1::START_IN_COLLISION;
    case CoordinationCode::kGoalInCollision: return v1::GOAL_IN_COLLISION;
    case CoordinationCode::kGoalUnreachable: return v1::GOAL_UNREACHABLE;
    case CoordinationCode::kStartsInConflict: return v1::STARTS_IN_CONFLICT;
    case CoordinationCode::kGoalsInConflict: return v1::GOALS_IN_CONFLICT;
    case CoordinationCode::kVerificationFailed: return v1::VERIFICATION_FAILED;
    case CoordinationCode::kCancelled:
    case CoordinationCode::kDeadlineExceeded: return v1::PLAN_OUTCOME_UNSPECIFIED;
  }
  return v1::PLAN_OUTCOME_UNSPECIFIED;
}

void CoordinationOutcomeToProto(const CoordinationOutcome& outcome, const CoordinationQuery& query,
                                v1::CoordinateResponse* response, bool knots) {
  response->set_outcome(CoordinationCodeToProto(outcome.code));
  response->set_message(outcome.message);
  response->set_seconds(outcome.seconds);
  for (const MethodAttemptReport& a : outcome.attempts) {
    v1::MethodAttempt* attempt = response->add_attempts();
    attempt->set_method(ToString(a.method));
    attempt->set_succeeded(a.succeeded);
    attempt->set_message(a.message);
    attempt->set_seconds(a.seconds);
    attempt->set_makespan(a.makespan);
  }
  if (outcome.code != CoordinationCode::kSuccess) return;  // nothing unverified leaves the server
  response->set_method(ToString(outcome.method));
  response->set_makespan(outcome.makespan);
  response->set_sum_of_durations(outcome.sum_of_durations);
  for (const std::string& name : outcome.order) response->add_order(name);
  response->set_reorderings(static_cast<std::uint32_t>(outcome.reorderings));
  v1::TeamVerification* verification = response->mutable_verification();
  verification->set_states_checked(outcome.verification.states_checked);
  verification->set_time_step(query.time_step);
  verification->set_max_joint_step(query.collision_resolution);
  verification->set_max_velocity_ratio(outcome.verification.max_velocity_ratio);
  verification->set_max_acceleration_ratio(outcome.verification.max_acceleration_ratio);
  verification->set_min_robot_distance(outcome.verification.min_robot_distance);
  verification->set_collision_guarantee(outcome.verification.collision_guarantee);
  verification->set_collision_guarantee_reason(outcome.verification.collision_guarantee_reason);
  if (outcome.fleet) {
    const FleetSummary& fleet = *outcome.fleet;
    v1::FleetStatistics* stats = response->mutable_fleet();
    stats->set_resolution(fleet.resolution);
    stats->set_width(static_cast<std::uint32_t>(fleet.width));
    stats->set_height(static_cast<std::uint32_t>(fleet.height));
    stats->set_free_nodes(static_cast<std::uint32_t>(fleet.free_nodes));
    stats->set_makespan_steps(static_cast<std::uint32_t>(fleet.makespan_steps));
    stats->set_sum_of_costs(static_cast<std::uint64_t>(fleet.sum_of_costs));
    stats->set_sum_of_lower_bounds(static_cast<std::uint64_t>(fleet.sum_of_lower_bounds));
    stats->set_lattice_seconds(fleet.lattice_seconds);
    stats->set_search_seconds(fleet.search_seconds);
    stats->set_schedule_seconds(fleet.schedule_seconds);
    stats->set_lattice_cached(fleet.lattice_cached);
    for (const FleetWait& wait : fleet.dependencies) {
      v1::FleetDependency* d = response->add_dependencies();
      d->set_robot(query.robots[static_cast<std::size_t>(wait.robot)].placement.name);
      d->set_leave_index(static_cast<std::uint32_t>(wait.leave_index));
      d->set_waits_for(query.robots[static_cast<std::size_t>(wait.waits_for)].placement.name);
      d->set_arrival_index(static_cast<std::uint32_t>(wait.arrival_index));
      d->set_x(wait.x);
      d->set_y(wait.y);
    }
  }
  for (std::size_t k = 0; k < outcome.robots.size(); ++k) {
    const RobotPlan& plan = outcome.robots[k];
    v1::RobotTrajectory* robot = response->add_robots();
    robot->set_name(plan.name);
    SamplesToProto(plan.samples, *query.robots[k].placement.model, robot->mutable_trajectory());
    if (knots) KnotsToProto(plan.trajectory, query.robots[k].placement.model->dof_names(), robot->mutable_knots());
    robot->set_duration(plan.duration);
    robot->set_start_delay(plan.start_delay);
    robot->set_wait_time(plan.wait_time);
    for (const Eigen::VectorXd& q : plan.path) ToProto(q, robot->add_path()->mutable_positions());
    ToProto(plan.goal, robot->mutable_goal()->mutable_positions());
  }
}

void WorkcellPlanToProto(const CoordinationOutcome& outcome, const CoordinationQuery& query, v1::PlanResponse* response) {
  response->set_outcome(CoordinationCodeToProto(outcome.code));
  // Outcomes that only a team has map to the single robot's: a conflict with a committed motion.
  if (outcome.code == CoordinationCode::kStartsInConflict) response->set_outcome(v1::STARTS_IN_CONFLICT);
  response->set_message(outcome.message);
  response->mutable_timings()->set_total(outcome.seconds);
  if (outcome.code != CoordinationCode::kSuccess || outcome.robots.empty()) return;
  const RobotPlan& plan = outcome.robots.front();
  for (const Eigen::VectorXd& q : plan.path) ToProto(q, response->add_path()->mutable_positions());
  SamplesToProto(plan.samples, *query.robots.front().placement.model, response->mutable_trajectory());
  response->set_duration(plan.duration);
  if (query.robots.front().pose_goal) ToProto(plan.goal, response->mutable_reached_goal()->mutable_positions());
  v1::Verification* verification = response->mutable_verification();
  verification->set_states_checked(static_cast<std::uint32_t>(outcome.verification.states_checked));
  verification->set_max_joint_step(query.collision_resolution);
  verification->set_max_velocity_ratio(outcome.verification.max_velocity_ratio);
  verification->set_max_acceleration_ratio(outcome.verification.max_acceleration_ratio);
  verification->set_collision_guarantee(outcome.verification.collision_guarantee);
  verification->set_collision_guarantee_reason(outcome.verification.collision_guarantee_reason);
  response->mutable_quality()->set_duration(plan.duration);
}

TimedTrajectory TrajectoryFromPoints(const v1::JointTrajectory& trajectory, const RobotModel& robot,
                                     const std::string& field) {
  const int n = robot.num_dofs();
  if (trajectory.points_size() == 0) ThrowInvalid(field + ".points is empty: a trajectory needs at least one point");
  std::vector<double> times;
  std::vector<Eigen::VectorXd> q, v;
  bool velocities = true;
  for (int k = 0; k < trajectory.points_size(); ++k) {
    const v1::TrajectoryPoint& p = trajectory.points(k);
    const std::string f = Indexed(field + ".points", k);
    const double t = p.time_from_start();
    if (!std::isfinite(t) || t < 0.0) ThrowInvalid(f + ".time_from_start = " + FormatNumber(t) + " must be finite and >= 0");
    if (k > 0 && !(t > times.back())) {
      ThrowInvalid(f + ".time_from_start = " + FormatNumber(t) + " must be greater than the previous point's " +
                   FormatNumber(times.back()));
    }
    if (p.positions_size() != n) {
      ThrowInvalid(f + ".positions has " + std::to_string(p.positions_size()) + " values, robot '" + robot.name() +
                   "' has " + std::to_string(n) + " joints");
    }
    if (p.velocities_size() != 0 && p.velocities_size() != n) {
      ThrowInvalid(f + ".velocities has " + std::to_string(p.velocities_size()) + " values, robot '" + robot.name() +
                   "' has " + std::to_string(n) + " joints (or give none)");
    }
    velocities = velocities && p.velocities_size() == n;
    Eigen::VectorXd qk(n), vk = Eigen::VectorXd::Zero(n);
    for (int i = 0; i < n; ++i) {
      qk[i] = p.positions(i);
      if (!std::isfinite(qk[i])) ThrowInvalid(Indexed(f + ".positions", i) + " = " + FormatNumber(qk[i]) + " must be finite");
      if (p.velocities_size() == n) {
        vk[i] = p.velocities(i);
        if (!std::isfinite(vk[i])) ThrowInvalid(Indexed(f + ".velocities", i) + " = " + FormatNumber(vk[i]) + " must be finite");
      }
    }
    times.push_back(t);
    q.push_back(qk);
    v.push_back(vk);
  }
  std::vector<TimedTrajectory::Piece> pieces;
  if (times.front() > 0.0) {
    TimedTrajectory::Piece hold;
    hold.duration = times.front();
    hold.coefficients = q.front();
    pieces.push_back(std::move(hold));
  }
  for (std::size_t k = 0; k + 1 < times.size(); ++k) {
    const double h = times[k + 1] - times[k];
    TimedTrajectory::Piece piece;
    piece.t0 = times[k];
    piece.duration = h;
    const Eigen::VectorXd dq = q[k + 1] - q[k];
    if (velocities) {
      piece.coefficients.resize(n, 4);
      piece.coefficients.col(0) = q[k];
      piece.coefficients.col(1) = v[k];
      piece.coefficients.col(2) = 3.0 * dq / (h * h) - (2.0 * v[k] + v[k + 1]) / h;
      piece.coefficients.col(3) = -2.0 * dq / (h * h * h) + (v[k] + v[k + 1]) / (h * h);
    } else {
      piece.coefficients.resize(n, 2);
      piece.coefficients.col(0) = q[k];
      piece.coefficients.col(1) = dq / h;
    }
    pieces.push_back(std::move(piece));
  }
  if (pieces.empty()) return HoldTrajectory(q.front(), 0.0);
  return TimedTrajectory(std::move(pieces), q.back());
}

double ClockTimeFromProto(double value, double now, const std::string& field) {
  if (!std::isfinite(value) || value < 0.0) {
    ThrowInvalid(field + " = " + FormatNumber(value) + " must be finite and >= 0 s since the Unix epoch (0 = now)");
  }
  return value == 0.0 ? now : value;
}

Reservation ReservationFromCommit(const v1::CommitTrajectoryRequest& request, ModelStore& store, double now) {
  const StoredRobot described = RobotOfRequest(store, request);
  StoredRobot robot = described;
  if (!request.group().empty()) {
    robot = NarrowToGroup(robot, request);
  } else if (request.held_positions_size() > 0) {
    ThrowInvalid("held_positions is set without group: name the planning group the trajectory moves, "
                 "or send no held_positions");
  }
  // What it carries occupies the workcell with it (the others plan around the load too).
  std::vector<std::string> ignored;  // the sphere cover's reach: reported to the plan that made it
  robot = store.Carrying(robot, request.attached_objects(), "attached_objects", &ignored);
  Reservation reservation;
  reservation.robot_name = request.robot_name();
  reservation.placement.name = request.robot_name();
  reservation.placement.model = robot.model;
  if (request.has_base_pose()) reservation.placement.base_pose = PoseFromProto(request.base_pose(), "base_pose");
  reservation.trajectory = TrajectoryFromPoints(request.trajectory(), *robot.model, "trajectory");
  reservation.start_time = ClockTimeFromProto(request.start_time(), now, "start_time");
  reservation.end_time = reservation.start_time + reservation.trajectory.duration();
  reservation.expires_at = reservation.end_time + request.hold();
  // What another replica rebuilds it from: the robot by id, the start resolved.
  v1::CommitTrajectoryRequest record = request;
  record.set_robot_id(described.id);
  record.set_start_time(reservation.start_time);
  reservation.record = record.SerializeAsString();
  return reservation;
}

Reservation ReservationFromRecord(const std::string& bytes, ModelStore& store) {
  v1::CommitTrajectoryRequest record;
  if (!record.ParseFromString(bytes)) {
    throw Error(ErrorCode::kFailedPrecondition, "the shared store holds an unreadable reservation record");
  }
  return ReservationFromCommit(record, store, record.start_time());
}

}  // namespace chasles
