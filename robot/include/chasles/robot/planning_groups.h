#pragma once
/// \file
/// SRDF planning groups (MoveIt's semantics) and planning for one group: the robot with every
/// other joint held where it is.

#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "chasles/robot/robot_model.h"

namespace chasles {

/// A named set of the robot's joints that move together, e.g. "left_arm".
struct PlanningGroup {
  std::string name;
  /// Configuration indices of the group's joints, ascending (the robot's joint order). Fixed
  /// joints have none; a mimic joint counts as the joint it follows.
  std::vector<int> dofs;
};

/// The `<group>` elements of an SRDF, read against `robot` as MoveIt reads them: a group is the
/// joints it names (`<joint name>`), the joints between each `<chain base_link tip_link>`'s
/// links, the parent joint of each `<link name>`, and the joints of each `<group name>` it
/// includes (defined anywhere in the file; cycles refused). An entry naming a joint, link or
/// group the robot or file lacks is skipped with a warning in *warnings (as
/// `disable_collisions` pairs are), an error when `strict`; a group left with no joint is
/// skipped with a warning too.
/// \throws Error(kInvalidArgument) naming the element for malformed XML, a group without a
///         name, two groups of one name, a chain whose base is not an ancestor of its tip, a cycle
///         of groups, or (strict) an unknown name.
std::vector<PlanningGroup> ReadPlanningGroups(const RobotModel& robot, std::string_view srdf, bool strict,
                                              std::vector<std::string>* warnings);

/// The robot planning only the joints `dofs` (configuration indices, ascending): every other
/// joint held fixed where `q` puts it (with the mimic joints that follow it), so the model's
/// configuration is those joints in the robot's order. Links, shapes, inertias, allowed pairs, kind and name are the robot's.
/// \throws Error(kInvalidArgument) when q has the wrong size or a dof is out of range or repeated.
std::shared_ptr<const RobotModel> HoldJointsOutside(const RobotModel& robot, const std::vector<int>& dofs,
                                                    const Eigen::VectorXd& q);

}  // namespace chasles
