#include "chasles/multi/moving_obstacles.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "chasles/robot/error.h"
#include "chasles/robot/mobile.h"

namespace chasles {
namespace {

constexpr double kPi = 3.14159265358979323846;

/// (yaw, pitch, roll) with R = Rz(yaw) Ry(pitch) Rx(roll), pitch in [−π/2, π/2].
Eigen::Vector3d EulerZyx(const Eigen::Matrix3d& r) {
  const double pitch = std::asin(std::clamp(-r(2, 0), -1.0, 1.0));
  double yaw, roll;
  if (std::abs(r(2, 0)) < 1.0 - 1e-12) {
    yaw = std::atan2(r(1, 0), r(0, 0));
    roll = std::atan2(r(2, 1), r(2, 2));
  } else {  // gimbal lock: only yaw ∓ roll is defined; put it all in yaw
    yaw = std::atan2(-r(0, 1), r(1, 1));
    roll = 0.0;
  }
  return {yaw, pitch, roll};
}

/// The angle equal to `angle` modulo 2π that is nearest to `reference`.
double Nearest(double angle, double reference) {
  return angle - 2.0 * kPi * std::round((angle - reference) / (2.0 * kPi));
}

/// The waypoints as free-flyer coordinates, angles unwrapped so each segment turns the shorter way.
std::vector<Eigen::VectorXd> Coordinates(const MovingObstacle& obstacle) {
  std::vector<Eigen::VectorXd> q;
  for (const Eigen::Isometry3d& pose : obstacle.poses) {
    Eigen::VectorXd c(6);
    c.head<3>() = pose.translation();
    c.tail<3>() = EulerZyx(pose.linear());
    if (!q.empty()) {
      for (int i = 3; i < 6; ++i) c[i] = Nearest(c[i], q.back()[i]);
    }
    q.push_back(std::move(c));
  }
  return q;
}

Eigen::Isometry3d PoseOf(const Eigen::VectorXd& c) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = c.head<3>();
  pose.linear() = (Eigen::AngleAxisd(c[3], Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(c[4], Eigen::Vector3d::UnitY()) *
                   Eigen::AngleAxisd(c[5], Eigen::Vector3d::UnitX()))
                      .toRotationMatrix();
  return pose;
}

}  // namespace

void MovingObstacle::Validate(const std::string& field) const {
  if (shapes.empty()) ThrowInvalid(field + " has no shapes: give at least one box, sphere, cylinder or capsule");
  for (std::size_t k = 0; k < shapes.size(); ++k) {
    if (shapes[k].type == ShapeType::kMesh) ThrowInvalid(field + " shape " + std::to_string(k) + " is a mesh: moving obstacles are primitives");
  }
  if (times.empty()) ThrowInvalid(field + ".waypoints is empty: give at least one timed pose");
  if (poses.size() != times.size()) ThrowInvalid(field + ": " + std::to_string(times.size()) + " times for " + std::to_string(poses.size()) + " poses");
  for (std::size_t k = 0; k < times.size(); ++k) {
    const std::string f = field + ".waypoints[" + std::to_string(k) + "].time";
    if (!std::isfinite(times[k]) || times[k] < 0.0) ThrowInvalid(f + " = " + FormatNumber(times[k]) + " must be finite and >= 0 s");
    if (k > 0 && !(times[k] > times[k - 1])) {
      ThrowInvalid(f + " = " + FormatNumber(times[k]) + " must be greater than the previous waypoint's " + FormatNumber(times[k - 1]) + " s");
    }
    if (!poses[k].matrix().allFinite()) ThrowInvalid(field + ".waypoints[" + std::to_string(k) + "].pose is not finite");
  }
}

Eigen::Isometry3d MovingObstacle::PoseAt(double t) const {
  if (times.size() == 1 || t <= times.front()) return poses.front();
  if (t >= times.back()) return poses.back();
  const std::vector<Eigen::VectorXd> q = Coordinates(*this);
  const std::size_t k = static_cast<std::size_t>(std::upper_bound(times.begin(), times.end(), t) - times.begin()) - 1;
  const double s = (t - times[k]) / (times[k + 1] - times[k]);
  return PoseOf(q[k] + s * (q[k + 1] - q[k]));
}

CommittedMotion MotionOfObstacle(const MovingObstacle& obstacle, const std::string& field) {
  obstacle.Validate(field);
  const std::vector<Eigen::VectorXd> q = Coordinates(obstacle);
  MobileDescription body;
  body.name = obstacle.name.empty() ? "moving_obstacle" : obstacle.name;
  body.kind = RobotKind::kFreeFlyer;
  body.max_tilt = 1.5;  // the chart's limits; the obstacle's coordinates are only evaluated, never planned
  body.workspace_min = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  body.workspace_max = -body.workspace_min;
  for (const Eigen::VectorXd& c : q) {
    body.workspace_min = body.workspace_min.cwiseMin(c.head<3>() - Eigen::Vector3d::Ones());
    body.workspace_max = body.workspace_max.cwiseMax(c.head<3>() + Eigen::Vector3d::Ones());
  }
  body.body.collision = obstacle.shapes;

  CommittedMotion motion;
  motion.id = "moving obstacle '" + obstacle.name + "'";
  motion.placement.name = body.name;
  motion.placement.model = RobotFromMobile(body);
  std::vector<TimedTrajectory::Piece> pieces;
  if (obstacle.times.front() > 0.0) {
    TimedTrajectory::Piece hold;
    hold.duration = obstacle.times.front();
    hold.coefficients = q.front();
    pieces.push_back(std::move(hold));
  }
  for (std::size_t k = 0; k + 1 < q.size(); ++k) {
    TimedTrajectory::Piece piece;
    piece.t0 = obstacle.times[k];
    piece.duration = obstacle.times[k + 1] - obstacle.times[k];
    piece.coefficients.resize(6, 2);
    piece.coefficients.col(0) = q[k];
    piece.coefficients.col(1) = (q[k + 1] - q[k]) / piece.duration;
    pieces.push_back(std::move(piece));
  }
  if (pieces.empty()) {
    TimedTrajectory::Piece stand;
    stand.coefficients = q.front();
    pieces.push_back(std::move(stand));
  }
  motion.trajectory = TimedTrajectory(std::move(pieces), q.back());
  motion.begin = 0.0;
  motion.until = std::numeric_limits<double>::infinity();
  return motion;
}

MovingDisc DiscOfObstacle(const MovingObstacle& obstacle) {
  bool upright = true;
  for (const Eigen::Isometry3d& pose : obstacle.poses) {
    upright = upright && std::abs(pose.linear()(2, 2) - 1.0) <= 1e-9;
  }
  MovingDisc disc;
  disc.name = obstacle.name;
  for (const Shape& shape : obstacle.shapes) {
    const Eigen::Vector3d offset = shape.pose.translation();
    const double reach = upright ? offset.head<2>().norm() : offset.norm();
    disc.radius = std::max(disc.radius, reach + BoundingRadius(shape));
  }
  // An upright cylinder or capsule about z, or a sphere, at the frame's z axis: its true radius.
  if (upright && obstacle.shapes.size() == 1) {
    const Shape& shape = obstacle.shapes.front();
    const bool on_axis = shape.pose.translation().head<2>().norm() == 0.0;
    const bool axis_z = std::abs(shape.pose.linear()(2, 2) - 1.0) <= 1e-12;
    if (on_axis && (shape.type == ShapeType::kSphere || (axis_z && (shape.type == ShapeType::kCylinder ||
                                                                     shape.type == ShapeType::kCapsule)))) {
      disc.radius = shape.radius;
    }
  }
  disc.times = obstacle.times;
  for (const Eigen::Isometry3d& pose : obstacle.poses) disc.centres.push_back(pose.translation().head<2>());
  return disc;
}

}  // namespace chasles
