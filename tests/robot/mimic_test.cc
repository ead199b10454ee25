// Mimic joints (URDF <mimic>): FK, Jacobians, IK and dynamics of robots with mimic joints
// against independent references — the same robot written WITHOUT <mimic> (every joint its own
// coordinate) evaluated at the expanded configuration θ = m·q + c (the expansion written out
// here from the robot's description, not taken from the model), and finite differences of FK
// and of the dynamics. Robots: a small arm with a revolute mimic (multiplier 2, offset 0.1)
// downstream of the joint it follows on a skew axis, a gripper whose second finger is a
// prismatic mimic (multiplier -1, offset 0.01) listed before the finger it follows, and a
// mimic of that mimic (a chain); and examples/robots/dual_arm.urdf.

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <regex>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "chasles/robot/dynamics.h"
#include "chasles/robot/inverse_kinematics.h"
#include "chasles/robot/kinematics.h"
#include "chasles/robot/lie_group.h"
#include "test_util.h"

namespace chasles {
namespace {

using testing::ReadExample;
using testing::TestCases;
using testing::TestSeed;
using testing::Uniform;

/// θ_joint = multiplier · q[follows] + offset, `follows` an actuated joint (chains composed by hand).
struct MimicOf {
  std::string joint, follows;
  double multiplier, offset;
};

struct MimicCase {
  std::string name;
  std::string urdf;              // with <mimic>
  std::vector<MimicOf> mimics;   // the expansion, written out independently
};

/// A 4-joint arm with a gripper. Every link has inertia; joints have friction.
std::string CoupledArmUrdf() {
  const auto inertial = [](double m, const char* com, double i) {
    return std::string("<inertial><origin xyz=\"") + com + "\"/><mass value=\"" + std::to_string(m) +
           "\"/><inertia ixx=\"" + std::to_string(i) + "\" ixy=\"0\" ixz=\"0\" iyy=\"" + std::to_string(1.3 * i) +
           "\" iyz=\"0\" izz=\"" + std::to_string(0.8 * i) + "\"/></inertial>";
  };
  std::string s = "<?xml version=\"1.0\"?>\n<robot name=\"coupled\">\n";
  s += "<link name=\"base\"/>\n";
  s += "<link name=\"l1\">" + inertial(3.0, "0.02 0.01 0.1", 0.05) + "</link>\n";
  s += "<link name=\"l2\">" + inertial(2.0, "0.2 0 0.01", 0.03) + "</link>\n";
  s += "<link name=\"l3\">" + inertial(1.5, "0.15 -0.02 0", 0.02) + "</link>\n";
  s += "<link name=\"hand\">" + inertial(0.7, "0.03 0 0.01", 0.004) + "</link>\n";
  s += "<link name=\"finger_a\">" + inertial(0.1, "0.02 0.01 0", 0.0002) + "</link>\n";
  s += "<link name=\"finger_b\">" + inertial(0.12, "0.02 -0.01 0", 0.0002) + "</link>\n";
  s += "<link name=\"tip\">" + inertial(0.05, "0.01 0 0", 0.0001) + "</link>\n";
  s += R"(<joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>
  <origin xyz="0 0 0.3"/><axis xyz="0 0 1"/><limit lower="-2.5" upper="2.5" velocity="2" effort="50"/>
  <dynamics damping="0.3" friction="0.2"/></joint>
<joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/>
  <origin xyz="0.1 0 0.2" rpy="0.3 0 0"/><axis xyz="0 1 0"/><limit lower="-1" upper="1" velocity="2" effort="50"/>
  <dynamics damping="0.2" friction="0.1"/></joint>
<joint name="j3" type="revolute"><parent link="l2"/><child link="l3"/>
  <origin xyz="0.4 0 0" rpy="0 0.2 -0.1"/><axis xyz="0 1 1"/><limit lower="-2.5" upper="2.5" velocity="5" effort="30"/>
  <dynamics damping="0.15" friction="0.05"/>
  <mimic joint="j2" multiplier="2" offset="0.1"/></joint>
<joint name="j4" type="continuous"><parent link="l3"/><child link="hand"/>
  <origin xyz="0.3 0 0"/><axis xyz="1 0 0"/><limit velocity="3" effort="10"/></joint>
<joint name="finger_b_joint" type="prismatic"><parent link="hand"/><child link="finger_b"/>
  <origin xyz="0.08 -0.01 0"/><axis xyz="0 1 0"/><limit lower="-0.05" upper="0.05" velocity="0.2" effort="20"/>
  <dynamics damping="4" friction="0.5"/>
  <mimic joint="finger_a_joint" multiplier="-1" offset="0.01"/></joint>
<joint name="finger_a_joint" type="prismatic"><parent link="hand"/><child link="finger_a"/>
  <origin xyz="0.08 0.01 0"/><axis xyz="0 1 0"/><limit lower="0" upper="0.04" velocity="0.2" effort="20"/>
  <dynamics damping="3" friction="0.4"/></joint>
<joint name="tip_joint" type="prismatic"><parent link="finger_a"/><child link="tip"/>
  <origin xyz="0.04 0 0" rpy="0 0 0.4"/><axis xyz="1 0 0"/><limit lower="-0.02" upper="0.02" velocity="0.2" effort="5"/>
  <dynamics damping="1" friction="0.1"/>
  <mimic joint="finger_b_joint" multiplier="0.5" offset="0.002"/></joint>
</robot>
)";
  return s;
}

std::vector<MimicCase> Cases() {
  return {
      {"coupled",
       CoupledArmUrdf(),
       // tip = 0.5 · finger_b + 0.002 = 0.5 · (−finger_a + 0.01) + 0.002 = −0.5 · finger_a + 0.007.
       {{"j3", "j2", 2.0, 0.1}, {"finger_b_joint", "finger_a_joint", -1.0, 0.01}, {"tip_joint", "finger_a_joint", -0.5, 0.007}}},
      {"dual_arm",
       ReadExample("robots/dual_arm.urdf"),
       {{"left_finger_b_joint", "left_finger_joint", -1.0, 0.0}, {"right_finger_b_joint", "right_finger_joint", -1.0, 0.0}}},
  };
}

/// The mimic robot and the same description with every <mimic> removed.
struct Pair {
  std::shared_ptr<const RobotModel> mimic, expanded;
  std::vector<MimicOf> table;
  /// A (expanded dofs × mimic dofs): θ̇ = A q̇.
  Eigen::MatrixXd A;
  /// θ at q: the expanded robot's configuration.
  Eigen::VectorXd Expand(const Eigen::VectorXd& q) const {
    Eigen::VectorXd theta = A * q;
    for (int e = 0; e < theta.size(); ++e) {
      for (const MimicOf& m : table) {
        if (m.joint == expanded->dof_names()[e]) theta[e] = m.multiplier * q[Dof(m.follows)] + m.offset;
      }
    }
    return theta;
  }
  int Dof(const std::string& name) const {
    const auto& names = mimic->dof_names();
    const auto it = std::find(names.begin(), names.end(), name);
    EXPECT_NE(it, names.end()) << name;
    return static_cast<int>(it - names.begin());
  }
};

Pair MakePair(const MimicCase& c) {
  Pair p;
  p.mimic = RobotModel::FromUrdf(c.urdf);
  p.expanded = RobotModel::FromUrdf(std::regex_replace(c.urdf, std::regex("<mimic[^>]*/>"), ""));
  p.table = c.mimics;
  EXPECT_EQ(p.expanded->num_dofs(), p.mimic->num_dofs() + static_cast<int>(c.mimics.size())) << c.name;
  p.A = Eigen::MatrixXd::Zero(p.expanded->num_dofs(), p.mimic->num_dofs());
  for (int e = 0; e < p.expanded->num_dofs(); ++e) {
    const std::string& name = p.expanded->dof_names()[e];
    bool is_mimic = false;
    for (const MimicOf& m : c.mimics) {
      if (m.joint == name) {
        p.A(e, p.Dof(m.follows)) = m.multiplier;
        is_mimic = true;
      }
    }
    if (!is_mimic) p.A(e, p.Dof(name)) = 1.0;
  }
  return p;
}

Eigen::VectorXd Random(const RobotModel& robot, std::mt19937_64& rng) {
  return testing::RandomConfiguration(robot, rng);
}
Eigen::VectorXd RandomVector(int n, double scale, std::mt19937_64& rng) {
  Eigen::VectorXd v(n);
  for (int i = 0; i < n; ++i) v[i] = scale * (2.0 * Uniform(rng) - 1.0);
  return v;
}

double PoseError(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return (a.matrix() - b.matrix()).cwiseAbs().maxCoeff();
}

TEST(MimicKinematics, TheModelHasOneCoordinatePerActuatedJoint) {
  const Pair p = MakePair(Cases()[0]);
  const RobotModel& r = *p.mimic;
  EXPECT_EQ(r.dof_names(), (std::vector<std::string>{"j1", "j2", "j4", "finger_a_joint"}));
  EXPECT_EQ(r.num_moving_joints(), 7);
  EXPECT_TRUE(r.has_mimic_joints());
  EXPECT_TRUE(r.load_warnings().empty());
  // The chain tip -> finger_b -> finger_a is resolved and composed.
  for (const MimicOf& m : p.table) {
    int j = -1;
    for (std::size_t k = 0; k < r.joints().size(); ++k) {
      if (r.joints()[k].name == m.joint) j = static_cast<int>(k);
    }
    ASSERT_GE(j, 0);
    const Joint& joint = r.joints()[j];
    ASSERT_TRUE(joint.mimic.has_value()) << m.joint;
    EXPECT_EQ(r.joints()[joint.mimic->joint].name, m.follows);
    EXPECT_DOUBLE_EQ(joint.mimic->multiplier, m.multiplier) << m.joint;
    EXPECT_NEAR(joint.mimic->offset, m.offset, 1e-15) << m.joint;
    EXPECT_EQ(joint.dof, p.Dof(m.follows));
    EXPECT_EQ(joint.multiplier(), m.multiplier);
  }
  // The actuated joints' limits are the URDF's (every mimic fits within its own over them).
  EXPECT_EQ(r.lower_limits()[1], -1.0);
  EXPECT_EQ(r.upper_limits()[1], 1.0);
  EXPECT_EQ(r.lower_limits()[3], 0.0);
  EXPECT_EQ(r.upper_limits()[3], 0.04);
}

TEST(MimicKinematics, FkEqualsTheRobotWithoutMimicAtTheExpandedConfiguration) {
  std::mt19937_64 rng(TestSeed(31));
  for (const MimicCase& c : Cases()) {
    const Pair p = MakePair(c);
    ASSERT_EQ(p.mimic->num_links(), p.expanded->num_links());
    std::vector<Eigen::Isometry3d> poe, chained, reference;
    double moved = 0.0;  // the mimic joints do move the links (not a vacuous comparison)
    for (int trial = 0; trial < TestCases(200); ++trial) {
      const Eigen::VectorXd q = Random(*p.mimic, rng);
      const Eigen::VectorXd theta = p.Expand(q);
      p.mimic->ForwardKinematics(q, &poe);
      p.mimic->ForwardKinematicsByChaining(q, &chained);
      p.expanded->ForwardKinematics(theta, &reference);
      std::vector<Eigen::Isometry3d> independent;
      p.expanded->ForwardKinematics(p.A * q, &independent);  // the mimic offsets left out
      for (int l = 0; l < p.mimic->num_links(); ++l) {
        ASSERT_EQ(p.mimic->links()[l].name, p.expanded->links()[l].name);
        EXPECT_LT(PoseError(poe[l], reference[l]), 1e-12) << c.name << " link " << p.mimic->links()[l].name;
        EXPECT_LT(PoseError(chained[l], reference[l]), 1e-12) << c.name << " link " << p.mimic->links()[l].name;
        moved = std::max(moved, PoseError(independent[l], reference[l]));
      }
    }
    if (c.name == "coupled") {
      EXPECT_GT(moved, 1e-3) << "the offsets must matter";
    }
  }
}

TEST(MimicKinematics, JacobiansMatchFiniteDifferencesOfFk) {
  std::mt19937_64 rng(TestSeed(37));
  const double h = 1e-6;
  for (const MimicCase& c : Cases()) {
    const Pair p = MakePair(c);
    const RobotModel& robot = *p.mimic;
    const int n = robot.num_dofs();
    std::vector<Eigen::Isometry3d> poses, plus, minus;
    for (int trial = 0; trial < TestCases(100) / 5 + 1; ++trial) {
      const Eigen::VectorXd q = Random(robot, rng);
      robot.ForwardKinematics(q, &poses);
      for (int link = 0; link < robot.num_links(); ++link) {
        const Jacobian Js = SpaceJacobian(robot, q, link);
        const Jacobian Jb = BodyJacobian(robot, q, link);
        const Eigen::Vector3d point(0.05, -0.1, 0.2);
        const Jacobian Jp = PointJacobian(robot, q, link, point);
        ASSERT_EQ(Js.cols(), n);
        for (int i = 0; i < n; ++i) {
          Eigen::VectorXd qp = q, qm = q;
          qp[i] += h;
          qm[i] -= h;
          robot.ForwardKinematics(qp, &plus);
          robot.ForwardKinematics(qm, &minus);
          const Eigen::Isometry3d& Tp = plus[link];
          const Eigen::Isometry3d& Tm = minus[link];
          const Vector6d vs = LogSE3(Tp * Tm.inverse()) / (2 * h);
          const Vector6d vb = LogSE3(Tm.inverse() * Tp) / (2 * h);
          const Eigen::Vector3d pdot = ((Tp * point) - (Tm * point)) / (2 * h);
          const std::string where = c.name + " link " + robot.links()[link].name + " dof " + robot.dof_names()[i];
          EXPECT_LT((Js.col(i) - vs).norm(), 1e-6) << where;
          EXPECT_LT((Jb.col(i) - vb).norm(), 1e-6) << where;
          EXPECT_LT((Jp.col(i).head<3>() - vs.head<3>()).norm(), 1e-6) << where;
          EXPECT_LT((Jp.col(i).tail<3>() - pdot).norm(), 1e-6) << where;
        }
        EXPECT_LT((Js - Adjoint(poses[link]) * Jb).norm(), 1e-12) << c.name << " link " << link;
        // The chain rule against the robot without mimic: J = J_θ A.
        const Jacobian Je = SpaceJacobian(*p.expanded, p.Expand(q), link);
        EXPECT_LT((Js - Je * p.A).norm(), 1e-12) << c.name << " link " << link;
      }
    }
  }
}

TEST(MimicKinematics, IkReachesPosesOfLinksMovedByMimicJoints) {
  const Pair p = MakePair(Cases()[0]);
  const RobotModel& robot = *p.mimic;
  std::mt19937_64 rng(TestSeed(41));
  std::vector<Eigen::Isometry3d> poses;
  int solved = 0;
  const int trials = 20;
  for (int trial = 0; trial < trials; ++trial) {
    const Eigen::VectorXd q = Random(robot, rng);
    robot.ForwardKinematics(q, &poses);
    IkRequest request;
    request.link = robot.FindLink("tip");  // moved by j2 directly and through j3, and by finger_a twice
    request.target = poses[request.link];
    request.time_budget = 0.5;
    request.seed = trial + 1;
    const IkResult result = SolveIk(robot, request);
    if (result.solutions.empty()) continue;
    ++solved;
    const Eigen::VectorXd& s = result.solutions[0];
    p.expanded->ForwardKinematics(p.Expand(s), &poses);  // checked on the robot without mimic
    EXPECT_LT((poses[request.link].translation() - request.target.translation()).norm(), request.position_tolerance);
    EXPECT_LT(LogSO3(poses[request.link].linear().transpose() * request.target.linear()).norm(),
              request.orientation_tolerance);
    for (int d = 0; d < robot.num_dofs(); ++d) {
      EXPECT_GE(s[d], robot.lower_limits()[d]);
      EXPECT_LE(s[d], robot.upper_limits()[d]);
    }
  }
  // 4 coordinates for a 6-d pose: reachable targets (generated by FK) only, and IK finds them.
  EXPECT_GE(solved, trials * 9 / 10);
}

/// The pair with armature on every moving joint (the URDF has none), rebuilt through FromTree
/// (the mimic robot from its own, already resolved joints).
Pair WithArmature(Pair p) {
  const auto rebuild = [](const RobotModel& r) {
    std::vector<Joint> joints = r.joints();
    for (std::size_t j = 0; j < joints.size(); ++j) {
      if (joints[j].type != JointType::kFixed) joints[j].armature = 0.01 * static_cast<double>(j + 1);
    }
    return RobotModel::FromTree(r.name(), r.links(), joints);
  };
  p.mimic = rebuild(*p.mimic);
  p.expanded = rebuild(*p.expanded);
  return p;
}

TEST(MimicDynamics, TorquesAreTheRobotWithoutMimicsMappedByTheMultipliers) {
  // By virtual work the force on dof d is Σ m_j τ_j over the joints it drives: τ = Aᵀ τ_θ at
  // θ = expanded q, θ̇ = A q̇, θ̈ = A q̈, friction (viscous and Coulomb) and armature included.
  std::mt19937_64 rng(TestSeed(43));
  for (const MimicCase& c : Cases()) {
    const Pair p = WithArmature(MakePair(c));
    ASSERT_TRUE(HasInertia(*p.mimic));
    const int n = p.mimic->num_dofs();
    for (int trial = 0; trial < TestCases(100) / 2; ++trial) {
      const Eigen::VectorXd q = Random(*p.mimic, rng);
      const Eigen::VectorXd qd = RandomVector(n, 1.5, rng);
      const Eigen::VectorXd qdd = RandomVector(n, 3.0, rng);
      const Eigen::VectorXd theta = p.Expand(q);
      const Eigen::VectorXd thetad = p.A * qd, thetadd = p.A * qdd;
      const Eigen::VectorXd tau = InverseDynamics(*p.mimic, q, qd, qdd);
      const Eigen::VectorXd expected = p.A.transpose() * InverseDynamics(*p.expanded, theta, thetad, thetadd);
      const double scale = 1.0 + expected.cwiseAbs().maxCoeff();
      EXPECT_LT((tau - expected).cwiseAbs().maxCoeff(), 1e-12 * scale) << c.name << " trial " << trial;
      const Eigen::MatrixXd M = MassMatrix(*p.mimic, q);
      const Eigen::MatrixXd Me = p.A.transpose() * MassMatrix(*p.expanded, theta) * p.A;
      EXPECT_LT((M - Me).cwiseAbs().maxCoeff(), 1e-12 * (1.0 + Me.cwiseAbs().maxCoeff())) << c.name;
      const Eigen::VectorXd g = GravityTorques(*p.mimic, q);
      EXPECT_LT((g - p.A.transpose() * GravityTorques(*p.expanded, theta)).cwiseAbs().maxCoeff(), 1e-12 * scale);
      const Eigen::VectorXd cq = CoriolisTorques(*p.mimic, q, qd);
      EXPECT_LT((cq - p.A.transpose() * CoriolisTorques(*p.expanded, theta, thetad)).cwiseAbs().maxCoeff(),
                1e-12 * scale);
    }
  }
}

TEST(MimicDynamics, MassMatrixCoriolisAndFrictionAgreeWithTheRecursion) {
  // Independent of the expanded robot: M's columns from the RNEA (τ is affine in q̈), C q̇ = c,
  // Ṁ − 2C skew-symmetric with Ṁ by central differences of M along q̇, forward dynamics inverts
  // inverse dynamics, and the friction InverseDynamics adds is DofFriction's.
  std::mt19937_64 rng(TestSeed(47));
  for (const MimicCase& c : Cases()) {
    const Pair p = WithArmature(MakePair(c));
    const RobotModel& robot = *p.mimic;
    const int n = robot.num_dofs();
    DynamicsOptions no_gravity;
    no_gravity.gravity.setZero();
    no_gravity.include_friction = false;
    for (int trial = 0; trial < 10; ++trial) {
      const Eigen::VectorXd q = Random(robot, rng);
      const Eigen::VectorXd qd = RandomVector(n, 1.5, rng);
      const Eigen::MatrixXd M = MassMatrix(robot, q);
      const Eigen::VectorXd zero = Eigen::VectorXd::Zero(n);
      const double scale = 1.0 + M.cwiseAbs().maxCoeff();
      for (int i = 0; i < n; ++i) {
        const Eigen::VectorXd column = InverseDynamics(robot, q, zero, Eigen::VectorXd::Unit(n, i), no_gravity);
        EXPECT_LT((column - M.col(i)).cwiseAbs().maxCoeff(), 1e-12 * scale) << c.name << " column " << i;
      }
      EXPECT_GT(M.ldlt().vectorD().minCoeff(), 0.0) << c.name;
      const Eigen::MatrixXd C = CoriolisMatrix(robot, q, qd);
      const Eigen::VectorXd cq = CoriolisTorques(robot, q, qd);
      EXPECT_LT((C * qd - cq).cwiseAbs().maxCoeff(), 1e-9 * (1.0 + cq.cwiseAbs().maxCoeff())) << c.name;
      const double h = 1e-6;
      const Eigen::MatrixXd Mdot = (MassMatrix(robot, q + h * qd) - MassMatrix(robot, q - h * qd)) / (2 * h);
      const Eigen::MatrixXd N = Mdot - 2.0 * C;
      EXPECT_LT((N + N.transpose()).cwiseAbs().maxCoeff(), 1e-6 * scale) << c.name;
      const Eigen::VectorXd qdd = RandomVector(n, 3.0, rng);
      const Eigen::VectorXd tau = InverseDynamics(robot, q, qd, qdd);
      EXPECT_LT((ForwardDynamics(robot, q, qd, tau) - qdd).cwiseAbs().maxCoeff(), 1e-7) << c.name;
      // Friction: with and without, at q̈ = 0.
      DynamicsOptions frictionless;
      frictionless.include_friction = false;
      const Eigen::VectorXd friction = InverseDynamics(robot, q, qd, zero) - InverseDynamics(robot, q, qd, zero, frictionless);
      for (int d = 0; d < n; ++d) {
        const JointFriction f = DofFriction(robot, d);
        const double expected = f.damping * qd[d] + f.friction * (qd[d] > 0 ? 1.0 : qd[d] < 0 ? -1.0 : 0.0);
        EXPECT_NEAR(friction[d], expected, 1e-9) << c.name << " dof " << d;
      }
    }
  }
  // The coupled arm's finger: its own damping 3 and finger_b's 4 (m = −1) and tip's 1 (m = −½).
  const Pair p = MakePair(Cases()[0]);
  const JointFriction f = DofFriction(*p.mimic, p.Dof("finger_a_joint"));
  EXPECT_DOUBLE_EQ(f.damping, 3.0 + 4.0 + 0.25 * 1.0);
  EXPECT_DOUBLE_EQ(f.friction, 0.4 + 0.5 + 0.5 * 0.1);
}

}  // namespace
}  // namespace chasles
