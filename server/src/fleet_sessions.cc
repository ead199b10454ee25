#include "chasles/server/fleet_sessions.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <tuple>
#include <utility>

#include "chasles/multi/fleet.h"
#include "chasles/pipeline/trajectory_stage.h"
#include "chasles/robot/error.h"
#include "chasles/server/convert.h"
#include "chasles/server/status.h"
#include "chasles/server/workcells.h"

namespace chasles {
namespace {

/// AssignFleetGoalsRequest.state_tolerance [m], its default for 0.
/// \throws Error(kInvalidArgument) when it is negative or not finite.
double StateTolerance(const v1::AssignFleetGoalsRequest& request) {
  const double t = request.state_tolerance();
  if (!std::isfinite(t) || t < 0.0) {
    ThrowInvalid("state_tolerance = " + FormatNumber(t) + " must be finite and > 0 m (0 = the default 0.05 m)");
  }
  return t == 0.0 ? 0.05 : t;
}

v1::FleetStateStatus StateStatusToProto(FleetStateStatus status) {
  switch (status) {
    case FleetStateStatus::kOnPlan: return v1::ON_PLAN;
    case FleetStateStatus::kLate: return v1::LATE;
    case FleetStateStatus::kAhead: return v1::AHEAD;
    case FleetStateStatus::kOffPlan: return v1::OFF_PLAN;
  }
  return v1::FLEET_STATE_STATUS_UNSPECIFIED;
}

Eigen::VectorXd Limits(const google::protobuf::RepeatedField<double>& values) {
  Eigen::VectorXd out(values.size());
  for (int i = 0; i < values.size(); ++i) out[i] = values.Get(i);
  return out;
}

/// `message` with every "robots[k].pose" (the planner's name for the start) as the wire's field.
std::string WireField(std::string message) {
  for (std::size_t at = message.find(".pose"); at != std::string::npos; at = message.find(".pose", at)) {
    message.replace(at, 5, ".start.positions");
  }
  return message;
}

/// Robot r's current plan appended to the response.
void AddPlan(const OpenFleet& fleet, int r, v1::AssignFleetGoalsResponse* response) {
  const FleetSessionPlan& plan = fleet.session->plan(r);
  v1::FleetPlan* out = response->add_plans();
  out->set_robot(fleet.names[static_cast<std::size_t>(r)]);
  out->set_start_time(plan.start_time);
  out->set_arrival_time(plan.arrival_time);
  out->set_finish_time(plan.finish_time);
  KnotsToProto(plan.trajectory, fleet.joint_names[static_cast<std::size_t>(r)], out->mutable_knots());
}

constexpr const char* kFleetsKey = "chasles:fleets";

std::string FleetKey(const std::string& name, const std::string& what) { return "chasles:fleet:" + name + ":" + what; }

}  // namespace

void FleetSessionStore::UseShared(std::shared_ptr<RedisClient> redis, Rebuild rebuild) {
  redis_ = std::move(redis);
  rebuild_ = std::move(rebuild);
}

void FleetSessionStore::Add(const std::string& name, std::shared_ptr<OpenFleet> fleet,
                            const v1::OpenFleetSessionRequest& record) {
  CheckName("name", name);
  const std::string already =
      "fleet session '" + name + "' is open already; close it first (CloseFleetSession) or use another name";
  if (redis_ != nullptr) {
    const long long open = redis_->Command({"SCARD", kFleetsKey}).integer;
    if (static_cast<std::size_t>(open) >= max_sessions_) {
      ThrowResourceExhausted("the shared store holds " + std::to_string(open) +
                             " fleet sessions already, the server's cap; close one (CloseFleetSession)");
    }
    fleet->record = record.SerializeAsString();
    fleet->applied = 0;
    if (redis_->Command({"SET", FleetKey(name, "open"), fleet->record, "NX"}).nil()) {
      throw Error(ErrorCode::kFailedPrecondition, already);
    }
    redis_->Command({"SADD", kFleetsKey, name});
    std::lock_guard<std::mutex> lock(mutex_);
    sessions_[name] = std::move(fleet);
    return;
  }
  std::lock_guard<std::mutex> lock(mutex_);
  if (sessions_.count(name) > 0) throw Error(ErrorCode::kFailedPrecondition, already);
  if (sessions_.size() >= max_sessions_) {
    ThrowResourceExhausted("this server holds " + std::to_string(sessions_.size()) +
                           " fleet sessions already, its cap; close one (CloseFleetSession)");
  }
  sessions_.emplace(name, std::move(fleet));
}

std::shared_ptr<OpenFleet> FleetSessionStore::Find(const std::string& name) {
  if (redis_ != nullptr) return FindShared(name);
  std::lock_guard<std::mutex> lock(mutex_);
  const auto it = sessions_.find(name);
  if (it != sessions_.end()) return it->second;
  std::string known;
  for (const auto& [open, fleet] : sessions_) known += (known.empty() ? "" : ", ") + open;
  throw Error(ErrorCode::kNotFound, "fleet session '" + name + "' is not open (open: " +
                                        (known.empty() ? "none" : known) + "); open it with OpenFleetSession");
}

std::shared_ptr<OpenFleet> FleetSessionStore::FindShared(const std::string& name) {
  const RedisReply record = redis_->Command({"GET", FleetKey(name, "open")});
  if (record.nil()) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      sessions_.erase(name);
    }
    std::string known;
    const RedisReply members = redis_->Command({"SMEMBERS", kFleetsKey});
    for (const RedisReply& open : members.elements) {
      known += (known.empty() ? "" : ", ") + open.str;
    }
    throw Error(ErrorCode::kNotFound, "fleet session '" + name + "' is not open (open: " +
                                          (known.empty() ? "none" : known) + "); open it with OpenFleetSession");
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto it = sessions_.find(name);
    if (it != sessions_.end() && it->second->record == record.str) return it->second;
  }
  // Opened on another replica (or closed and opened again): built here from its record.
  v1::OpenFleetSessionRequest request;
  if (!request.ParseFromString(record.str)) {
    throw Error(ErrorCode::kFailedPrecondition, "the shared store holds an unreadable fleet session '" + name + "'");
  }
  std::shared_ptr<OpenFleet> fleet = rebuild_(request);
  fleet->record = record.str;
  fleet->applied = 0;
  std::lock_guard<std::mutex> lock(mutex_);
  auto& slot = sessions_[name];
  if (slot == nullptr || slot->record != record.str) slot = fleet;
  return slot;
}

