#pragma once
/// \file
/// Trajectories as other tools load them: MoveIt's moveit_msgs/RobotTrajectory as YAML (what
/// `ros2 topic echo` prints and MoveIt's Python/C++ YAML loaders read) and ROS's
/// trajectory_msgs/JointTrajectory as JSON (rosbridge's encoding). ROS 2 field names
/// (time_from_start {sec, nanosec}); the joint names are the robot's; positions [rad] or [m],
/// velocities, accelerations per second.

#include <string>
#include <vector>

#include "chasles/optimizers/timed_trajectory.h"
#include "chasles/robot/robot_model.h"

namespace chasles {

std::string MoveItTrajectoryYaml(const RobotModel& robot, const std::vector<TrajectorySample>& samples);
std::string RosTrajectoryJson(const RobotModel& robot, const std::vector<TrajectorySample>& samples);

}  // namespace chasles
