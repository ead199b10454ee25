#pragma once
/// \file
/// A joint of a RobotModel: type, frames, limits, friction and, for a URDF <mimic> joint, the
/// joint it follows. SI units and radians.

#include <optional>
#include <string>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace chasles {

enum class JointType { kRevolute, kContinuous, kPrismatic, kFixed };

/// Limits of one joint. Continuous joints get lower = -π, upper = π (the planner does not
/// wrap around; documented in the API).
struct JointLimits {
  double lower = 0.0;     ///< [rad] or [m]
  double upper = 0.0;     ///< [rad] or [m]
  double velocity = 0.0;  ///< > 0 [rad/s] or [m/s]
  double effort = 0.0;    ///< >= 0 [N·m] or [N]; 0 = unknown
};

/// A joint that has no configuration coordinate of its own (URDF `<mimic>`): its value is
/// θ = multiplier · θ_followed + offset, θ_followed the value of joints()[joint].
struct JointMimic {
  int joint = -1;           ///< index into the robot's joints() of the joint it follows
  double multiplier = 1.0;  ///< finite and non-zero
  double offset = 0.0;      ///< [rad] or [m], finite
};

struct Joint {
  std::string name;
  JointType type = JointType::kFixed;
  int parent_link = -1;
  int child_link = -1;
  Eigen::Isometry3d origin = Eigen::Isometry3d::Identity();  ///< child frame in parent frame at q = 0
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();             ///< unit, in the joint (child) frame
  /// For a mimic joint: its own (URDF) limits. RobotModel narrows the followed joint's position
  /// and velocity limits so that the mimic joint stays within them (continuous mimic joints have
  /// no position limits); its effort limit is not enforced.
  JointLimits limits;
  double damping = 0.0;   ///< viscous friction [N·m·s/rad] or [N·s/m], >= 0
  double friction = 0.0;  ///< Coulomb friction [N·m] or [N], >= 0
  double armature = 0.0;  ///< reflected rotor inertia added to M(q)'s diagonal [kg·m²] or [kg], >= 0
  /// Set for a mimic joint (moving joints only). RobotModel resolves chains (a mimic of a mimic):
  /// in a model's joints(), mimic->joint is always an actuated joint and multiplier and offset
  /// are composed along the chain, so θ = multiplier · q[dof] + offset.
  std::optional<JointMimic> mimic;
  /// Index into the configuration vector of the coordinate that drives the joint: its own, or
  /// for a mimic joint the one of the actuated joint it follows; -1 for fixed joints. Set by
  /// RobotModel (any value given is ignored).
  int dof = -1;

  /// dθ/dq[dof] in a model's joints(): the mimic multiplier, 1 for an actuated joint, 0 for a
  /// fixed one.
  double multiplier() const { return dof < 0 ? 0.0 : mimic ? mimic->multiplier : 1.0; }
  /// The joint value θ [rad] or [m] at configuration q, for a joint of a model's joints():
  /// q[dof], multiplier · q[dof] + offset for a mimic joint, 0 for a fixed joint.
  double Position(const Eigen::VectorXd& q) const {
    if (dof < 0) return 0.0;
    return mimic ? mimic->multiplier * q[dof] + mimic->offset : q[dof];
  }
};

}  // namespace chasles