void FleetSessionStore::Assign(const std::string& name, const v1::AssignFleetGoalsRequest& request, double now,
                               const Termination& termination, v1::AssignFleetGoalsResponse* response) {
  const std::shared_ptr<OpenFleet> fleet = Find(name);
  std::lock_guard<std::mutex> lock(fleet->mutex);
  if (redis_ != nullptr) return AssignShared(name, *fleet, request, now, termination, response);
  AssignFleetGoalsFromProto(*fleet, request, now, termination, response);
}

void FleetSessionStore::AssignShared(const std::string& name, OpenFleet& fleet, const v1::AssignFleetGoalsRequest& request,
                                     double now, const Termination& termination,
                                     v1::AssignFleetGoalsResponse* response) {
  const std::string log = FleetKey(name, "log");
  for (int attempt = 0; attempt < 50; ++attempt) {
    bool done = false;
    redis_->Transaction([&](RedisClient::Held& redis) {
      redis.Send({"WATCH", log});
      const std::vector<RedisReply> state = redis.Pipeline({{"GET", FleetKey(name, "open")}, {"LLEN", log}});
      if (state[0].nil() || state[0].str != fleet.record) {
        throw Error(ErrorCode::kNotFound, "fleet session '" + name + "' was closed meanwhile; open it again");
      }
      const std::uint64_t length = static_cast<std::uint64_t>(state[1].integer);
      if (length > fleet.applied) {
        // Catch up with the batches other replicas appended.
        const RedisReply batches = redis.Send({"LRANGE", log, std::to_string(fleet.applied), std::to_string(length - 1)});
        for (const RedisReply& batch : batches.elements) {
          ReplayFleetGoals(fleet, batch.str);
          ++fleet.applied;
        }
      }
      // Plan on a copy: it becomes the session only once the batch is in the log.
      OpenFleet trial;
      trial.session = std::make_unique<FleetSession>(*fleet.session);
      trial.names = fleet.names;
      trial.joint_names = fleet.joint_names;
      trial.index = fleet.index;
      response->Clear();
      AssignFleetGoalsFromProto(trial, request, now, termination, response);
      v1::AssignFleetGoalsRequest batch;
      batch.set_now(now);
      *batch.mutable_states() = request.states();  // (states always apply: Report is deterministic)
      batch.set_state_tolerance(request.state_tolerance());
      for (int k = 0; k < request.goals_size(); ++k) {
        v1::FleetGoal* goal = batch.add_goals();
        goal->set_robot(request.goals(k).robot());
        if (response->results(k).outcome() == v1::SUCCESS) *goal->mutable_positions() = request.goals(k).positions();
      }
      const std::vector<RedisReply> replies =
          redis.Pipeline({{"MULTI"}, {"RPUSH", log, batch.SerializeAsString()}, {"EXEC"}});
      if (replies.back().nil()) return;  // another replica appended first: start over
      fleet.session = std::move(trial.session);
      ++fleet.applied;
      done = true;
    });
    if (done) return;
  }
  throw Error(ErrorCode::kUnavailable, "fleet session '" + name + "' changed under this call 50 times in a row; try again");
}

