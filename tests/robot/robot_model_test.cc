// RobotModel: FK against analytic answers and published parameters, PoE vs chaining, screw
// axes, ACM, configuration validation, FromTree rules.

#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "chasles/robot/robot_model.h"
#include "test_util.h"

namespace chasles {
namespace {

using testing::ExpectInvalid;
using testing::LoadExampleRobot;
using Screw = Eigen::Matrix<double, 6, 1>;

Eigen::VectorXd RandomConfiguration(const RobotModel& model, std::mt19937* rng) {
  Eigen::VectorXd q(model.num_dofs());
  for (int d = 0; d < model.num_dofs(); ++d) {
    q[d] = std::uniform_real_distribution<double>(model.lower_limits()[d], model.upper_limits()[d])(*rng);
  }
  return q;
}

double PoseError(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return (a.matrix() - b.matrix()).cwiseAbs().maxCoeff();
}

// ---------------------------------------------------------------------------------------------
// Planar 2R: analytic FK.

TEST(RobotModelTest, Planar2rMatchesAnalyticForwardKinematics) {
  const auto robot = LoadExampleRobot("planar_2r");
  ASSERT_EQ(robot->num_dofs(), 2);
  const int tool = robot->FindLink("tool");
  const int link2 = robot->FindLink("link2");
  ASSERT_GE(tool, 0);
  const double l1 = 1.0, l2 = 0.8;
  std::mt19937 rng(7);
  std::vector<Eigen::Isometry3d> poses;
  for (int i = 0; i < 100; ++i) {
    const Eigen::VectorXd q = RandomConfiguration(*robot, &rng);
    robot->ForwardKinematics(q, &poses);
    const double c1 = std::cos(q[0]), s1 = std::sin(q[0]);
    const double c12 = std::cos(q[0] + q[1]), s12 = std::sin(q[0] + q[1]);
    const Eigen::Vector3d expected_tool(l1 * c1 + l2 * c12, l1 * s1 + l2 * s12, 0.0);
    EXPECT_LT((poses[tool].translation() - expected_tool).norm(), 1e-12) << q.transpose();
    EXPECT_LT((poses[link2].translation() - Eigen::Vector3d(l1 * c1, l1 * s1, 0.0)).norm(), 1e-12);
    const Eigen::Matrix3d expected_rotation =
        Eigen::AngleAxisd(q[0] + q[1], Eigen::Vector3d::UnitZ()).toRotationMatrix();
    EXPECT_LT((poses[tool].linear() - expected_rotation).cwiseAbs().maxCoeff(), 1e-12);
  }
  // One hand-checked value: q = (π/2, -π/2) puts the tool at (0.8, 1.0).
  robot->ForwardKinematics(Eigen::Vector2d(M_PI / 2, -M_PI / 2), &poses);
  EXPECT_LT((poses[tool].translation() - Eigen::Vector3d(0.8, 1.0, 0.0)).norm(), 1e-12);
}

// ---------------------------------------------------------------------------------------------
// PoE == chaining on every link of every example robot.

class ExampleRobotFkTest : public ::testing::TestWithParam<std::string> {};

TEST_P(ExampleRobotFkTest, ProductOfExponentialsEqualsChaining) {
  const auto robot = LoadExampleRobot(GetParam());
  std::mt19937 rng(42);
  std::vector<Eigen::Isometry3d> poe, chain;
  double worst = 0.0;
  for (int i = 0; i < 1000; ++i) {
    const Eigen::VectorXd q = RandomConfiguration(*robot, &rng);
    robot->ForwardKinematics(q, &poe);
    robot->ForwardKinematicsByChaining(q, &chain);
    ASSERT_EQ(poe.size(), static_cast<size_t>(robot->num_links()));
    ASSERT_EQ(chain.size(), poe.size());
    for (int l = 0; l < robot->num_links(); ++l) worst = std::max(worst, PoseError(poe[l], chain[l]));
  }
  EXPECT_LT(worst, 1e-9);
}

TEST_P(ExampleRobotFkTest, HomePosesAreTheZeroConfiguration) {
  const auto robot = LoadExampleRobot(GetParam());
  std::vector<Eigen::Isometry3d> poses;
  robot->ForwardKinematics(Eigen::VectorXd::Zero(robot->num_dofs()), &poses);
  for (int l = 0; l < robot->num_links(); ++l) {
    EXPECT_LT(PoseError(poses[l], robot->home_pose(l)), 1e-15) << robot->links()[l].name;
    EXPECT_DOUBLE_EQ(poses[l].matrix()(3, 3), 1.0);
  }
}

INSTANTIATE_TEST_SUITE_P(Robots, ExampleRobotFkTest,
                         ::testing::Values("planar_2r", "ur5", "panda"));

// ---------------------------------------------------------------------------------------------
// UR5: space screw axes and M of Lynch & Park Example 4.5; FK against the DH table.

struct Ur5Params {
  double w1 = 0.10915, w2 = 0.0823, l1 = 0.425, l2 = 0.39225, h1 = 0.089159, h2 = 0.09465;
};

TEST(RobotModelTest, Ur5ScrewAxesMatchModernRoboticsExample45) {
  const auto robot = LoadExampleRobot("ur5");
  ASSERT_EQ(robot->num_dofs(), 6);
  const Ur5Params p;
  std::vector<Screw> expected(6);
  expected[0] << 0, 0, 1, 0, 0, 0;
  expected[1] << 0, 1, 0, -p.h1, 0, 0;
  expected[2] << 0, 1, 0, -p.h1, 0, p.l1;
  expected[3] << 0, 1, 0, -p.h1, 0, p.l1 + p.l2;
  expected[4] << 0, 0, -1, -p.w1, p.l1 + p.l2, 0;
  expected[5] << 0, 1, 0, p.h2 - p.h1, 0, p.l1 + p.l2;
  for (int d = 0; d < 6; ++d) {
    EXPECT_LT((robot->space_screw_axis(d) - expected[d]).cwiseAbs().maxCoeff(), 1e-12)
        << "S" << d + 1 << " = " << robot->space_screw_axis(d).transpose();
  }
  Eigen::Matrix4d m;
  m << -1, 0, 0, p.l1 + p.l2,  //
      0, 0, 1, p.w1 + p.w2,    //
      0, 1, 0, p.h1 - p.h2,    //
      0, 0, 0, 1;
  const int tool0 = robot->FindLink("tool0");
  ASSERT_GE(tool0, 0);
  EXPECT_LT((robot->home_pose(tool0).matrix() - m).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_EQ(robot->link_chain(tool0), (std::vector<int>{0, 1, 2, 3, 4, 5}));
}

Eigen::Isometry3d StandardDh(double a, double d, double alpha, double theta) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.rotate(Eigen::AngleAxisd(theta, Eigen::Vector3d::UnitZ()));
  t.translate(Eigen::Vector3d(0, 0, d));
  t.translate(Eigen::Vector3d(a, 0, 0));
  t.rotate(Eigen::AngleAxisd(alpha, Eigen::Vector3d::UnitX()));
  return t;
}

TEST(RobotModelTest, Ur5MatchesPublishedDhTable) {
  const auto robot = LoadExampleRobot("ur5");
  const double a[6] = {0, -0.425, -0.39225, 0, 0, 0};
  const double d[6] = {0.089159, 0, 0, 0.10915, 0.09465, 0.0823};
  const double alpha[6] = {M_PI / 2, 0, 0, M_PI / 2, -M_PI / 2, 0};
  // The Modern Robotics base frame is the DH base frame turned by π about z.
  const Eigen::Isometry3d base(Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitZ()));
  const int tool0 = robot->FindLink("tool0");
  std::mt19937 rng(3);
  std::vector<Eigen::Isometry3d> poses;
  for (int i = 0; i < 200; ++i) {
    const Eigen::VectorXd q = RandomConfiguration(*robot, &rng);
    Eigen::Isometry3d dh = base;
    for (int j = 0; j < 6; ++j) dh = dh * StandardDh(a[j], d[j], alpha[j], q[j]);
    robot->ForwardKinematics(q, &poses);
    EXPECT_LT(PoseError(poses[tool0], dh), 1e-12) << q.transpose();
  }
}

// Panda: FK of the flange against Franka's modified-DH (Craig) table.
TEST(RobotModelTest, PandaMatchesPublishedModifiedDhTable) {
  const auto robot = LoadExampleRobot("panda");
  ASSERT_EQ(robot->num_dofs(), 7);
  const double a[8] = {0, 0, 0, 0.0825, -0.0825, 0, 0.088, 0};
  const double d[8] = {0.333, 0, 0.316, 0, 0.384, 0, 0, 0.107};
  const double alpha[8] = {0, -M_PI / 2, M_PI / 2, M_PI / 2, -M_PI / 2, M_PI / 2, M_PI / 2, 0};
  const int flange = robot->FindLink("panda_link8");
  ASSERT_GE(flange, 0);
  std::mt19937 rng(5);
  std::vector<Eigen::Isometry3d> poses;
  for (int i = 0; i < 200; ++i) {
    const Eigen::VectorXd q = RandomConfiguration(*robot, &rng);
    Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
    for (int j = 0; j < 8; ++j) {
      t.rotate(Eigen::AngleAxisd(alpha[j], Eigen::Vector3d::UnitX()));
      t.translate(Eigen::Vector3d(a[j], 0, 0));
      t.rotate(Eigen::AngleAxisd(j < 7 ? q[j] : 0.0, Eigen::Vector3d::UnitZ()));
      t.translate(Eigen::Vector3d(0, 0, d[j]));
    }
    robot->ForwardKinematics(q, &poses);
    EXPECT_LT(PoseError(poses[flange], t), 1e-12) << q.transpose();
  }
  // Zero configuration: flange at (0.088, 0, 0.926) pointing down.
  robot->ForwardKinematics(Eigen::VectorXd::Zero(7), &poses);
  EXPECT_LT((poses[flange].translation() - Eigen::Vector3d(0.088, 0, 0.926)).norm(), 1e-12);
  EXPECT_LT((poses[flange].linear().col(2) - Eigen::Vector3d(0, 0, -1)).norm(), 1e-12);
}

// ---------------------------------------------------------------------------------------------
// Allowed-collision matrix.

TEST(RobotModelTest, AllowedCollisionMatrixHoldsAdjacentAndSrdfPairsOnly) {
  const auto robot = LoadExampleRobot("panda");
  const AllowedCollisionMatrix& acm = robot->allowed_collisions();
  ASSERT_EQ(acm.num_links(), robot->num_links());
  auto allowed = [&](const char* a, const char* b) {
    const int ia = robot->FindLink(a), ib = robot->FindLink(b);
    EXPECT_GE(ia, 0) << a;
    EXPECT_GE(ib, 0) << b;
    EXPECT_EQ(acm.IsAllowed(ia, ib), acm.IsAllowed(ib, ia)) << "symmetric";
    return acm.IsAllowed(ia, ib);
  };
  // Every joint's parent/child pair, fixed joints included.
  for (const Joint& joint : robot->joints()) {
    EXPECT_TRUE(acm.IsAllowed(joint.parent_link, joint.child_link)) << joint.name;
  }
  EXPECT_TRUE(allowed("panda_link7", "panda_link8"));  // fixed flange joint
  EXPECT_TRUE(allowed("panda_link8", "panda_hand"));   // fixed hand joint
  // SRDF pairs.
  EXPECT_TRUE(allowed("panda_link7", "panda_hand"));
  EXPECT_TRUE(allowed("panda_link0", "panda_link2"));
  EXPECT_TRUE(allowed("panda_link1", "panda_link3"));
  // Not allowed: everything else.
  EXPECT_FALSE(allowed("panda_link5", "panda_link7"));
  EXPECT_FALSE(allowed("panda_link0", "panda_hand"));
  EXPECT_FALSE(allowed("panda_link5", "panda_hand"));
  EXPECT_FALSE(allowed("panda_link0", "panda_link0"));
  int count = 0;
  for (int a = 0; a < robot->num_links(); ++a)
    for (int b = a + 1; b < robot->num_links(); ++b) count += acm.IsAllowed(a, b);
  EXPECT_EQ(count, static_cast<int>(robot->joints().size()) + 4);  // 4 SRDF pairs
  EXPECT_FALSE(acm.IsAllowed(-1, 0));
  EXPECT_FALSE(acm.IsAllowed(0, robot->num_links()));
}

// ---------------------------------------------------------------------------------------------
// ValidateConfiguration.

TEST(RobotModelTest, ValidateConfigurationMessages) {
  const auto robot = LoadExampleRobot("ur5");
  Eigen::VectorXd q = Eigen::VectorXd::Zero(6);
  robot->ValidateConfiguration(q, "start.positions");
  ExpectInvalid([&] { robot->ValidateConfiguration(Eigen::VectorXd::Zero(7), "start.positions"); },
                "start.positions has 7 values, robot 'ur5' has 6 joints");
  q[2] = std::nan("");
  ExpectInvalid([&] { robot->ValidateConfiguration(q, "start.positions"); },
                "start.positions[2] = nan must be finite");
  q[2] = -INFINITY;
  ExpectInvalid([&] { robot->ValidateConfiguration(q, "goal.positions"); },
                "goal.positions[2] = -inf must be finite");
  q[2] = 3.5;  // elbow limited to ±π
  ExpectInvalid([&] { robot->ValidateConfiguration(q, "start.positions"); },
                "start.positions[2] = 3.5 must be within [-3.141592653589793, 3.141592653589793] (joint 'elbow_joint')");
  q[2] = M_PI;  // the limit itself is inside
  robot->ValidateConfiguration(q, "start.positions");
}

// ---------------------------------------------------------------------------------------------
// FromTree.

Link MakeLink(const std::string& name) {
  Link link;
  link.name = name;
  return link;
}

Joint MakeJoint(const std::string& name, JointType type, int parent, int child,
                const Eigen::Vector3d& xyz, const Eigen::Vector3d& axis) {
  Joint joint;
  joint.name = name;
  joint.type = type;
  joint.parent_link = parent;
  joint.child_link = child;
  joint.origin = Eigen::Translation3d(xyz) * Eigen::Isometry3d::Identity();
  joint.axis = axis;
  joint.limits = {-1.0, 1.0, 1.0, 10.0};
  return joint;
}

TEST(RobotModelTest, FromTreeOrdersDofsSkipsFixedJointsAndBuildsChains) {
  std::vector<Link> links = {MakeLink("base"), MakeLink("a"), MakeLink("b"), MakeLink("c"),
                             MakeLink("d")};
  std::vector<Joint> joints = {
      MakeJoint("j0", JointType::kFixed, 0, 1, {0, 0, 0.5}, Eigen::Vector3d::UnitZ()),
      MakeJoint("j1", JointType::kPrismatic, 1, 2, {1, 0, 0}, Eigen::Vector3d(0, 0, 2)),
      MakeJoint("j2", JointType::kContinuous, 2, 3, {0, 1, 0}, Eigen::Vector3d::UnitX()),
      MakeJoint("j3", JointType::kRevolute, 1, 4, {0, 0, 1}, Eigen::Vector3d::UnitY()),
  };
  const auto robot = RobotModel::FromTree("t", links, joints, {{"base", "d"}});
  ASSERT_EQ(robot->num_dofs(), 3);
  EXPECT_EQ(robot->dof_names(), (std::vector<std::string>{"j1", "j2", "j3"}));
  EXPECT_EQ(robot->dof_joint(0), 1);
  EXPECT_EQ(robot->joints()[0].dof, -1);
  EXPECT_EQ(robot->joints()[3].dof, 2);
  EXPECT_EQ(robot->links()[3].parent_joint, 2);
  EXPECT_EQ(robot->root_link(), 0);
  // Continuous joints get [-π, π]; the prismatic axis is normalised.
  EXPECT_DOUBLE_EQ(robot->lower_limits()[1], -M_PI);
  EXPECT_DOUBLE_EQ(robot->upper_limits()[1], M_PI);
  EXPECT_EQ(robot->joints()[1].axis, Eigen::Vector3d::UnitZ());
  // Prismatic screw (0, axis); revolute screw (ω, −ω × p).
  Screw s0, s1, s2;
  s0 << 0, 0, 0, 0, 0, 1;
  s1 << 1, 0, 0, 0, 0.5, -1;   // ω = x through (1, 1, 0.5): v = −x × p = (0, 0.5, −1)
  s2 << 0, 1, 0, -1.5, 0, 0;   // ω = y through (0, 0, 1.5)
  EXPECT_LT((robot->space_screw_axis(0) - s0).norm(), 1e-15);
  EXPECT_LT((robot->space_screw_axis(1) - s1).norm(), 1e-15);
  EXPECT_LT((robot->space_screw_axis(2) - s2).norm(), 1e-15);
  EXPECT_EQ(robot->link_chain(0), std::vector<int>{});
  EXPECT_EQ(robot->link_chain(1), std::vector<int>{});
  EXPECT_EQ(robot->link_chain(3), (std::vector<int>{0, 1}));
  EXPECT_EQ(robot->link_chain(4), (std::vector<int>{2}));
  EXPECT_TRUE(robot->allowed_collisions().IsAllowed(0, 1));  // fixed joint pair
  EXPECT_TRUE(robot->allowed_collisions().IsAllowed(4, 0));  // given pair
  EXPECT_FALSE(robot->allowed_collisions().IsAllowed(2, 4));
  // PoE equals chaining on the branched tree with a prismatic joint.
  std::mt19937 rng(1);
  std::vector<Eigen::Isometry3d> a, b;
  for (int i = 0; i < 100; ++i) {
    const Eigen::VectorXd q = RandomConfiguration(*robot, &rng);
    robot->ForwardKinematics(q, &a);
    robot->ForwardKinematicsByChaining(q, &b);
    for (int l = 0; l < robot->num_links(); ++l) EXPECT_LT(PoseError(a[l], b[l]), 1e-12);
  }
  // Prismatic motion along z moves link b by q.
  robot->ForwardKinematics(Eigen::Vector3d(0.25, 0, 0), &a);
  EXPECT_LT((a[2].translation() - Eigen::Vector3d(1, 0, 0.75)).norm(), 1e-15);
}

TEST(RobotModelTest, FromTreeRejectsMalformedTrees) {
  const Eigen::Vector3d z = Eigen::Vector3d::UnitZ();
  auto links3 = [] { return std::vector<Link>{MakeLink("base"), MakeLink("a"), MakeLink("b")}; };
  ExpectInvalid([&] { RobotModel::FromTree("t", {}, {}); }, "robot 't': has no links");
  ExpectInvalid(
      [&] {
        RobotModel::FromTree("t", links3(),
                             {MakeJoint("j1", JointType::kRevolute, 1, 2, {0, 0, 0}, z),
                              MakeJoint("j0", JointType::kRevolute, 0, 1, {0, 0, 0}, z)});
      },
      "robot 't': joint[0] 'j1' parent link 'a' is the child of a later joint[1]; joints must be "
      "in topological order");
  ExpectInvalid(
      [&] {
        RobotModel::FromTree("t", links3(),
                             {MakeJoint("j0", JointType::kRevolute, 0, 1, {0, 0, 0}, z),
                              MakeJoint("j1", JointType::kRevolute, 0, 3, {0, 0, 0}, z)});
      },
      "robot 't': joint[1] 'j1' child_link = 3 must be within [0, 3)");
  ExpectInvalid(
      [&] { RobotModel::FromTree("t", links3(), {MakeJoint("j0", JointType::kRevolute, 0, 1, {0, 0, 0}, z)}); },
      "robot 't': links 'base' and 'b' both have no parent joint; the tree must have exactly one "
      "root link");
  ExpectInvalid(
      [&] {
        RobotModel::FromTree("t", links3(),
                             {MakeJoint("j0", JointType::kRevolute, 0, 1, {0, 0, 0}, z),
                              MakeJoint("j1", JointType::kRevolute, 1, 2, {0, 0, 0}, Eigen::Vector3d::Zero())});
      },
      "robot 't': joint[1] 'j1' axis = (0 0 0) must be finite and non-zero");
  ExpectInvalid(
      [&] {
        Joint bad = MakeJoint("j1", JointType::kRevolute, 1, 2, {0, 0, 0}, z);
        bad.limits.velocity = 0.0;
        RobotModel::FromTree("t", links3(), {MakeJoint("j0", JointType::kRevolute, 0, 1, {0, 0, 0}, z), bad});
      },
      "robot 't': joint[1] 'j1' limit velocity = 0 must be > 0 and finite");
  ExpectInvalid(
      [&] {
        RobotModel::FromTree("t", links3(),
                             {MakeJoint("j0", JointType::kRevolute, 0, 1, {0, 0, 0}, z),
                              MakeJoint("j1", JointType::kRevolute, 1, 2, {0, 0, 0}, z)},
                             {{"a", "hand"}});
      },
      "robot 't': allowed_pairs[0].second = 'hand' is not a link of the robot");
}

}  // namespace
}  // namespace chasles
