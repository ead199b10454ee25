#pragma once
/// \file
/// Jacobians and manipulability (Lynch & Park, ch. 5). Columns follow the configuration-vector
/// order of the model; columns of joints that do not move the link are zero. Rows are (ω, v).
/// A configuration entry that also drives mimic joints on the link's chain moves the link
/// through each of them: its column is Σ multiplier_j · (column of joint j) over those joints
/// (its own joint with multiplier 1), dθ_j = multiplier_j dq.

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "chasles/robot/lie_group.h"
#include "chasles/robot/robot_model.h"

namespace chasles {

using Jacobian = Eigen::Matrix<double, 6, Eigen::Dynamic>;

/// Space Jacobian J_s(q) of `link`: the twist of the link frame expressed in the base frame,
/// 𝒱_s = J_s q̇. Precondition: q.size() == num_dofs(), 0 <= link < num_links()
/// (\throws Error(kInvalidArgument) otherwise; same for the functions below).
/// Allocates only the returned matrix.
Jacobian SpaceJacobian(const RobotModel& robot, const Eigen::VectorXd& q, int link);
/// Body Jacobian J_b(q) = [Ad_{T_sb^{-1}}] J_s(q) of `link` (twist in the link frame).
Jacobian BodyJacobian(const RobotModel& robot, const Eigen::VectorXd& q, int link);
/// Geometric Jacobian of a point fixed on `link` (`point` in the link frame): rows are the
/// link's angular velocity ω and the point's linear velocity ṗ, both in the base frame.
Jacobian PointJacobian(const RobotModel& robot, const Eigen::VectorXd& q, int link,
                       const Eigen::Vector3d& point);

/// Lever arms of a point fixed on `link` (`point` in the link frame), one per moving joint m
/// (RobotModel::num_moving_joints()): over ALL configurations, the point moves at most
/// levers[m] [m] per unit of the coordinate that drives m (|dθ_m/dq| = |multiplier| included),
/// so |ṗ| <= Σ_m levers[m]·|q̇_dof(m)| along any path. A revolute joint's lever bounds the
/// point's distance from its axis: |a × t| + reach, t the next joint's origin in the joint's
/// frame and reach the bound on the point's distance from that origin (the point's norm in its
/// link frame plus the translations below; a prismatic joint in between adds its largest |θ|
/// over its limits). A prismatic joint's lever is |multiplier|. 0 for joints off the link's chain.
/// 	hrows Error(kInvalidArgument) when link is out of range.
Eigen::VectorXd PointLevers(const RobotModel& robot, int link, const Eigen::Vector3d& point);

/// Angular levers of `link`, one per moving joint: |multiplier| for a revolute joint on the
/// link's chain, else 0, so the link's angular speed |ω| <= Σ_m levers[m]·|q̇_dof(m)|.
Eigen::VectorXd AngularLevers(const RobotModel& robot, int link);

/// Yoshikawa's manipulability √det(J Jᵀ) of a 6×n Jacobian (0 at a singularity).
/// In general the product of the min(6, n) singular values of J: √det(J Jᵀ) for n >= 6 and
/// √det(Jᵀ J) for n < 6 (so an arm with fewer than 6 joints is not identically 0); 0 for n = 0.
/// To measure a task subspace (e.g. planar position), zero the other rows first.
double Manipulability(const Jacobian& J);
/// True when the smallest of the min(6, n) singular values of J is below `tolerance`
/// (J has lost rank; units are those of J's rows). True for n = 0.
bool IsSingular(const Jacobian& J, double tolerance = 1e-6);

}  // namespace chasles