bool FleetSessionStore::Close(const std::string& name) {
  bool closed = false;
  if (redis_ != nullptr) {
    closed = redis_->Command({"DEL", FleetKey(name, "open"), FleetKey(name, "log")}).integer > 0;
    redis_->Command({"SREM", kFleetsKey, name});
  }
  std::lock_guard<std::mutex> lock(mutex_);
  closed = sessions_.erase(name) > 0 || closed;
  return closed;
}

void ReplayFleetGoals(OpenFleet& fleet, const std::string& bytes) {
  v1::AssignFleetGoalsRequest batch;
  if (!batch.ParseFromString(bytes)) {
    throw Error(ErrorCode::kFailedPrecondition, "the shared store holds an unreadable fleet goal batch");
  }
  for (const v1::FleetRobotState& state : batch.states()) {
    const auto it = fleet.index.find(state.robot());
    if (it == fleet.index.end()) throw Error(ErrorCode::kFailedPrecondition, "a stored state names an unknown robot");
    fleet.session->Report(it->second, Eigen::Vector2d(state.x(), state.y()), batch.now(), StateTolerance(batch));
  }
  for (const v1::FleetGoal& goal : batch.goals()) {
    const auto it = fleet.index.find(goal.robot());
    if (it == fleet.index.end()) throw Error(ErrorCode::kFailedPrecondition, "a stored goal names an unknown robot");
    if (goal.positions_size() != 3) {
      fleet.session->Skip(batch.now());
      continue;
    }
    const Eigen::Vector3d target(goal.positions(0), goal.positions(1), goal.positions(2));
    const FleetGoalOutcome outcome = fleet.session->Assign(it->second, target, batch.now());
    if (outcome.code != FleetGoalCode::kSuccess) {
      throw Error(ErrorCode::kFailedPrecondition, "replaying the shared fleet session diverged at a goal of robot '" +
                                                      goal.robot() + "': " + outcome.message);
    }
  }
}

