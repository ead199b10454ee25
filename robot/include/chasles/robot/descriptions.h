#pragma once
/// \file
/// Robot descriptions besides URDF: a Denavit–Hartenberg table (standard or modified
/// convention) and a product-of-exponentials screw list (Lynch & Park, ch. 4). Both build the
/// one internal RobotModel, so everything downstream (FK, collision, planning, dynamics) is
/// the same whichever description a user sends.

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "chasles/robot/geometry.h"
#include "chasles/robot/input_limits.h"
#include "chasles/robot/lie_group.h"
#include "chasles/robot/robot_model.h"

namespace chasles {

/// Geometry and mass of one link, given in that link's frame (DH frame i, or for PoE the
/// frame whose home pose the description gives).
struct LinkProperties {
  std::vector<Shape> collision;
  std::optional<Inertial> inertial;
};

enum class DhConvention {
  kStandard,  ///< distal (Denavit–Hartenberg 1955): T_i = Rz(θ) Tz(d) Tx(a) Rx(α); joint i about z_{i−1}
  kModified,  ///< proximal (Craig): T_i = Rx(α_{i−1}) Tx(a_{i−1}) Rz(θ) Tz(d); joint i about z_i
};

struct DhJoint {
  std::string name;                 ///< empty = "joint<i+1>"
  JointType type = JointType::kRevolute;  ///< revolute, continuous or prismatic
  double a = 0.0;                   ///< [m]
  double alpha = 0.0;               ///< [rad]
  double d = 0.0;                   ///< [m]; offset for prismatic joints
  double theta_offset = 0.0;        ///< [rad]; θ = q + offset for revolute joints
  JointLimits limits;
  double damping = 0.0, friction = 0.0, armature = 0.0;  ///< see Joint
  LinkProperties link;              ///< of the link this joint moves, in DH frame i
};

struct DhDescription {
  std::string name;
  DhConvention convention = DhConvention::kStandard;
  std::vector<DhJoint> joints;
  Eigen::Isometry3d base = Eigen::Isometry3d::Identity();  ///< DH frame 0 in the robot base frame
  Eigen::Isometry3d tool = Eigen::Isometry3d::Identity();  ///< tool frame in the last DH frame
  LinkProperties base_link;         ///< geometry of the fixed base, in the robot base frame
  std::vector<std::pair<std::string, std::string>> allowed_collisions;
};

struct PoeJoint {
  std::string name;                 ///< empty = "joint<i+1>"
  JointType type = JointType::kRevolute;
  /// Screw axis (ω, v): in the space frame at home when PoeDescription::body_frame is false,
  /// else in the end-effector frame at home (B_i). Revolute: ‖ω‖ = 1. Prismatic: ω = 0, ‖v‖ = 1.
  Vector6d screw = Vector6d::Zero();
  JointLimits limits;
  double damping = 0.0, friction = 0.0, armature = 0.0;
  /// Home pose of this joint's link frame in the space frame (the frame `link` is given in).
  /// Absent: a frame with the base's orientation at the point of the axis nearest the origin.
  std::optional<Eigen::Isometry3d> link_home;
  LinkProperties link;
};

struct PoeDescription {
  std::string name;
  Eigen::Isometry3d home = Eigen::Isometry3d::Identity();  ///< M: end-effector pose at q = 0
  bool body_frame = false;          ///< screws are body axes B_i (S_i = [Ad_M] B_i)
  std::vector<PoeJoint> joints;
  LinkProperties base_link;
  std::vector<std::pair<std::string, std::string>> allowed_collisions;
};

/// Builds the model; the end-effector link is called "tool" (DH: tool frame; PoE: M).
/// Links: `base_link` (root), `link1`…`linkn`, `tool` (fixed joint `tool_joint`); joint names
/// default to `joint<i+1>`. Internal link frames sit on their joint axes, and link geometry and
/// inertia are converted into them: modified DH: link i = DH frame i; standard DH: link i =
/// DH frame i−1 · Rz(θ_off + q_i) Tz(d_i), so DH frame i = link i · Tx(a_i) Rx(α_i); PoE: link i
/// has link_home's orientation, at the foot of the perpendicular from link_home's origin to the
/// axis (revolute) or at link_home (prismatic). The `tool` pose is exactly the DH product
/// base · T_1 ··· T_n · tool, or e^[S1]q1 ··· e^[Sn]qn M.
/// \throws Error(kInvalidArgument) naming the field, e.g.
/// `poe.joints[2].screw: |ω| = 0.5 must be 1 for a revolute joint`,
/// `poe.joints[1].screw: ω = 0 and |v| = 2 must be 1 for a prismatic joint`,
/// `poe.home is not in SE(3): rotation part has det = -1`, `dh.joints[0].limits lower = 2 > upper = 1`,
/// `dh.joints[1].link.inertial inertia = (ixx 1, iyy -2, …) has principal moment -2; principal moments must be >= 0 …`.
/// \throws Error(kResourceExhausted) when the joints are more than `limits.max_dofs` or the
///         links (joints + 2) more than `limits.max_links`.
std::shared_ptr<const RobotModel> RobotFromDh(const DhDescription& dh, const InputLimits& limits = {});
std::shared_ptr<const RobotModel> RobotFromPoe(const PoeDescription& poe, const InputLimits& limits = {});

}  // namespace chasles
