// The example robots in examples/robots: published parameters, joint order, collision geometry,
// and that they are self-collision free at their zero and 'ready' configurations under the ACM
// (checked without the collision module: plain sphere/sphere overlap for the panda, containing
// capsules for the others).

#include <algorithm>
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "capsule_overlap.h"
#include "chasles/robot/robot_model.h"
#include "test_util.h"

namespace chasles {
namespace {

using testing::LoadExampleRobot;

Eigen::VectorXd Vec(std::initializer_list<double> values) {
  Eigen::VectorXd q(values.size());
  int i = 0;
  for (double v : values) q[i++] = v;
  return q;
}

Eigen::VectorXd PandaReady() { return Vec({0, -0.785, 0, -2.356, 0, 1.571, 0.785}); }
Eigen::VectorXd Ur5Ready() { return Vec({0, -M_PI / 2, M_PI / 2, -M_PI / 2, -M_PI / 2, 0}); }
Eigen::VectorXd Planar2rReady() { return Vec({M_PI / 4, M_PI / 2}); }
/// Torso straight, both arms lowered with the elbows bent up and the grippers half open.
Eigen::VectorXd DualArmReady() {
  return Vec({0, 0.4, 0.2, -1.2, 0, 0.6, 0.02, 0.4, -0.2, -1.2, 0, 0.6, 0.02});
}

/// Exact sphere/sphere self-collision check (every shape must be a sphere).
/// Returns the smallest clearance [m] over pairs not allowed by the ACM (negative = overlap).
double SphereSelfClearance(const RobotModel& robot, const Eigen::VectorXd& q, std::string* worst_pair) {
  std::vector<Eigen::Isometry3d> poses;
  robot.ForwardKinematics(q, &poses);
  double clearance = INFINITY;
  for (int a = 0; a < robot.num_links(); ++a) {
    for (int b = a + 1; b < robot.num_links(); ++b) {
      if (robot.allowed_collisions().IsAllowed(a, b)) continue;
      for (const Shape& sa : robot.links()[a].collision) {
        const Eigen::Vector3d ca = poses[a] * sa.pose.translation();
        for (const Shape& sb : robot.links()[b].collision) {
          const Eigen::Vector3d cb = poses[b] * sb.pose.translation();
          const double c = (ca - cb).norm() - sa.radius - sb.radius;
          if (c < clearance) {
            clearance = c;
            *worst_pair = robot.links()[a].name + " / " + robot.links()[b].name;
          }
        }
      }
    }
  }
  return clearance;
}

TEST(ExampleRobotsTest, PandaIsSphereOnlyWithPublishedLimits) {
  const auto robot = LoadExampleRobot("panda");
  ASSERT_EQ(robot->num_dofs(), 7);
  EXPECT_EQ(robot->dof_names(),
            (std::vector<std::string>{"panda_joint1", "panda_joint2", "panda_joint3", "panda_joint4",
                                      "panda_joint5", "panda_joint6", "panda_joint7"}));
  int spheres = 0;
  for (const Link& link : robot->links()) {
    for (const Shape& shape : link.collision) {
      EXPECT_EQ(shape.type, ShapeType::kSphere) << link.name;
      EXPECT_GT(shape.radius, 0.0);
      ++spheres;
    }
  }
  EXPECT_GE(spheres, 40);
  EXPECT_LE(spheres, 60);
  const Eigen::VectorXd lower = Vec({-2.8973, -1.7628, -2.8973, -3.0718, -2.8973, -0.0175, -2.8973});
  const Eigen::VectorXd upper = Vec({2.8973, 1.7628, 2.8973, -0.0698, 2.8973, 3.7525, 2.8973});
  const Eigen::VectorXd velocity = Vec({2.175, 2.175, 2.175, 2.175, 2.61, 2.61, 2.61});
  EXPECT_EQ(robot->lower_limits(), lower);
  EXPECT_EQ(robot->upper_limits(), upper);
  EXPECT_EQ(robot->velocity_limits(), velocity);
  // The ready configuration is within the limits.
  EXPECT_NO_THROW(robot->ValidateConfiguration(PandaReady(), "ready"));
}

TEST(ExampleRobotsTest, PandaIsSelfCollisionFreeAtZeroAndReady) {
  const auto robot = LoadExampleRobot("panda");
  for (const Eigen::VectorXd& q : {Eigen::VectorXd(Eigen::VectorXd::Zero(7)), PandaReady()}) {
    std::string pair;
    const double clearance = SphereSelfClearance(*robot, q, &pair);
    // At least 5 mm, so a checker with a few millimetres of padding agrees.
    EXPECT_GT(clearance, 0.005) << "q = " << q.transpose() << ": " << pair;
  }
}

TEST(ExampleRobotsTest, PandaIsInSelfCollisionWhenFoldedOntoItself) {
  // The check above could fail: with the hand folded back onto the base it reports contact.
  const auto robot = LoadExampleRobot("panda");
  std::mt19937 rng(11);
  int colliding = 0;
  for (int i = 0; i < 2000; ++i) {
    Eigen::VectorXd q(7);
    for (int d = 0; d < 7; ++d) {
      q[d] = std::uniform_real_distribution<double>(robot->lower_limits()[d], robot->upper_limits()[d])(rng);
    }
    std::string pair;
    colliding += SphereSelfClearance(*robot, q, &pair) < 0.0;
  }
  EXPECT_GT(colliding, 20);
  EXPECT_LT(colliding, 1000);
}

/// Joint-graph distance between links (number of joints on the path).
int TreeDistance(const RobotModel& robot, int a, int b) {
  auto ancestors = [&](int link) {
    std::vector<int> path{link};
    while (robot.links()[link].parent_joint >= 0) {
      link = robot.joints()[robot.links()[link].parent_joint].parent_link;
      path.push_back(link);
    }
    return path;
  };
  const std::vector<int> pa = ancestors(a), pb = ancestors(b);
  for (size_t i = 0; i < pa.size(); ++i) {
    for (size_t j = 0; j < pb.size(); ++j) {
      if (pa[i] == pb[j]) return static_cast<int>(i + j);
    }
  }
  return -1;
}

class ExampleRobotAcmTest : public ::testing::TestWithParam<std::string> {};

TEST_P(ExampleRobotAcmTest, SelfCollisionFreeAtZeroAndReady) {
  const auto robot = LoadExampleRobot(GetParam());
  const Eigen::VectorXd ready = GetParam() == "panda"      ? PandaReady()
                                : GetParam() == "ur5"      ? Ur5Ready()
                                : GetParam() == "dual_arm" ? DualArmReady()
                                                           : Planar2rReady();
  for (const Eigen::VectorXd& q : {Eigen::VectorXd(Eigen::VectorXd::Zero(robot->num_dofs())), ready}) {
    // (The panda's zero configuration is outside its joint-4 limits; it is still checked.)
    if (GetParam() != "panda" || q != Eigen::VectorXd::Zero(7)) {
      EXPECT_NO_THROW(robot->ValidateConfiguration(q, "q"));
    }
    const auto pairs = testing::SelfCollisions(*robot, q);
    for (const auto& [a, b] : pairs) ADD_FAILURE() << GetParam() << " q = " << q.transpose() << ": " << a << " / " << b;
  }
}

TEST_P(ExampleRobotAcmTest, PairsThatAlwaysOverlapAreAllowed) {
  // Links two joints apart (and any other pair) whose geometry overlaps in every sampled
  // configuration must be in the ACM, or every state would be in self-collision.
  const auto robot = LoadExampleRobot(GetParam());
  const int n = robot->num_links();
  std::vector<int> overlaps(n * n, 0);
  std::mt19937 rng(2024);
  const int samples = 500;
  std::vector<Eigen::Isometry3d> poses;
  for (int i = 0; i < samples; ++i) {
    Eigen::VectorXd q(robot->num_dofs());
    for (int d = 0; d < q.size(); ++d) {
      q[d] = std::uniform_real_distribution<double>(robot->lower_limits()[d], robot->upper_limits()[d])(rng);
    }
    robot->ForwardKinematics(q, &poses);
    for (int a = 0; a < n; ++a) {
      for (int b = a + 1; b < n; ++b) {
        if (robot->links()[a].collision.empty() || robot->links()[b].collision.empty()) continue;
        overlaps[a * n + b] += testing::LinkPenetration(*robot, poses, a, b) > 0.0;
      }
    }
  }
  for (int a = 0; a < n; ++a) {
    for (int b = a + 1; b < n; ++b) {
      if (overlaps[a * n + b] == samples) {
        EXPECT_TRUE(robot->allowed_collisions().IsAllowed(a, b))
            << robot->links()[a].name << " / " << robot->links()[b].name << " (tree distance "
            << TreeDistance(*robot, a, b) << ") always overlap but are not allowed";
      }
    }
  }
  if (GetParam() == "panda") {
    // The hand is two joints from link7 (through the flange link8) and always overlaps it.
    EXPECT_EQ(TreeDistance(*robot, robot->FindLink("panda_link7"), robot->FindLink("panda_hand")), 2);
    EXPECT_EQ(overlaps[robot->FindLink("panda_link7") * n + robot->FindLink("panda_hand")], samples);
  }
}

INSTANTIATE_TEST_SUITE_P(Robots, ExampleRobotAcmTest, ::testing::Values("planar_2r", "ur5", "panda", "dual_arm"));

TEST(ExampleRobotsTest, DualArmHasOneCoordinatePerGripperAndWarnsOfItsStaleSrdfEntry) {
  const std::string urdf = testing::ReadExample("robots/dual_arm.urdf");
  const std::string srdf = testing::ReadExample("robots/dual_arm.srdf");
  const auto robot = RobotModel::FromUrdf(urdf, srdf);
  // 1 torso + 2 × (5 arm joints + 1 gripper); the second fingers are mimic joints.
  ASSERT_EQ(robot->num_dofs(), 13);
  EXPECT_EQ(robot->num_moving_joints(), 15);
  EXPECT_EQ(robot->dof_names(),
            (std::vector<std::string>{"torso_joint", "left_shoulder_pitch", "left_shoulder_roll", "left_elbow",
                                      "left_wrist_roll", "left_wrist_pitch", "left_finger_joint", "right_shoulder_pitch",
                                      "right_shoulder_roll", "right_elbow", "right_wrist_roll", "right_wrist_pitch",
                                      "right_finger_joint"}));
  for (const char* side : {"left", "right"}) {
    const std::string finger = std::string(side) + "_finger_joint";
    const int d = static_cast<int>(std::find(robot->dof_names().begin(), robot->dof_names().end(), finger) -
                                   robot->dof_names().begin());
    EXPECT_EQ(robot->lower_limits()[d], 0.0) << side;
    EXPECT_EQ(robot->upper_limits()[d], 0.04) << side;
    int mimics = 0;
    for (const Joint& joint : robot->joints()) {
      if (!joint.mimic) continue;
      if (joint.dof != d) continue;
      ++mimics;
      EXPECT_EQ(joint.name, std::string(side) + "_finger_b_joint");
      EXPECT_EQ(joint.type, JointType::kPrismatic);
      EXPECT_EQ(robot->joints()[joint.mimic->joint].name, finger);
      EXPECT_EQ(joint.mimic->multiplier, -1.0);
    }
    EXPECT_EQ(mimics, 1) << side;
  }
  // The stale SRDF pair is the one warning (the mimic limits fit: nothing is narrowed).
  ASSERT_EQ(robot->load_warnings().size(), 1u);
  EXPECT_NE(robot->load_warnings()[0].find("'left_wrist_camera_link'"), std::string::npos) << robot->load_warnings()[0];
  EXPECT_NE(robot->load_warnings()[0].find("the pair is skipped"), std::string::npos) << robot->load_warnings()[0];
  try {
    RobotModel::FromUrdf(urdf, srdf, {}, {}, /*strict_srdf=*/true);
    ADD_FAILURE() << "strict_srdf accepted the stale entry";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("left_wrist_camera_link"), std::string::npos) << e.what();
  }
  // Spheres only (the fast, certified collision path), and mass on every moving link.
  for (const Link& link : robot->links()) {
    for (const Shape& shape : link.collision) EXPECT_EQ(shape.type, ShapeType::kSphere) << link.name;
  }
  for (const Joint& joint : robot->joints()) {
    if (joint.type == JointType::kFixed) continue;
    const Link& child = robot->links()[joint.child_link];
    ASSERT_TRUE(child.inertial.has_value()) << child.name;
    EXPECT_GT(child.inertial->mass, 0.0) << child.name;
  }
  // The fingers close towards each other and are checked against each other.
  EXPECT_FALSE(robot->allowed_collisions().IsAllowed(robot->FindLink("left_finger_a"), robot->FindLink("left_finger_b")));
  std::vector<Eigen::Isometry3d> poses;
  Eigen::VectorXd q = DualArmReady();
  for (double opening : {0.0, 0.04}) {
    q[6] = opening;
    robot->ForwardKinematics(q, &poses);
    const double gap = (poses[robot->FindLink("left_finger_a")].translation() -
                        poses[robot->FindLink("left_finger_b")].translation()).norm();
    EXPECT_NEAR(gap, 0.03 + 2 * opening, 1e-12);
  }
}

TEST(ExampleRobotsTest, Ur5AndPlanar2rJointOrderAndLimits) {
  const auto ur5 = LoadExampleRobot("ur5");
  EXPECT_EQ(ur5->dof_names(),
            (std::vector<std::string>{"shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint",
                                      "wrist_1_joint", "wrist_2_joint", "wrist_3_joint"}));
  EXPECT_EQ(ur5->velocity_limits(), Eigen::VectorXd::Constant(6, 3.15));
  bool has_cylinder = false;
  for (const Link& link : ur5->links())
    for (const Shape& s : link.collision) has_cylinder |= s.type == ShapeType::kCylinder;
  EXPECT_TRUE(has_cylinder) << "the UR5 exercises the generic (non-sphere) collision path";

  const auto planar = LoadExampleRobot("planar_2r");
  EXPECT_EQ(planar->dof_names(), (std::vector<std::string>{"joint1", "joint2"}));
  EXPECT_EQ(planar->velocity_limits(), Eigen::VectorXd::Constant(2, 2.0));
  EXPECT_DOUBLE_EQ(planar->upper_limits()[0], M_PI);
  std::vector<Eigen::Isometry3d> poses;
  std::mt19937 rng(9);
  for (int i = 0; i < 200; ++i) {
    const Eigen::Vector2d q(std::uniform_real_distribution<double>(-M_PI, M_PI)(rng),
                            std::uniform_real_distribution<double>(-M_PI, M_PI)(rng));
    planar->ForwardKinematics(q, &poses);
    for (int l = 0; l < planar->num_links(); ++l) {
      for (const Shape& s : planar->links()[l].collision) {
        EXPECT_DOUBLE_EQ(s.radius, 0.05);
        EXPECT_GT((poses[l] * s.pose.translation()).z() - s.radius, 0.0) << "above the base plane";
      }
    }
  }
}

}  // namespace
}  // namespace chasles