std::shared_ptr<OpenFleet> OpenFleetFromProto(const v1::OpenFleetSessionRequest& request,
                                              std::shared_ptr<const Scene> scene, const std::string& scene_id,
                                              const TeamRobotResolver& resolve, double start_time, int max_robots,
                                              FleetLatticeCache* cache, v1::OpenFleetSessionResponse* response) {
  const int n = request.robots_size();
  if (n < 1 || n > max_robots) {
    ThrowInvalid("robots has " + std::to_string(n) + " entries; a fleet session has 1 to " +
                 std::to_string(max_robots) + " robots (the server's --max-team-robots)");
  }
  if (!std::isfinite(request.robot_padding()) || request.robot_padding() < 0.0 || request.robot_padding() > 0.5) {
    ThrowInvalid("robot_padding = " + FormatNumber(request.robot_padding()) + " must be within [0, 0.5] m");
  }
  if (!std::isfinite(request.fleet_resolution()) || request.fleet_resolution() < 0.0) {
    ThrowInvalid("fleet_resolution = " + FormatNumber(request.fleet_resolution()) + " must be finite and >= 0 m");
  }
  auto fleet = std::make_shared<OpenFleet>();
  std::vector<std::shared_ptr<const RobotModel>> models;
  std::vector<FleetSessionRobot> robots(static_cast<std::size_t>(n));
  for (int k = 0; k < n; ++k) {
    const v1::TeamRobot& r = request.robots(k);
    const std::string field = "robots[" + std::to_string(k) + "]";
    CheckName(field + ".name", r.name());
    if (!fleet->index.emplace(r.name(), k).second) {
      ThrowInvalid(field + ".name = '" + r.name() + "' repeats robots[" + std::to_string(fleet->index[r.name()]) +
                   "].name; names must be unique");
    }
    std::shared_ptr<const RobotModel> model = resolve(r, field);
    if (model->kind() != RobotKind::kPlanar || model->num_dofs() != 3) {
      ThrowInvalid(field + " '" + r.name() + "' is not a planar mobile base (x, y, θ); a fleet session holds them only");
    }
    if (r.has_base_pose()) ThrowInvalid(field + ".base_pose is set; a fleet's bases move in the scene frame");
    if (!r.group().empty()) ThrowInvalid(field + ".group = '" + r.group() + "' is set; a planar base has no groups");
    const Eigen::VectorXd start = ConfigurationFromProto(r.start().positions(), *model, field + ".start.positions");
    TrajectorySpec spec;
    spec.max_velocity = Limits(r.max_velocity());
    spec.max_acceleration = Limits(r.max_acceleration());
    KinematicLimits limits;
    try {
      limits = ResolveLimits(*model, spec);
    } catch (const Error& e) {
      std::string message = e.what();
      const std::size_t at = message.find("trajectory.");
      if (at != std::string::npos) message.replace(at, 11, field + ".");
      throw Error(e.code(), message);
    }
    FleetSessionRobot& robot = robots[static_cast<std::size_t>(k)];
    robot.name = r.name();
    robot.pose = start.head<3>();
    robot.max_velocity = limits.max_velocity.head<3>();
    robot.max_acceleration = limits.max_acceleration.head<3>();
    fleet->names.push_back(r.name());
    fleet->joint_names.push_back(model->dof_names());
    models.push_back(std::move(model));
  }
  const FleetLatticeChoice choice = ChooseFleetLattice(models, robots[0].pose.head<2>(), *scene, scene_id,
                                                       request.fleet_resolution(), request.robot_padding(), cache);
  try {
    fleet->session = std::make_unique<FleetSession>(choice.lattice, std::move(robots), start_time);
  } catch (const Error& e) {
    throw Error(e.code(), WireField(e.what()));
  }
  const LatticeGeometry& g = choice.lattice->geometry();
  v1::FleetStatistics* lattice = response->mutable_lattice();
  lattice->set_resolution(choice.spacing);
  lattice->set_width(static_cast<std::uint32_t>(g.width));
  lattice->set_height(static_cast<std::uint32_t>(g.height));
  const auto& blocked = choice.lattice->map().blocked;
  lattice->set_free_nodes(static_cast<std::uint32_t>(std::count(blocked.begin(), blocked.end(), 0)));
  lattice->set_lattice_seconds(choice.seconds);
  lattice->set_lattice_cached(choice.cached);
  response->set_robots(static_cast<std::uint32_t>(n));
  response->set_start_time(start_time);
  return fleet;
}

