#pragma once
// Internal: allocation-free forward kinematics of one link along its PoE chain, emitting the
// space-Jacobian column of every chain dof on the way. Shared by kinematics.cc and
// inverse_kinematics.cc.

#include <cmath>
#include <vector>

#include <Eigen/Core>

#include "chasles/robot/robot_model.h"

namespace chasles {
namespace kinematics_internal {

/// e^{[S]θ} for a screw with unit ω (any pitch) or ω = 0 (prismatic, unit v).
inline void ScrewExp(const Eigen::Matrix<double, 6, 1>& s, bool prismatic, double theta,
                     Eigen::Matrix3d* R, Eigen::Vector3d* p) {
  if (prismatic) {
    R->setIdentity();
    *p = s.tail<3>() * theta;
    return;
  }
  const double sn = std::sin(theta), cs = std::cos(theta), vc = 1.0 - cs;
  const double wx = s[0], wy = s[1], wz = s[2];
  const double xyv = wx * wy * vc, xzv = wx * wz * vc, yzv = wy * wz * vc;
  Eigen::Matrix3d& r = *R;
  r(0, 0) = cs + wx * wx * vc;
  r(0, 1) = xyv - wz * sn;
  r(0, 2) = xzv + wy * sn;
  r(1, 0) = xyv + wz * sn;
  r(1, 1) = cs + wy * wy * vc;
  r(1, 2) = yzv - wx * sn;
  r(2, 0) = xzv - wy * sn;
  r(2, 1) = yzv + wx * sn;
  r(2, 2) = cs + wz * wz * vc;
  // p = (Iθ + (1 − cos θ)[ω] + (θ − sin θ)[ω]²) v.
  const Eigen::Vector3d w = s.head<3>();
  const Eigen::Vector3d v = s.tail<3>();
  const Eigen::Vector3d wv = w.cross(v);
  *p = theta * v + vc * wv + (theta - sn) * w.cross(wv);
}

/// Pose (R, p) of `link` at q (q has num_dofs() entries) by the PoE along `chain` (the link's
/// moving joints, root to tip; RobotModel::link_chain). For the j-th chain joint calls
/// column(j, ω_s, v_s) with its space-Jacobian column Ad_{e^{[S_1]θ_1}···e^{[S_{j−1}]θ_{j−1}}} S_j
/// (per unit of its own value θ_j; configuration entry d moves the link at Σ multiplier_j ·
/// column_j over the chain joints j it drives).
template <typename ColumnSink>
inline void ChainForward(const RobotModel& robot, const double* q, const std::vector<int>& chain,
                         int link, Eigen::Matrix3d* R_out, Eigen::Vector3d* p_out,
                         ColumnSink&& column) {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  const int k = static_cast<int>(chain.size());
  for (int j = 0; j < k; ++j) {
    const int m = chain[j];
    const Eigen::Matrix<double, 6, 1>& s = robot.space_screw_axis(m);
    const Joint& joint = robot.joints()[robot.moving_joint(m)];
    const bool prismatic = joint.type == JointType::kPrismatic;
    const Eigen::Vector3d w = R * s.head<3>();
    const Eigen::Vector3d v = p.cross(w) + R * s.tail<3>();
    column(j, w, v);
    if (j + 1 == k && R_out == nullptr) break;
    Eigen::Matrix3d Re;
    Eigen::Vector3d pe;
    const double theta = joint.mimic ? joint.mimic->multiplier * q[joint.dof] + joint.mimic->offset : q[joint.dof];
    ScrewExp(s, prismatic, theta, &Re, &pe);
    p.noalias() += R * pe;
    R = R * Re;
  }
  if (R_out != nullptr) {
    const Eigen::Isometry3d& M = robot.home_pose(link);
    p_out->noalias() = R * M.translation() + p;
    R_out->noalias() = R * M.linear();
  }
}

}  // namespace kinematics_internal
}  // namespace chasles
