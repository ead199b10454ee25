#pragma once
/// \file
/// Obstacles that move along known paths (a person walking by, a cart, another machine's part):
/// planned around in space-time by the coordinator, as committed motions of free-flying bodies
/// that carry the obstacle's shapes.

#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "chasles/multi/coordinator.h"
#include "chasles/multi/velocity_obstacles.h"
#include "chasles/robot/geometry.h"

namespace chasles {

/// An obstacle at poses[k] (its frame in the scene frame) at times[k] [s] (t = 0 = the plan's
/// start). In between, its origin moves linearly and its Z-Y-X Euler angles (yaw, pitch, roll)
/// linearly, each angle by the shorter turn; so a waypoint-to-waypoint turn about one fixed axis
/// is exact when that axis is z (or the tilt is held). Before times.front() it stands at
/// poses.front(), after times.back() at poses.back() for good.
struct MovingObstacle {
  std::string name;
  std::vector<Shape> shapes;            ///< in the obstacle's frame; spheres, boxes, cylinders, capsules
  std::vector<double> times;            ///< [s] at least one, finite, >= 0, strictly increasing
  std::vector<Eigen::Isometry3d> poses; ///< one per time

  /// \throws Error(kInvalidArgument) naming the field (`field` prefix, e.g. `moving_obstacles[1]`):
  /// no shapes, no waypoints, times negative / not increasing / not finite, sizes.
  void Validate(const std::string& field) const;
  /// The pose at time t (the interpolation above).
  Eigen::Isometry3d PoseAt(double t) const;
};

/// The obstacle as a committed motion from t = 0: a free flyer (x, y, z, yaw, pitch, roll) that
/// carries its shapes, linear between waypoints (held at the first pose from 0 to times.front()),
/// standing at its last pose for good (until = +inf). `id` = "moving obstacle 'name'".
/// \throws Error(kInvalidArgument) as Validate.
CommittedMotion MotionOfObstacle(const MovingObstacle& obstacle, const std::string& field);

/// The obstacle as a disc in the plane, for velocity obstacles: centred on its origin's (x, y),
/// radius the farthest extent of its shapes from its frame's z axis (over the poses' tilts,
/// bounded by the shapes' bounding balls: conservative).
MovingDisc DiscOfObstacle(const MovingObstacle& obstacle);

}  // namespace chasles
