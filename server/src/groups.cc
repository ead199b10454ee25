#include "chasles/server/groups.h"

#include <algorithm>
#include <cstdio>
#include <utility>

#include "chasles/robot/error.h"
#include "chasles/server/convert.h"
#include "chasles/server/status.h"

namespace chasles {
namespace {

/// Per joint of `model`: 1 when `group` moves it.
std::vector<char> InGroup(const RobotModel& model, const PlanningGroup& group) {
  std::vector<char> in_group(static_cast<std::size_t>(model.num_dofs()), 0);
  for (int dof : group.dofs) in_group[static_cast<std::size_t>(dof)] = 1;
  return in_group;
}

/// The group's joints as 'a', 'b', … for messages.
std::string GroupJointNames(const RobotModel& model, const PlanningGroup& group) {
  std::string names;
  for (int dof : group.dofs) names += (names.empty() ? "'" : ", '") + model.dof_names()[dof] + "'";
  return names;
}

/// Velocities or accelerations given for every joint narrowed to the group's (those outside it
/// must be 0: they stand still); given for the group's joints, or none, they are kept.
/// \throws Error(kInvalidArgument) naming `field` and the index.
void NarrowDerivatives(google::protobuf::RepeatedField<double>* values, const RobotModel& model,
                       const PlanningGroup& group, const std::string& field) {
  if (values->size() != model.num_dofs() || static_cast<int>(group.dofs.size()) == model.num_dofs()) return;
  const std::vector<char> in_group = InGroup(model, group);
  for (int i = 0; i < model.num_dofs(); ++i) {
    if (in_group[static_cast<std::size_t>(i)] || values->Get(i) == 0.0) continue;
    ThrowInvalid(field + "[" + std::to_string(i) + "] = " + FormatNumber(values->Get(i)) + " but joint '" +
                 model.dof_names()[i] + "' is not in group '" + group.name + "' and stands still");
  }
  google::protobuf::RepeatedField<double> narrowed;
  for (int dof : group.dofs) narrowed.Add(values->Get(dof));
  values->Swap(&narrowed);
}

}  // namespace

const PlanningGroup& FindGroup(const StoredRobot& robot, const std::string& name, const std::string& field) {
  const auto group = std::find_if(robot.groups.begin(), robot.groups.end(),
                                  [&](const PlanningGroup& g) { return g.name == name; });
  if (group == robot.groups.end()) {
    std::string known;
    for (const PlanningGroup& g : robot.groups) known += (known.empty() ? "'" : ", '") + g.name + "'";
    ThrowInvalid(field + " = '" + name + "' is not a planning group of robot '" + robot.model->name() + "' (" +
                 (known.empty() ? std::string("its SRDF defines none") : "its groups: " + known) + ")");
  }
  return *group;
}

StoredRobot HoldOutside(const StoredRobot& robot, const PlanningGroup& group, const Eigen::VectorXd& state) {
  const std::vector<char> in_group = InGroup(*robot.model, group);
  std::string id = robot.id + "/group=" + group.name + "/held=";
  for (int i = 0; i < robot.model->num_dofs(); ++i) {
    if (in_group[static_cast<std::size_t>(i)]) continue;
    char text[40];
    std::snprintf(text, sizeof(text), "%a,", state[i]);
    id += text;
  }
  StoredRobot held;
  held.id = std::move(id);
  held.model = HoldJointsOutside(*robot.model, group.dofs, state);
  return held;
}

void NarrowPositions(google::protobuf::RepeatedField<double>* values, const RobotModel& model,
                     const PlanningGroup& group, const Eigen::VectorXd& held, const std::string& field,
                     const std::string& held_field, const std::string& held_name, double tolerance,
                     std::vector<std::string>* warnings) {
  const std::vector<int>& dofs = group.dofs;
  const int given = values->size();
  if (given == model.num_dofs() && static_cast<int>(dofs.size()) != model.num_dofs()) {
    const Eigen::VectorXd full = ConfigurationFromProto(*values, model, field, tolerance, warnings);
    const std::vector<char> in_group = InGroup(model, group);
    for (int i = 0; i < model.num_dofs(); ++i) {
      if (in_group[static_cast<std::size_t>(i)] || full[i] == held[i]) continue;
      ThrowInvalid(field + "[" + std::to_string(i) + "] = " + FormatNumber(full[i]) + " differs from " +
                   held_field + "[" + std::to_string(i) + "] = " + FormatNumber(held[i]) + ", but joint '" +
                   model.dof_names()[i] + "' is not in group '" + group.name + "' and stays where " + held_name +
                   " puts it: give the group's joints (" + GroupJointNames(model, group) +
                   "), or every joint with those outside the group equal to " + held_name + "'s");
    }
    values->Clear();
    for (int dof : dofs) values->Add(full[dof]);
  } else if (given != static_cast<int>(dofs.size())) {
    ThrowInvalid(field + " has " + std::to_string(given) + " values; group '" + group.name + "' of robot '" +
                 model.name() + "' has " + std::to_string(dofs.size()) + " joints (" +
                 GroupJointNames(model, group) + "): give those, or all " + std::to_string(model.num_dofs()) +
                 " of the robot's joints");
  }
}

Eigen::VectorXd TakeHeldState(google::protobuf::RepeatedField<double>* values, const RobotModel& model,
                              const PlanningGroup& group, const std::string& field, double tolerance,
                              std::vector<std::string>* warnings) {
  const Eigen::VectorXd held = ConfigurationFromProto(*values, model, field, tolerance, warnings);
  values->Clear();
  for (int dof : group.dofs) values->Add(held[dof]);
  return held;
}

StoredRobot NarrowToGroup(const StoredRobot& robot, v1::PlanRequest* request, std::vector<std::string>* warnings,
                          const std::string& prefix) {
  const RobotModel& model = *robot.model;
  const PlanningGroup& group = FindGroup(robot, request->group(), prefix + "group");
  const double tolerance = BoundsToleranceFromProto(request->bounds_tolerance());
  const Eigen::VectorXd start = TakeHeldState(request->mutable_start()->mutable_positions(), model, group,
                                              prefix + "start.positions", tolerance, warnings);
  if (request->target_case() == v1::PlanRequest::kGoal) {
    NarrowPositions(request->mutable_goal()->mutable_positions(), model, group, start, prefix + "goal.positions",
                    prefix + "start.positions", "the start", tolerance, warnings);
  }
  return HoldOutside(robot, group, start);
}

StoredRobot NarrowToGroup(const StoredRobot& robot, v1::OptimizeRequest* request, std::vector<std::string>* warnings) {
  const RobotModel& model = *robot.model;
  const PlanningGroup& group = FindGroup(robot, request->group());
  const double tolerance = kDefaultBoundsTolerance;
  Eigen::VectorXd held;
  if (request->path_size() > 0) {
    held = TakeHeldState(request->mutable_path(0)->mutable_positions(), model, group, "path[0].positions", tolerance,
                         warnings);
    for (int k = 1; k < request->path_size(); ++k) {
      NarrowPositions(request->mutable_path(k)->mutable_positions(), model, group, held,
                      "path[" + std::to_string(k) + "].positions", "path[0].positions", "the first waypoint",
                      tolerance, warnings);
    }
  } else if (request->trajectory().points_size() > 0) {
    v1::JointTrajectory* trajectory = request->mutable_trajectory();
    held = TakeHeldState(trajectory->mutable_points(0)->mutable_positions(), model, group,
                         "trajectory.points[0].positions", tolerance, warnings);
    for (int k = 0; k < trajectory->points_size(); ++k) {
      const std::string field = "trajectory.points[" + std::to_string(k) + "]";
      v1::TrajectoryPoint* point = trajectory->mutable_points(k);
      if (k > 0) {
        NarrowPositions(point->mutable_positions(), model, group, held, field + ".positions",
                        "trajectory.points[0].positions", "the first waypoint", tolerance, warnings);
      }
      NarrowDerivatives(point->mutable_velocities(), model, group, field + ".velocities");
      NarrowDerivatives(point->mutable_accelerations(), model, group, field + ".accelerations");
    }
    trajectory->clear_joint_names();
    for (int dof : group.dofs) trajectory->add_joint_names(model.dof_names()[dof]);
  } else {
    ThrowInvalid("path and trajectory are both empty: give the waypoints to optimize");
  }
  return HoldOutside(robot, group, held);
}

StoredRobot NarrowToGroup(const StoredRobot& robot, v1::InverseKinematicsRequest* request) {
  const RobotModel& model = *robot.model;
  const PlanningGroup& group = FindGroup(robot, request->group());
  if (request->initial_guess_size() != model.num_dofs()) {
    ThrowInvalid("initial_guess has " + std::to_string(request->initial_guess_size()) + " values; with group '" +
                 group.name + "' it must hold all " + std::to_string(model.num_dofs()) + " joints of robot '" +
                 model.name() + "': those outside the group are held at them");
  }
  const Eigen::VectorXd guess = ConfigurationFromProto(request->initial_guess(), model, "initial_guess");
  request->clear_initial_guess();
  for (int dof : group.dofs) request->add_initial_guess(guess[dof]);
  return HoldOutside(robot, group, guess);
}

StoredRobot NarrowToGroup(const StoredRobot& robot, const v1::CommitTrajectoryRequest& request) {
  const RobotModel& model = *robot.model;
  const PlanningGroup& group = FindGroup(robot, request.group());
  if (request.held_positions_size() != model.num_dofs()) {
    ThrowInvalid("held_positions has " + std::to_string(request.held_positions_size()) + " values; with group '" +
                 group.name + "' it must hold all " + std::to_string(model.num_dofs()) + " joints of robot '" +
                 model.name() + "': those outside the group stand there while the trajectory moves the group's " +
                 std::to_string(group.dofs.size()) + " (" + GroupJointNames(model, group) + ")");
  }
  return HoldOutside(robot, group, ConfigurationFromProto(request.held_positions(), model, "held_positions"));
}

}  // namespace chasles