void AssignFleetGoalsFromProto(OpenFleet& fleet, const v1::AssignFleetGoalsRequest& request, double now,
                               const Termination& termination, v1::AssignFleetGoalsResponse* response) {
  FleetSession& session = *fleet.session;
  // Every state and goal validated before any is applied, so a bad one changes nothing.
  const double tolerance = StateTolerance(request);
  std::vector<std::pair<int, Eigen::Vector2d>> states;
  for (int k = 0; k < request.states_size(); ++k) {
    const v1::FleetRobotState& state = request.states(k);
    const std::string field = "states[" + std::to_string(k) + "]";
    const auto it = fleet.index.find(state.robot());
    if (it == fleet.index.end()) {
      ThrowInvalid(field + ".robot = '" + state.robot() + "' is not a robot of this fleet session");
    }
    if (!std::isfinite(state.x()) || !std::isfinite(state.y())) {
      ThrowInvalid(field + " (x, y) = (" + FormatNumber(state.x()) + ", " + FormatNumber(state.y()) +
                   ") must be finite [m]");
    }
    states.emplace_back(it->second, Eigen::Vector2d(state.x(), state.y()));
  }
  std::vector<std::pair<int, Eigen::Vector3d>> goals;
  for (int k = 0; k < request.goals_size(); ++k) {
    const v1::FleetGoal& goal = request.goals(k);
    const std::string field = "goals[" + std::to_string(k) + "]";
    const auto it = fleet.index.find(goal.robot());
    if (it == fleet.index.end()) {
      ThrowInvalid(field + ".robot = '" + goal.robot() + "' is not a robot of this fleet session");
    }
    if (goal.positions_size() != 3) {
      ThrowInvalid(field + ".positions has " + std::to_string(goal.positions_size()) + " values; give (x, y, θ)");
    }
    Eigen::Vector3d target;
    for (int i = 0; i < 3; ++i) {
      target[i] = goal.positions(i);
      if (!std::isfinite(target[i])) {
        ThrowInvalid(field + ".positions[" + std::to_string(i) + "] = " + FormatNumber(target[i]) + " must be finite");
      }
    }
    session.GoalCell(target, field + ".positions");
    goals.emplace_back(it->second, target);
  }
  response->set_now(now);
  std::vector<int> changed;  // robots with a new plan, each once
  const auto new_plan = [&](int r) {
    if (std::find(changed.begin(), changed.end(), r) == changed.end()) changed.push_back(r);
    AddPlan(fleet, r, response);
  };
  for (const auto& [robot, position] : states) {
    const FleetStateOutcome outcome = session.Report(robot, position, now, tolerance);
    v1::FleetStateResult* result = response->add_states();
    result->set_robot(fleet.names[static_cast<std::size_t>(robot)]);
    result->set_status(StateStatusToProto(outcome.status));
    result->set_deviation(outcome.deviation);
    result->set_delay(outcome.delay);
    for (int i = 0; i < 3; ++i) result->add_planned(outcome.planned[i]);
    result->set_message(outcome.message);
    for (std::size_t i = 0; i < outcome.robots.size(); ++i) {
      const int r = outcome.robots[i];
      if (i > 0) result->add_delayed(fleet.names[static_cast<std::size_t>(r)]);
      new_plan(r);
    }
  }
  for (std::size_t k = 0; k < goals.size(); ++k) {
    const auto& [robot, target] = goals[k];
    const FleetGoalOutcome outcome = session.Assign(robot, target, now, termination);
    v1::FleetGoalResult* result = response->add_results();
    result->set_robot(fleet.names[static_cast<std::size_t>(robot)]);
    result->set_outcome(outcome.code == FleetGoalCode::kSuccess ? v1::SUCCESS : v1::NO_PATH_WITHIN_BUDGET);
    result->set_message(outcome.message);
    result->set_seconds(outcome.seconds);
    result->set_expansions(outcome.expansions);
    for (std::size_t r = 1; r < outcome.robots.size(); ++r) {
      result->add_moved_aside(fleet.names[static_cast<std::size_t>(outcome.robots[r])]);
    }
    // The moved-aside robots were planned first, the goal's robot last.
    for (std::size_t i = outcome.robots.size(); i-- > 0;) new_plan(outcome.robots[i]);
  }
  // The orders of the plans as they stand after the last goal (a later goal may replace a plan
  // an earlier one was ordered against); an order between two new plans is listed once.
  std::set<std::tuple<int, int, GridCell, double>> seen;
  for (int r : changed) {
    for (const FleetSessionOrder& order : session.Orders(r, now)) {
      if (!seen.emplace(order.before_robot, order.after_robot, order.cell, order.enters).second) continue;
      v1::FleetOrder* out = response->add_orders();
      out->set_before(fleet.names[static_cast<std::size_t>(order.before_robot)]);
      out->set_after(fleet.names[static_cast<std::size_t>(order.after_robot)]);
      out->set_x(order.x);
      out->set_y(order.y);
      out->set_leaves(order.leaves);
      out->set_enters(order.enters);
    }
  }
}

}  // namespace chasles
