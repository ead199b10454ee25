#pragma once
/// \file
/// Objects a robot carries (MoveIt's attached collision objects): shapes fixed to a link that
/// move with it in every check. Each object becomes a link of its own, on a fixed joint under the
/// link it is attached to, so the robot's configuration and kinematics are unchanged and the
/// object is checked against the scene and against the robot's other links like any link.

#include <memory>
#include <string>
#include <vector>

#include "chasles/robot/geometry.h"
#include "chasles/robot/robot_model.h"

namespace chasles {

struct AttachedObject {
  std::string name;                      ///< the new link's name: unique among the robot's links
  int link = -1;                         ///< the link it is fixed to
  std::vector<Shape> shapes;             ///< >= 1, poses in `link`'s frame
  std::vector<std::string> touch_links;  ///< robot links it may touch (besides `link`, always)
  /// [kg] >= 0: the load in the dynamics (torques, torque-limited timing); 0 = none. A point mass
  /// at `center_of_mass` (in `link`'s frame): the inertia about it is left at zero.
  double mass = 0.0;
  Eigen::Vector3d center_of_mass = Eigen::Vector3d::Zero();
};

/// `robot` carrying `objects`: a link per object (its shapes as collision geometry; its mass, if
/// any, as the link's inertial),
/// on a fixed joint `<name>_attachment` under its link; allowed pairs: the robot's own, each
/// object with its link and its touch links. Joints, dofs, limits and kind are the robot's.
/// `field` names the objects in errors (e.g. "attached_objects").
/// \throws Error(kInvalidArgument) naming `field[i]` for an empty or duplicate name or one that
///         is a link of the robot, a link index out of range, no shapes, a mass that is not finite
///         and >= 0 or a centre of mass that is not finite, or a touch link the robot lacks (the
///         robot's links listed).
std::shared_ptr<const RobotModel> AttachObjects(const RobotModel& robot, const std::vector<AttachedObject>& objects,
                                                const std::string& field = "attached_objects");

}  // namespace chasles
