// AttachObjects: a carried object is a link of its own under its link — the robot's joints,
// dofs and the poses of its own links unchanged (compared with the robot as loaded), the object's
// pose its link's, allowed pairs as asked, and named errors.

#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "chasles/robot/attached_objects.h"
#include "chasles/robot/dynamics.h"
#include "chasles/robot/kinematics.h"
#include "chasles/robot/error.h"
#include "test_util.h"

namespace chasles {
namespace {

AttachedObject Box(const RobotModel& robot, const std::string& name, const std::string& link) {
  AttachedObject object;
  object.name = name;
  object.link = robot.FindLink(link);
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = Eigen::Vector3d(0.0, 0.0, 0.1);
  object.shapes.push_back(Shape::Box(Eigen::Vector3d(0.04, 0.04, 0.2), pose));
  return object;
}

TEST(AttachObjects, KeepsTheJointsAndMovesTheObjectWithItsLink) {
  const auto robot = testing::LoadExampleRobot("panda");
  AttachedObject box = Box(*robot, "box", "panda_hand");
  box.touch_links = {"panda_link7"};
  const auto carrying = AttachObjects(*robot, {box});
  ASSERT_EQ(carrying->num_dofs(), robot->num_dofs());
  EXPECT_EQ(carrying->dof_names(), robot->dof_names());
  EXPECT_EQ(carrying->num_links(), robot->num_links() + 1);
  const int object = carrying->FindLink("box");
  ASSERT_GE(object, 0);
  ASSERT_EQ(carrying->links()[static_cast<std::size_t>(object)].collision.size(), 1u);
  std::mt19937_64 rng(3);
  std::vector<Eigen::Isometry3d> before, after;
  for (int trial = 0; trial < 20; ++trial) {
    Eigen::VectorXd q(robot->num_dofs());
    for (int i = 0; i < q.size(); ++i) {
      q[i] = std::uniform_real_distribution<double>(robot->lower_limits()[i], robot->upper_limits()[i])(rng);
    }
    robot->ForwardKinematics(q, &before);
    carrying->ForwardKinematics(q, &after);
    for (int l = 0; l < robot->num_links(); ++l) {
      const int same = carrying->FindLink(robot->links()[static_cast<std::size_t>(l)].name);
      ASSERT_GE(same, 0);
      EXPECT_TRUE(after[static_cast<std::size_t>(same)].isApprox(before[static_cast<std::size_t>(l)], 1e-12));
    }
    EXPECT_TRUE(after[static_cast<std::size_t>(object)].isApprox(
        before[static_cast<std::size_t>(robot->FindLink("panda_hand"))], 1e-12));
  }
  const AllowedCollisionMatrix& acm = carrying->allowed_collisions();
  EXPECT_TRUE(acm.IsAllowed(object, carrying->FindLink("panda_hand")));
  EXPECT_TRUE(acm.IsAllowed(object, carrying->FindLink("panda_link7")));
  EXPECT_FALSE(acm.IsAllowed(object, carrying->FindLink("panda_link5")));
  EXPECT_FALSE(acm.IsAllowed(object, carrying->FindLink("panda_link0")));
  // The robot's own pairs are kept.
  for (int a = 0; a < robot->num_links(); ++a) {
    for (int b = 0; b < robot->num_links(); ++b) {
      EXPECT_EQ(robot->allowed_collisions().IsAllowed(a, b),
                acm.IsAllowed(carrying->FindLink(robot->links()[static_cast<std::size_t>(a)].name),
                              carrying->FindLink(robot->links()[static_cast<std::size_t>(b)].name)));
    }
  }
}

// A carried point mass m at p on a link held still needs J_p(q)ᵀ (0, 0, m·9.81) more torque (the
// virtual work of its weight; J_p from PointJacobian, not from the dynamics code).
TEST(AttachObjects, AMassIsHeldByTheWeightItsPointJacobianGives) {
  const auto robot = testing::LoadExampleRobot("panda");
  AttachedObject load = Box(*robot, "load", "panda_hand");
  load.mass = 2.5;
  load.center_of_mass = Eigen::Vector3d(0.02, -0.01, 0.12);
  const auto carrying = AttachObjects(*robot, {load});
  ASSERT_TRUE(HasInertia(*carrying));
  std::mt19937_64 rng(5);
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(robot->num_dofs());
  for (int trial = 0; trial < 20; ++trial) {
    Eigen::VectorXd q(robot->num_dofs());
    for (int i = 0; i < q.size(); ++i) {
      q[i] = std::uniform_real_distribution<double>(robot->lower_limits()[i], robot->upper_limits()[i])(rng);
    }
    const Eigen::VectorXd extra = InverseDynamics(*carrying, q, zero, zero) - InverseDynamics(*robot, q, zero, zero);
    const Jacobian J = PointJacobian(*robot, q, robot->FindLink("panda_hand"), load.center_of_mass);
    const Eigen::VectorXd weight = J.bottomRows<3>().transpose() * Eigen::Vector3d(0.0, 0.0, load.mass * 9.81);
    EXPECT_LT((extra - weight).cwiseAbs().maxCoeff(), 1e-10) << extra.transpose() << "\n" << weight.transpose();
  }
  // No mass: the dynamics are the robot's.
  const auto light = AttachObjects(*robot, {Box(*robot, "box", "panda_hand")});
  Eigen::VectorXd q = Eigen::VectorXd::Constant(robot->num_dofs(), 0.3);
  EXPECT_LT((InverseDynamics(*light, q, zero, zero) - InverseDynamics(*robot, q, zero, zero)).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(AttachObjects, NamesTheFieldOfABadObject) {
  const auto robot = testing::LoadExampleRobot("panda");
  const auto message = [&](const std::vector<AttachedObject>& objects) {
    try {
      AttachObjects(*robot, objects);
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const AttachedObject box = Box(*robot, "box", "panda_hand");
  EXPECT_EQ(message({box, box}), "attached_objects[1].name = 'box' is attached twice");
  AttachedObject named_as_link = Box(*robot, "panda_link3", "panda_hand");
  EXPECT_EQ(message({named_as_link}),
            "attached_objects[0].name = 'panda_link3' is a link of robot 'panda'; give the object a name of its own");
  AttachedObject unnamed = box;
  unnamed.name.clear();
  EXPECT_EQ(message({unnamed}), "attached_objects[0].name is empty: an attached object needs a name");
  AttachedObject empty = box;
  empty.shapes.clear();
  EXPECT_EQ(message({empty}), "attached_objects[0] has no shapes: give it a box, sphere, cylinder or capsule");
  AttachedObject touching = box;
  touching.touch_links = {"panda_hand", "gripper"};
  EXPECT_NE(message({touching}).find("attached_objects[0].touch_links[1] = 'gripper' is not a link of robot 'panda'"),
            std::string::npos);
  AttachedObject nowhere = box;
  nowhere.link = 99;
  EXPECT_EQ(message({nowhere}), "attached_objects[0].link = 99 is not a link of robot 'panda'");
  AttachedObject heavy = box;
  heavy.mass = -1.0;
  EXPECT_EQ(message({heavy}), "attached_objects[0].mass = -1 must be finite and >= 0 [kg]");
}

}  // namespace
}  // namespace chasles
