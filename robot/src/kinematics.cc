#include "chasles/robot/kinematics.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <Eigen/SVD>

#include "chasles/robot/error.h"
#include "kinematics_internal.h"

namespace chasles {

namespace {

void CheckArguments(const RobotModel& robot, const Eigen::VectorXd& q, int link,
                    const char* function) {
  if (q.size() != robot.num_dofs()) {
    ThrowInvalid(std::string(function) + ": q has " + std::to_string(q.size()) +
                 " values, robot '" + robot.name() + "' has " + std::to_string(robot.num_dofs()) +
                 " joints");
  }
  if (link < 0 || link >= robot.num_links()) {
    ThrowInvalid(std::string(function) + ": link = " + std::to_string(link) +
                 " is not a link of robot '" + robot.name() + "' (" +
                 std::to_string(robot.num_links()) + " links)");
  }
}

// Fills J (already 6×n and zeroed) with the space Jacobian; returns the link pose if asked.
// Column d sums multiplier × column over the chain joints that dof d drives (its own joint and
// its mimic joints): dθ_j = multiplier_j dq_d.
void FillSpaceJacobian(const RobotModel& robot, const Eigen::VectorXd& q, int link, Jacobian* J,
                       Eigen::Matrix3d* R, Eigen::Vector3d* p) {
  const std::vector<int>& chain = robot.link_chain(link);
  kinematics_internal::ChainForward(
      robot, q.data(), chain, link, R, p,
      [&](int j, const Eigen::Vector3d& w, const Eigen::Vector3d& v) {
        const Joint& joint = robot.joints()[robot.moving_joint(chain[j])];
        if (joint.mimic) {
          J->col(joint.dof).head<3>() += joint.mimic->multiplier * w;
          J->col(joint.dof).tail<3>() += joint.mimic->multiplier * v;
        } else {
          J->col(joint.dof).head<3>() += w;
          J->col(joint.dof).tail<3>() += v;
        }
      });
}

}  // namespace

Jacobian SpaceJacobian(const RobotModel& robot, const Eigen::VectorXd& q, int link) {
  CheckArguments(robot, q, link, "SpaceJacobian");
  Jacobian J = Jacobian::Zero(6, robot.num_dofs());
  FillSpaceJacobian(robot, q, link, &J, nullptr, nullptr);
  return J;
}

Jacobian BodyJacobian(const RobotModel& robot, const Eigen::VectorXd& q, int link) {
  CheckArguments(robot, q, link, "BodyJacobian");
  Jacobian J = Jacobian::Zero(6, robot.num_dofs());
  Eigen::Matrix3d R;
  Eigen::Vector3d p;
  FillSpaceJacobian(robot, q, link, &J, &R, &p);
  // [Ad_{T⁻¹}] (ω, v) = (Rᵀω, Rᵀ(v − p × ω)), column by column in place (zero columns stay 0).
  for (int d = 0; d < robot.num_dofs(); ++d) {
    const Eigen::Vector3d w = J.col(d).head<3>();
    const Eigen::Vector3d v = J.col(d).tail<3>();
    J.col(d).head<3>().noalias() = R.transpose() * w;
    J.col(d).tail<3>().noalias() = R.transpose() * (v - p.cross(w));
  }
  return J;
}

Jacobian PointJacobian(const RobotModel& robot, const Eigen::VectorXd& q, int link,
                       const Eigen::Vector3d& point) {
  CheckArguments(robot, q, link, "PointJacobian");
  Jacobian J = Jacobian::Zero(6, robot.num_dofs());
  Eigen::Matrix3d R;
  Eigen::Vector3d p;
  FillSpaceJacobian(robot, q, link, &J, &R, &p);
  // ṗ = v_s + ω_s × p_world for the point's position p_world in the base frame.
  const Eigen::Vector3d x = R * point + p;
  for (int d = 0; d < robot.num_dofs(); ++d) {
    const Eigen::Vector3d w = J.col(d).head<3>();
    J.col(d).tail<3>() += w.cross(x);
  }
  return J;
}

double Manipulability(const Jacobian& J) {
  const Eigen::Index n = J.cols();
  if (n == 0) return 0.0;
  double det;
  if (n >= 6) {
    const Matrix6d G = J * J.transpose();
    det = G.determinant();
  } else {
    const Eigen::MatrixXd G = J.transpose() * J;
    det = G.determinant();
  }
  return std::sqrt(std::max(det, 0.0));
}

bool IsSingular(const Jacobian& J, double tolerance) {
  if (J.cols() == 0) return true;
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(J);
  const Eigen::VectorXd& s = svd.singularValues();  // min(6, n) values, descending
  return s[s.size() - 1] < tolerance;
}

Eigen::VectorXd PointLevers(const RobotModel& robot, int link, const Eigen::Vector3d& point) {
  if (link < 0 || link >= robot.num_links()) {
    ThrowInvalid("PointLevers: link = " + std::to_string(link) + " must be within [0, " +
                 std::to_string(robot.num_links() - 1) + "]");
  }
  // Walking up from the point's link, in the child frame F of each joint J the point is
  // x = t + v: t the translation of the joint below (its origin in F; at the point's own link,
  // t = the point and v = 0), |v| <= reach. J turns x about its axis a through F's origin at
  // |a × x| <= |a × t| + reach per radian, never more than the distance bound |t| + reach.
  Eigen::VectorXd levers = Eigen::VectorXd::Zero(robot.num_moving_joints());
  Eigen::Vector3d t = point;
  double reach = 0.0;
  for (int l = link; robot.links()[l].parent_joint >= 0;) {
    const int ji = robot.links()[l].parent_joint;
    const Joint& j = robot.joints()[ji];
    const int m = robot.moving_index(ji);
    double dist = t.norm() + reach;  // bound on the point's distance from F's origin
    if (m >= 0) {
      const double scale = j.mimic ? std::abs(j.mimic->multiplier) : 1.0;  // |dθ/dq|
      if (j.type == JointType::kPrismatic) {
        levers[m] += scale;
        // |θ| over the dof's limits (θ = m·q + c is monotone in q, also as rounded).
        const double lo = robot.lower_limits()[j.dof], hi = robot.upper_limits()[j.dof];
        const double travel = j.mimic ? std::max(std::abs(j.mimic->multiplier * lo + j.mimic->offset),
                                                 std::abs(j.mimic->multiplier * hi + j.mimic->offset))
                                      : std::max(std::abs(lo), std::abs(hi));
        dist += std::isfinite(travel) ? travel : std::numeric_limits<double>::infinity();
      } else {
        levers[m] += scale * std::min(dist, j.axis.normalized().cross(t).norm() + reach);
      }
    }
    t = j.origin.translation();
    reach = dist;
    l = j.parent_link;
  }
  return levers;
}

Eigen::VectorXd AngularLevers(const RobotModel& robot, int link) {
  if (link < 0 || link >= robot.num_links()) {
    ThrowInvalid("AngularLevers: link = " + std::to_string(link) + " must be within [0, " +
                 std::to_string(robot.num_links() - 1) + "]");
  }
  Eigen::VectorXd levers = Eigen::VectorXd::Zero(robot.num_moving_joints());
  for (const int m : robot.link_chain(link)) {
    const Joint& j = robot.joints()[robot.moving_joint(m)];
    if (j.type != JointType::kPrismatic) levers[m] = std::abs(j.multiplier());
  }
  return levers;
}

}  // namespace chasles
