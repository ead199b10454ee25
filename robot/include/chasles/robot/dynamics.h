#pragma once
/// \file
/// Rigid-body dynamics of a RobotModel (Lynch & Park, ch. 8): inverse dynamics by recursive
/// Newton–Euler over the kinematic tree, mass matrix, Coriolis/centrifugal and gravity terms,
/// forward dynamics. τ = M(q) q̈ + c(q, q̇) + g(q) + friction + armature. SI units.
///
/// Conventions (every function):
/// - Link inertia is each link's `Inertial` (mass, com and inertia about the com, link frame);
///   links without one are massless. Links behind fixed joints move rigidly with their parent.
/// - Friction of joint i (only when `include_friction`):
///   τ_f,i = damping_i · q̇_i + friction_i · sign(q̇_i), with sign(0) = 0.
///   Armature: M(q) gets armature_i on its diagonal, so InverseDynamics adds armature_i · q̈_i.
///   c(q, q̇) and g(q) never contain friction or armature.
/// - Mimic joints (Joint::mimic) move with the dof that drives them: θ_j = m_j q_d + c_j,
///   θ̇_j = m_j q̇_d, θ̈_j = m_j q̈_d; the generalised force of dof d is Σ m_j τ_j over the joints it
///   drives (virtual work), so M(q) = Aᵀ M_θ A with A(j, d) = m_j, and a mimic joint's damping,
///   friction and armature reach dof d as DofFriction says.
/// - Preconditions (sizes asserted in Debug builds only): every vector has num_dofs()
///   entries and is finite. No function throws; the returned vector/matrix is the only heap
///   allocation of InverseDynamics, MassMatrix, CoriolisTorques and GravityTorques (per-link
///   scratch is thread_local; a robot with mimic joints adds M_θ and A to MassMatrix). All
///   functions are thread-safe.
/// - Cost, 7-DOF Panda on one core: InverseDynamics ≈ 0.6 µs, MassMatrix ≈ 1 µs (composite rigid
///   body algorithm), ForwardDynamics ≈ 2 µs (LDLT), CoriolisMatrix ≈ 15 µs (exact Christoffel
///   symbols from ∂M/∂q via body-Jacobian derivatives; meant for analysis, not inner loops).

#include <Eigen/Core>

#include "chasles/robot/robot_model.h"

namespace chasles {

struct DynamicsOptions {
  Eigen::Vector3d gravity = Eigen::Vector3d(0.0, 0.0, -9.81);  ///< in the base frame [m/s²]
  bool include_friction = true;  ///< joint viscous damping and Coulomb friction from the model
};

/// True when every dof drives (through its own joint or a mimic joint) a body with mass > 0: the
/// joint's child link plus every link attached to that child through fixed joints only (so M(q)
/// is positive definite in practice).
bool HasInertia(const RobotModel& robot);

/// Friction and armature acting on one configuration entry.
struct JointFriction {
  double damping = 0.0;   ///< viscous [N·m·s/rad] or [N·s/m]: τ = damping · q̇
  double friction = 0.0;  ///< Coulomb [N·m] or [N]: τ = friction · sign(q̇)
  double armature = 0.0;  ///< added to M(q)'s diagonal [kg·m²] or [kg]
};
/// What InverseDynamics applies to dof `dof`: over the joints j it drives (its own, m_j = 1, and
/// its mimic joints), damping Σ m_j² damping_j, friction Σ |m_j| friction_j, armature
/// Σ m_j² armature_j. Precondition: 0 <= dof < num_dofs().
JointFriction DofFriction(const RobotModel& robot, int dof);

/// τ for (q, q̇, q̈) by recursive Newton–Euler. All vectors have num_dofs() entries.
Eigen::VectorXd InverseDynamics(const RobotModel& robot, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                                const Eigen::VectorXd& qdd, const DynamicsOptions& options = {});
/// Along a path q(s) with q′ = dq/ds and q″ = d²q/ds², the rigid-body inverse dynamics at path
/// speed ṡ and acceleration s̈ (q̇ = q′ṡ, q̈ = q′s̈ + q″ṡ²) is τ = a·s̈ + b·ṡ² + c, with
/// a = M(q) q′, b = M(q) q″ + C(q, q′) q′ and c = g(q) (armature included, friction not: add
/// DofFriction's terms with q̇ = q′ṡ). One pass over the tree computes all three (the cost of
/// about 1.5 InverseDynamics calls instead of 3).
struct PathTorque {
  Eigen::VectorXd a, b, c;
};
PathTorque PathTorqueCoefficients(const RobotModel& robot, const Eigen::VectorXd& q, const Eigen::VectorXd& dq,
                                  const Eigen::VectorXd& ddq,
                                  const Eigen::Vector3d& gravity = Eigen::Vector3d(0.0, 0.0, -9.81));
/// The same into *out, reusing its vectors (no allocation once they have num_dofs() entries).
void PathTorqueCoefficients(const RobotModel& robot, const Eigen::VectorXd& q, const Eigen::VectorXd& dq,
                            const Eigen::VectorXd& ddq, const Eigen::Vector3d& gravity, PathTorque* out);
/// M(q), symmetric positive definite, including the joint armature on the diagonal.
Eigen::MatrixXd MassMatrix(const RobotModel& robot, const Eigen::VectorXd& q);
/// c(q, q̇) = C(q, q̇) q̇: Coriolis and centrifugal torques.
Eigen::VectorXd CoriolisTorques(const RobotModel& robot, const Eigen::VectorXd& q, const Eigen::VectorXd& qd);
/// C(q, q̇) from the Christoffel symbols, so that Ṁ − 2C is skew-symmetric.
Eigen::MatrixXd CoriolisMatrix(const RobotModel& robot, const Eigen::VectorXd& q, const Eigen::VectorXd& qd);
/// g(q): gravity torques.
Eigen::VectorXd GravityTorques(const RobotModel& robot, const Eigen::VectorXd& q,
                               const Eigen::Vector3d& gravity = Eigen::Vector3d(0.0, 0.0, -9.81));
/// q̈ = M⁻¹ (τ − c − g − friction), M including armature, solved by LDLT. Inverts
/// InverseDynamics with the same options. Precondition: M(q) positive definite (HasInertia).
Eigen::VectorXd ForwardDynamics(const RobotModel& robot, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                                const Eigen::VectorXd& tau, const DynamicsOptions& options = {});

}  // namespace chasles
