// Jacobians against finite differences of FK for the three example robots, the UR5 space
// Jacobian against independent computations, manipulability of the planar 2R in closed form,
// and known singularities.
#include "chasles/robot/kinematics.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include <Eigen/SVD>
#include <gtest/gtest.h>

#include "chasles/robot/lie_group.h"
#include "test_util.h"

namespace chasles {
namespace {

using testing::RandomConfiguration;
using testing::TestCases;
using testing::TestSeed;
using testing::Uniform;
using testing::ExpectInvalid;
using testing::LoadExampleRobot;

constexpr double kPi = 3.14159265358979323846;



Eigen::Isometry3d LinkPose(const RobotModel& robot, const Eigen::VectorXd& q, int link) {
  std::vector<Eigen::Isometry3d> poses;
  robot.ForwardKinematics(q, &poses);
  return poses[link];
}

struct RobotCase {
  const char* name;
  const char* tip;
};
const RobotCase kRobots[] = {{"planar_2r", "tool"}, {"ur5", "tool0"}, {"panda", "panda_tcp"}};

TEST(KinematicsTest, JacobiansMatchFiniteDifferencesOfFk) {
  std::mt19937_64 rng(TestSeed(2024u));
  const double h = 1e-6;
  for (const RobotCase& rc : kRobots) {
    const auto robot = LoadExampleRobot(rc.name);
    const int n = robot->num_dofs();
    for (int trial = 0; trial < TestCases(100) / 5 + 1; ++trial) {
      const Eigen::VectorXd q = RandomConfiguration(*robot, rng);
      // Every link, not only the tip: columns of dofs outside the chain must be zero.
      for (int link = 0; link < robot->num_links(); ++link) {
        const Jacobian Js = SpaceJacobian(*robot, q, link);
        const Jacobian Jb = BodyJacobian(*robot, q, link);
        const Eigen::Vector3d point(0.05, -0.1, 0.2);
        const Jacobian Jp = PointJacobian(*robot, q, link, point);
        ASSERT_EQ(Js.cols(), n);
        const Eigen::Isometry3d T = LinkPose(*robot, q, link);
        for (int i = 0; i < n; ++i) {
          Eigen::VectorXd qp = q, qm = q;
          qp[i] += h;
          qm[i] -= h;
          const Eigen::Isometry3d Tp = LinkPose(*robot, qp, link);
          const Eigen::Isometry3d Tm = LinkPose(*robot, qm, link);
          const Vector6d vs = LogSE3(Tp * Tm.inverse()) / (2 * h);
          const Vector6d vb = LogSE3(Tm.inverse() * Tp) / (2 * h);
          const Eigen::Vector3d pdot = ((Tp * point) - (Tm * point)) / (2 * h);
          EXPECT_LT((Js.col(i) - vs).norm(), 1e-6) << rc.name << " link " << link << " dof " << i;
          EXPECT_LT((Jb.col(i) - vb).norm(), 1e-6) << rc.name << " link " << link << " dof " << i;
          EXPECT_LT((Jp.col(i).head<3>() - vs.head<3>()).norm(), 1e-6) << rc.name << " dof " << i;
          EXPECT_LT((Jp.col(i).tail<3>() - pdot).norm(), 1e-6) << rc.name << " dof " << i;
          const bool in_chain = std::find(robot->link_chain(link).begin(),
                                          robot->link_chain(link).end(),
                                          i) != robot->link_chain(link).end();
          if (!in_chain) {
            EXPECT_EQ(Js.col(i).norm(), 0.0);
          }
        }
        // J_s = [Ad_T] J_b.
        EXPECT_LT((Js - Adjoint(T) * Jb).norm(), 1e-12) << rc.name << " link " << link;
      }
    }
  }
}

// UR5 screw axes of Lynch & Park Example 4.5 with the UR5's published dimensions (written here,
// not read from the URDF).
std::vector<Vector6d> Ur5TextbookScrews() {
  const double W1 = 0.10915, L1 = 0.425, L2 = 0.39225, H1 = 0.089159, H2 = 0.09465;
  std::vector<Vector6d> s(6);
  s[0] << 0, 0, 1, 0, 0, 0;
  s[1] << 0, 1, 0, -H1, 0, 0;
  s[2] << 0, 1, 0, -H1, 0, L1;
  s[3] << 0, 1, 0, -H1, 0, L1 + L2;
  s[4] << 0, 0, -1, -W1, L1 + L2, 0;
  s[5] << 0, 1, 0, H2 - H1, 0, L1 + L2;
  return s;
}

TEST(KinematicsTest, Ur5SpaceJacobianMatchesTextbookAndGeometricForms) {
  const auto robot = LoadExampleRobot("ur5");
  const int tool = robot->FindLink("tool0");
  ASSERT_GE(tool, 0);
  Eigen::VectorXd q(6);
  q << 0.3, -1.1, 1.4, -0.6, 0.9, 2.2;
  const Jacobian Js = SpaceJacobian(*robot, q, tool);

  // (1) Textbook: J_si = Ad_{e^[S1]q1 ··· e^[S_{i-1}]q_{i-1}} S_i with the textbook screws.
  const std::vector<Vector6d> S = Ur5TextbookScrews();
  Eigen::Isometry3d prefix = Eigen::Isometry3d::Identity();
  for (int i = 0; i < 6; ++i) {
    const Vector6d expected = Adjoint(prefix) * S[i];
    EXPECT_LT((Js.col(i) - expected).norm(), 1e-12) << "column " << i;
    prefix = prefix * ExpSE3(S[i], q[i]);
  }

  // (2) Geometric: column i = (ω_i, −ω_i × p_i) with the joint axis ω_i and a point p_i on it,
  //     taken from the URDF joint-by-joint chaining (not the PoE).
  std::vector<Eigen::Isometry3d> poses;
  robot->ForwardKinematicsByChaining(q, &poses);
  for (int i = 0; i < 6; ++i) {
    const Joint& joint = robot->joints()[robot->dof_joint(i)];
    const Eigen::Isometry3d& frame = poses[joint.child_link];
    const Eigen::Vector3d w = frame.linear() * joint.axis;
    const Eigen::Vector3d p = frame.translation();
    Vector6d expected;
    expected << w, -w.cross(p);
    EXPECT_LT((Js.col(i) - expected).norm(), 1e-12) << "column " << i;
  }

  // (3) At q = 0 the columns are the screw axes themselves.
  const Jacobian J0 = SpaceJacobian(*robot, Eigen::VectorXd::Zero(6), tool);
  for (int i = 0; i < 6; ++i) EXPECT_LT((J0.col(i) - S[i]).norm(), 1e-12) << "column " << i;
}

TEST(KinematicsTest, Planar2rManipulabilityClosedForm) {
  // Compared quantity: Manipulability of the tool-point Jacobian restricted to the planar
  // position rows (ẋ, ẏ; all other rows zeroed) = |det ∂(x, y)/∂q| = L1 L2 |sin q2|.
  const auto robot = LoadExampleRobot("planar_2r");
  const int tool = robot->FindLink("tool");
  ASSERT_GE(tool, 0);
  const double L1 = 1.0, L2 = 0.8;
  std::mt19937_64 rng(TestSeed(2024u) + 1);
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::VectorXd q = RandomConfiguration(*robot, rng);
    Jacobian J = PointJacobian(*robot, q, tool, Eigen::Vector3d::Zero());
    // The planar arm's ω has only a z component and ṗ no z component.
    EXPECT_LT(J.topRows<2>().norm() + J.row(5).norm(), 1e-12);
    const Eigen::Matrix2d Jxy = J.middleRows<2>(3);
    Eigen::Matrix2d expected;
    expected << -L1 * std::sin(q[0]) - L2 * std::sin(q[0] + q[1]), -L2 * std::sin(q[0] + q[1]),
        L1 * std::cos(q[0]) + L2 * std::cos(q[0] + q[1]), L2 * std::cos(q[0] + q[1]);
    EXPECT_LT((Jxy - expected).norm(), 1e-12);
    J.row(2).setZero();
    EXPECT_NEAR(Manipulability(J), L1 * L2 * std::abs(std::sin(q[1])), 1e-12);
  }
  // Straight arm: the planar position part is singular (the full 6×2 Jacobian is not: the two
  // columns still differ in ṗ while having the same ω).
  Jacobian J = PointJacobian(*robot, Eigen::Vector2d(0.4, 0.0), tool, Eigen::Vector3d::Zero());
  EXPECT_FALSE(IsSingular(J));
  J.row(2).setZero();
  EXPECT_TRUE(IsSingular(J));
  EXPECT_NEAR(Manipulability(J), 0.0, 1e-12);
  J = PointJacobian(*robot, Eigen::Vector2d(0.4, 0.5), tool, Eigen::Vector3d::Zero());
  J.row(2).setZero();
  EXPECT_FALSE(IsSingular(J));
}

TEST(KinematicsTest, Ur5SingularitiesAndFullRankConfigurations) {
  const auto robot = LoadExampleRobot("ur5");
  const int tool = robot->FindLink("tool0");
  // q = 0: arm stretched (elbow singularity, θ3 = 0) and S2, S3, S4, S6 all parallel to y.
  const Jacobian J0 = SpaceJacobian(*robot, Eigen::VectorXd::Zero(6), tool);
  EXPECT_TRUE(IsSingular(J0));
  EXPECT_NEAR(Manipulability(J0), 0.0, 1e-12);
  // Wrist singularity alone: θ5 = 0 aligns the axes of joints 4 and 6.
  Eigen::VectorXd q(6);
  q << 0.3, -1.0, 1.5, -0.4, 0.0, 0.7;
  EXPECT_TRUE(IsSingular(SpaceJacobian(*robot, q, tool)));
  EXPECT_TRUE(IsSingular(BodyJacobian(*robot, q, tool)));
  // Away from singularities: full rank and positive manipulability (space = body, Ad has det 1).
  q << 0.3, -1.0, 1.5, -0.4, 1.2, 0.7;
  const Jacobian Js = SpaceJacobian(*robot, q, tool);
  const Jacobian Jb = BodyJacobian(*robot, q, tool);
  EXPECT_FALSE(IsSingular(Js));
  EXPECT_GT(Manipulability(Js), 1e-3);
  EXPECT_NEAR(Manipulability(Js), Manipulability(Jb), 1e-12);
  // Manipulability is the product of singular values.
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(Js);
  EXPECT_NEAR(Manipulability(Js), svd.singularValues().prod(), 1e-12);
}

TEST(KinematicsTest, PandaRedundantJacobianHasFullRank) {
  const auto robot = LoadExampleRobot("panda");
  const int tcp = robot->FindLink("panda_tcp");
  Eigen::VectorXd q(7);
  q << 0, -0.785, 0, -2.356, 0, 1.571, 0.785;
  const Jacobian J = SpaceJacobian(*robot, q, tcp);
  EXPECT_FALSE(IsSingular(J));
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(J);
  EXPECT_NEAR(Manipulability(J), svd.singularValues().prod(), 1e-12);
}

TEST(KinematicsTest, RootLinkAndEmptyJacobians) {
  const auto robot = LoadExampleRobot("ur5");
  const Jacobian J = SpaceJacobian(*robot, Eigen::VectorXd::Zero(6), robot->root_link());
  EXPECT_EQ(J.cols(), 6);
  EXPECT_EQ(J.norm(), 0.0);
  EXPECT_TRUE(IsSingular(J));
  EXPECT_EQ(Manipulability(J), 0.0);
  EXPECT_TRUE(IsSingular(Jacobian(6, 0)));
  EXPECT_EQ(Manipulability(Jacobian(6, 0)), 0.0);
}

TEST(KinematicsTest, InvalidArgumentsAreNamed) {
  const auto robot = LoadExampleRobot("ur5");
  ExpectInvalid([&] { SpaceJacobian(*robot, Eigen::VectorXd::Zero(5), 1); },
                "SpaceJacobian: q has 5 values, robot 'ur5' has 6 joints");
  ExpectInvalid([&] { BodyJacobian(*robot, Eigen::VectorXd::Zero(6), 12); },
                "BodyJacobian: link = 12 is not a link of robot 'ur5' (8 links)");
  ExpectInvalid([&] { PointJacobian(*robot, Eigen::VectorXd::Zero(6), -1, Eigen::Vector3d::Zero()); },
                "PointJacobian: link = -1 is not a link of robot 'ur5' (8 links)");
}

}  // namespace
}  // namespace chasles
