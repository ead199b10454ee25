#include "chasles/server/trajectory_export.h"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>

namespace chasles {
namespace {

/// A number with round-trip precision (17 significant digits; 0 for -0).
std::string Number(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.17g", value == 0.0 ? 0.0 : value);
  return buffer;
}

std::string List(const Eigen::VectorXd& values) {
  std::string out = "[";
  for (Eigen::Index i = 0; i < values.size(); ++i) out += (i ? ", " : "") + Number(values[i]);
  return out + "]";
}

/// time_from_start as {sec, nanosec}: nanoseconds rounded, nanosec in [0, 1e9).
std::string Duration(double seconds) {
  const std::int64_t ns = std::llround(seconds * 1e9);
  return "{\"sec\": " + std::to_string(ns / 1000000000) + ", \"nanosec\": " + std::to_string(ns % 1000000000) + "}";
}

std::string Names(const RobotModel& robot) {
  std::string out = "[";
  for (std::size_t i = 0; i < robot.dof_names().size(); ++i) out += (i ? ", " : "") + std::string("\"") + robot.dof_names()[i] + "\"";
  return out + "]";
}

}  // namespace

std::string MoveItTrajectoryYaml(const RobotModel& robot, const std::vector<TrajectorySample>& samples) {
  std::string out;
  out += "# moveit_msgs/RobotTrajectory of robot '" + robot.name() + "' (written by chasles)\n";
  out += "joint_trajectory:\n";
  out += "  header:\n    stamp: {sec: 0, nanosec: 0}\n    frame_id: ''\n";
  out += "  joint_names: " + Names(robot) + "\n";
  out += "  points:\n";
  for (const TrajectorySample& s : samples) {
    out += "    - positions: " + List(s.q) + "\n";
    out += "      velocities: " + List(s.qd) + "\n";
    out += "      accelerations: " + List(s.qdd) + "\n";
    out += "      effort: " + List(s.effort) + "\n";
    std::string duration = Duration(s.t);
    for (char& c : duration) {
      if (c == '"') c = ' ';
    }
    out += "      time_from_start: " + duration + "\n";
  }
  out += "multi_dof_joint_trajectory:\n";
  out += "  header:\n    stamp: {sec: 0, nanosec: 0}\n    frame_id: ''\n";
  out += "  joint_names: []\n  points: []\n";
  return out;
}

std::string RosTrajectoryJson(const RobotModel& robot, const std::vector<TrajectorySample>& samples) {
  std::string out = "{\n  \"header\": {\"stamp\": {\"sec\": 0, \"nanosec\": 0}, \"frame_id\": \"\"},\n";
  out += "  \"joint_names\": " + Names(robot) + ",\n  \"points\": [\n";
  for (std::size_t k = 0; k < samples.size(); ++k) {
    const TrajectorySample& s = samples[k];
    out += "    {\"positions\": " + List(s.q) + ", \"velocities\": " + List(s.qd) + ", \"accelerations\": " + List(s.qdd) +
           ", \"effort\": " + List(s.effort) + ", \"time_from_start\": " + Duration(s.t) + "}" +
           (k + 1 < samples.size() ? ",\n" : "\n");
  }
  return out + "  ]\n}\n";
}

}  // namespace chasles
