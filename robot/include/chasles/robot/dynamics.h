#pragma once
/// \file
/// Rigid-body dynamics of a RobotModel (Lynch & Park, ch. 8): inverse dynamics by recursive
/// Newton–Euler over the kinematic tree, mass matrix, Coriolis/centrifugal and gravity terms,
/// forward dynamics. τ = M(q) q̈ + c(q, q̇) + g(q) + friction + armature. SI units.

#include <Eigen/Core>

#include "chasles/robot/robot_model.h"

namespace chasles {

struct DynamicsOptions {
  Eigen::Vector3d gravity = Eigen::Vector3d(0.0, 0.0, -9.81);  ///< in the base frame [m/s²]
  bool include_friction = true;  ///< joint viscous damping and Coulomb friction from the model
};

/// True when every moving link has a mass > 0 (dynamics are meaningful).
bool HasInertia(const RobotModel& robot);

/// τ for (q, q̇, q̈) by recursive Newton–Euler. All vectors have num_dofs() entries.
Eigen::VectorXd InverseDynamics(const RobotModel& robot, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                                const Eigen::VectorXd& qdd, const DynamicsOptions& options = {});
/// M(q), symmetric positive definite, including the joint armature on the diagonal.
Eigen::MatrixXd MassMatrix(const RobotModel& robot, const Eigen::VectorXd& q);
/// c(q, q̇) = C(q, q̇) q̇: Coriolis and centrifugal torques.
Eigen::VectorXd CoriolisTorques(const RobotModel& robot, const Eigen::VectorXd& q, const Eigen::VectorXd& qd);
/// C(q, q̇) from the Christoffel symbols, so that Ṁ − 2C is skew-symmetric.
Eigen::MatrixXd CoriolisMatrix(const RobotModel& robot, const Eigen::VectorXd& q, const Eigen::VectorXd& qd);
/// g(q): gravity torques.
Eigen::VectorXd GravityTorques(const RobotModel& robot, const Eigen::VectorXd& q,
                               const Eigen::Vector3d& gravity = Eigen::Vector3d(0.0, 0.0, -9.81));
/// q̈ = M⁻¹ (τ − c − g − friction).
Eigen::VectorXd ForwardDynamics(const RobotModel& robot, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                                const Eigen::VectorXd& tau, const DynamicsOptions& options = {});

}  // namespace chasles
