#pragma once
/// \file
/// SRDF planning groups in requests (PlanRequest.group, OptimizeRequest.group, TeamRobot.group,
/// InverseKinematicsRequest.group, CommitTrajectoryRequest.group, benchmark problems): the robot
/// with every joint outside the group held at given values, and the request's positions narrowed
/// to the group's joints. Internal to server/; errors name the proto field like convert.h.

#include <string>
#include <vector>

#include <Eigen/Core>
#include <google/protobuf/repeated_field.h>

#include "chasles/robot/planning_groups.h"
#include "chasles/server/model_store.h"
#include "chasles/v1/chasles.pb.h"

namespace chasles {

/// The planning group `name` of `robot`. \throws Error(kInvalidArgument) naming `field` and
/// listing its groups.
const PlanningGroup& FindGroup(const StoredRobot& robot, const std::string& name, const std::string& field = "group");

/// `robot` with every joint outside `group` held where `state` (every joint) puts it; its id
/// names the group and the held values exactly (hex floats), so two states never share a
/// cached checker.
StoredRobot HoldOutside(const StoredRobot& robot, const PlanningGroup& group, const Eigen::VectorXd& state);

/// Positions of a robot narrowed to `group`: given for the group's joints (kept as they are),
/// or for every joint (validated and clamped as ConfigurationFromProto does, those outside the
/// group equal to `held`, which `held_field` gives — `held_name` in messages: "the start",
/// "the first waypoint"), rewritten to the group's values. \throws Error(kInvalidArgument)
/// naming `field`.
void NarrowPositions(google::protobuf::RepeatedField<double>* values, const RobotModel& model,
                     const PlanningGroup& group, const Eigen::VectorXd& held, const std::string& field,
                     const std::string& held_field, const std::string& held_name, double tolerance,
                     std::vector<std::string>* warnings);

/// The full state a grouped request holds the other joints at (every joint, validated and
/// clamped), its field rewritten to the group's values.
Eigen::VectorXd TakeHeldState(google::protobuf::RepeatedField<double>* values, const RobotModel& model,
                              const PlanningGroup& group, const std::string& field, double tolerance,
                              std::vector<std::string>* warnings);

/// PlanRequest.group: the robot with every joint outside the group held where the start puts
/// it, and the request's start and goal narrowed to the group's joints; start values clamped
/// within bounds_tolerance are reported in *warnings. Fields are named after `prefix`
/// ("problems[3].request." in a benchmark). \throws Error(kInvalidArgument) naming the field.
StoredRobot NarrowToGroup(const StoredRobot& robot, v1::PlanRequest* request, std::vector<std::string>* warnings,
                          const std::string& prefix = "");

/// OptimizeRequest.group: the robot held outside the group where the first waypoint (path[0] or
/// the trajectory's first point, every joint) puts it; every waypoint narrowed to the group's
/// joints (velocities and accelerations of trajectory points too, given for the group or for
/// every joint). \throws Error(kInvalidArgument) naming the field.
StoredRobot NarrowToGroup(const StoredRobot& robot, v1::OptimizeRequest* request, std::vector<std::string>* warnings);

/// InverseKinematicsRequest.group: the robot with every joint outside the group held where
/// initial_guess (every joint, required) puts it, and initial_guess narrowed to the group's
/// joints. \throws Error(kInvalidArgument) naming the field.
StoredRobot NarrowToGroup(const StoredRobot& robot, v1::InverseKinematicsRequest* request);

/// CommitTrajectoryRequest.group: the robot held outside the group at held_positions (every
/// joint, required with a group; the group's own values there are ignored), so the trajectory
/// gives the group's joints as Plan and Coordinate return them. \throws Error(kInvalidArgument)
/// naming the field.
StoredRobot NarrowToGroup(const StoredRobot& robot, const v1::CommitTrajectoryRequest& request);

}  // namespace chasles
