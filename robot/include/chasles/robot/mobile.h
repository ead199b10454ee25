#pragma once
/// \file
/// Mobile robots: a rigid body moving in the plane (SE(2)), a car-like body with a minimum
/// turning radius (Dubins: forwards only; Reeds–Shepp: forwards and backwards), or a free-flying
/// body in SE(3) (a drone). Each becomes the one internal RobotModel — a chain of prismatic and
/// revolute joints carrying the body — so collision checking, verification and time
/// parameterisation are the same as for arms. RobotModel::kind() tells planners which motions
/// the coordinates allow.
///
/// Configuration coordinates:
///   planar and cars: (x, y, θ) — the body frame's origin [m] and heading about z [rad];
///   free flyer:      (x, y, z, yaw, pitch, roll) — origin [m] and Z-Y-X Euler angles [rad],
///                    R = Rz(yaw) Ry(pitch) Rx(roll); |pitch| and |roll| ≤ max_tilt < π/2, so
///                    the chart of SE(3) never reaches its singularity (a drone never needs it).
/// Headings: planar and free-flyer headings are planned in [-π, π] like continuous joints (a
/// turn from 3 rad to −3 rad goes the long way round). A car's heading is an SO(2) angle in its
/// OMPL state space (Dubins/Reeds–Shepp), unwrapped along the returned path, so its joint range
/// is ±8π (four turns either way).

#include <memory>
#include <string>

#include <Eigen/Core>

#include "chasles/robot/descriptions.h"
#include "chasles/robot/robot_model.h"

namespace chasles {

struct MobileDescription {
  std::string name;                 ///< empty = "mobile_robot"
  RobotKind kind = RobotKind::kPlanar;  ///< kPlanar, kDubinsCar, kReedsSheppCar or kFreeFlyer
  /// Bounds of the body frame's origin [m]; z is ignored for planar robots and cars.
  Eigen::Vector3d workspace_min = Eigen::Vector3d::Zero();
  Eigen::Vector3d workspace_max = Eigen::Vector3d::Zero();
  double turning_radius = 1.0;      ///< cars: minimum turning radius [m] > 0
  double max_tilt = 0.7853981633974483;  ///< free flyer: bound on |pitch| and |roll| [rad], in (0, 1.5]
  double linear_velocity = 1.0;     ///< [m/s] > 0, per translation coordinate
  double angular_velocity = 1.0;    ///< [rad/s] > 0, per rotation coordinate
  LinkProperties body;              ///< collision geometry (and mass) in the body frame
};

/// Builds the model: links `world` (root), one massless intermediate link per coordinate but the
/// last, and `body`; joints named x, y, (z,) theta / yaw, pitch, roll.
/// \throws Error(kInvalidArgument) naming the field (`mobile.` prefix), e.g.
/// `mobile.workspace_min.x = 2 must be < workspace_max.x = 1`,
/// `mobile.turning_radius = 0 must be > 0 for a car`, `mobile.body has no collision geometry`,
/// `mobile.kind must be planar, dubins_car, reeds_shepp_car or free_flyer (got arm)`.
std::shared_ptr<const RobotModel> RobotFromMobile(const MobileDescription& mobile);

}  // namespace chasles
