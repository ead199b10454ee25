// SRDF planning groups read as MoveIt reads them (issue 25, item 1: "several planning groups").

#include <algorithm>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "chasles/robot/planning_groups.h"
#include "test_util.h"

namespace chasles {
namespace {

using testing::ExpectInvalid;
using testing::LoadExampleRobot;
using testing::ReadExample;

std::vector<int> Range(int first, int last) {
  std::vector<int> out;
  for (int i = first; i <= last; ++i) out.push_back(i);
  return out;
}

TEST(PlanningGroups, TheMobileManipulatorsChainJointAndSubgroupGroups) {
  const auto robot = LoadExampleRobot("mobile_manipulator");
  ASSERT_EQ(robot->num_dofs(), 8);
  std::vector<std::string> warnings;
  const std::vector<PlanningGroup> groups =
      ReadPlanningGroups(*robot, ReadExample("robots/mobile_manipulator.srdf"), false, &warnings);
  // "arm": the chain torso_lift_link → gripper_link (shoulder_pan … wrist_roll; the fixed
  // gripper_axis has no coordinate); "arm_with_torso": the torso joint and the arm.
  ASSERT_EQ(groups.size(), 2u);
  EXPECT_EQ(groups[0].name, "arm");
  EXPECT_EQ(groups[0].dofs, Range(1, 7));
  for (int dof : groups[0].dofs) EXPECT_NE(robot->dof_names()[dof], "torso_lift_joint");
  EXPECT_EQ(groups[1].name, "arm_with_torso");
  EXPECT_EQ(groups[1].dofs, Range(0, 7));
  // "gripper_sensors" names a link this description lacks: skipped, then empty, skipped too.
  ASSERT_EQ(warnings.size(), 2u);
  EXPECT_EQ(warnings[0],
            "srdf: group 'gripper_sensors' link[0] name = 'gripper_camera_link' is not a link of robot "
            "'mobile_manipulator'; the entry is skipped");
  EXPECT_EQ(warnings[1], "srdf: group 'gripper_sensors' moves no joint of robot 'mobile_manipulator'; it is skipped");
  ExpectInvalid([&] { ReadPlanningGroups(*robot, ReadExample("robots/mobile_manipulator.srdf"), true, nullptr); },
                "srdf: group 'gripper_sensors' link[0] name = 'gripper_camera_link' is not a link of robot "
                "'mobile_manipulator'");
}

TEST(PlanningGroups, LinksNameTheirParentJointsAndSubgroupsMayComeLater) {
  const auto robot = LoadExampleRobot("panda");
  const std::string srdf = R"(<robot name="panda">
    <group name="both"><group name="wrist"/><joint name="panda_joint1"/></group>
    <group name="wrist"><link name="panda_link6"/><link name="panda_link7"/><link name="panda_link0"/></group>
  </robot>)";
  std::vector<std::string> warnings;
  const std::vector<PlanningGroup> groups = ReadPlanningGroups(*robot, srdf, false, &warnings);
  ASSERT_EQ(groups.size(), 2u);
  EXPECT_EQ(groups[0].name, "both");
  EXPECT_EQ(groups[0].dofs, (std::vector<int>{0, 5, 6}));
  EXPECT_EQ(groups[1].name, "wrist");
  EXPECT_EQ(groups[1].dofs, (std::vector<int>{5, 6}));  // panda_link0 is the root: no joint
  EXPECT_TRUE(warnings.empty());
}

TEST(PlanningGroups, MalformedGroupsAreNamedErrors) {
  const auto robot = LoadExampleRobot("panda");
  ExpectInvalid([&] { ReadPlanningGroups(*robot, "<robot><group/></robot>", false, nullptr); },
                "srdf: group[0] has no name");
  ExpectInvalid(
      [&] {
        ReadPlanningGroups(*robot, "<robot><group name='a'><joint name='panda_joint1'/></group><group name='a'/></robot>",
                           false, nullptr);
      },
      "srdf: group[1] name = 'a' is the name of group[0] too");
  ExpectInvalid(
      [&] {
        ReadPlanningGroups(*robot, "<robot><group name='a'><group name='b'/></group><group name='b'><group name='a'/></group></robot>",
                           false, nullptr);
      },
      "srdf: group 'a' includes itself through its subgroups");
  ExpectInvalid(
      [&] {
        ReadPlanningGroups(*robot, "<robot><group name='a'><chain base_link='panda_link7' tip_link='panda_link2'/></group></robot>",
                           false, nullptr);
      },
      "srdf: group 'a' chain[0] base_link = 'panda_link7' is not an ancestor of tip_link = 'panda_link2'");
  ExpectInvalid([&] { ReadPlanningGroups(*robot, "<robot><group name='a'>", false, nullptr); },
                "srdf: malformed XML at line 0, column 0: Error reading Element value.");
}

TEST(PlanningGroups, HoldingTheOtherJointsGivesTheSameKinematics) {
  // The arm of the mobile manipulator with its prismatic torso held at 0.3 m: every link pose of
  // the held model at g equals the full robot's at the full configuration with the arm's entries g.
  const auto robot = LoadExampleRobot("mobile_manipulator");
  std::vector<std::string> warnings;
  const PlanningGroup arm =
      ReadPlanningGroups(*robot, ReadExample("robots/mobile_manipulator.srdf"), false, &warnings).front();
  std::mt19937_64 rng(3);
  Eigen::VectorXd held = testing::RandomConfiguration(*robot, rng);
  held[0] = 0.3;
  const auto model = HoldJointsOutside(*robot, arm.dofs, held);
  ASSERT_EQ(model->num_dofs(), 7);
  ASSERT_EQ(model->num_links(), robot->num_links());
  for (int i = 0; i < 7; ++i) EXPECT_EQ(model->dof_names()[i], robot->dof_names()[arm.dofs[i]]);
  for (int trial = 0; trial < 50; ++trial) {
    const Eigen::VectorXd g = testing::RandomConfiguration(*model, rng);
    Eigen::VectorXd full = held;
    for (int i = 0; i < 7; ++i) full[arm.dofs[i]] = g[i];
    std::vector<Eigen::Isometry3d> a, b;
    model->ForwardKinematics(g, &a);
    robot->ForwardKinematics(full, &b);
    for (int link = 0; link < robot->num_links(); ++link) {
      EXPECT_LT((a[link].matrix() - b[link].matrix()).cwiseAbs().maxCoeff(), 1e-12) << robot->links()[link].name;
    }
  }
  for (int a = 0; a < robot->num_links(); ++a) {
    for (int b = 0; b < robot->num_links(); ++b) {
      EXPECT_EQ(model->allowed_collisions().IsAllowed(a, b), robot->allowed_collisions().IsAllowed(a, b));
    }
  }
  ExpectInvalid([&] { HoldJointsOutside(*robot, {1, 1}, held); },
                "HoldJointsOutside: joint index 1 is out of range or repeated");
}

TEST(PlanningGroups, HeldGroupsOfTheDualArmKeepTheirMimicFingersRight) {
  // left_gripper names both fingers; the second mimics the first, so the group is one joint and
  // its mimic moves with it. left_arm holds the grippers: the mimic finger held at its mimic value.
  const auto robot = LoadExampleRobot("dual_arm");
  std::vector<std::string> warnings;
  const std::vector<PlanningGroup> groups =
      ReadPlanningGroups(*robot, ReadExample("robots/dual_arm.srdf"), false, &warnings);
  std::mt19937_64 rng(9);
  for (const char* name : {"left_gripper", "left_arm", "both"}) {
    SCOPED_TRACE(name);
    const auto group = std::find_if(groups.begin(), groups.end(), [&](const PlanningGroup& g) { return g.name == name; });
    ASSERT_NE(group, groups.end());
    if (std::string(name) == "left_gripper") {
      ASSERT_EQ(group->dofs.size(), 1u);
      EXPECT_EQ(robot->dof_names()[group->dofs[0]], "left_finger_joint");
    }
    const Eigen::VectorXd held = testing::RandomConfiguration(*robot, rng);
    const auto model = HoldJointsOutside(*robot, group->dofs, held);
    ASSERT_EQ(model->num_dofs(), static_cast<int>(group->dofs.size()));
    for (int trial = 0; trial < 30; ++trial) {
      const Eigen::VectorXd g = testing::RandomConfiguration(*model, rng);
      Eigen::VectorXd full = held;
      for (std::size_t i = 0; i < group->dofs.size(); ++i) full[group->dofs[i]] = g[static_cast<Eigen::Index>(i)];
      std::vector<Eigen::Isometry3d> a, b;
      model->ForwardKinematics(g, &a);
      robot->ForwardKinematics(full, &b);
      for (int link = 0; link < robot->num_links(); ++link) {
        EXPECT_LT((a[link].matrix() - b[link].matrix()).cwiseAbs().maxCoeff(), 1e-12) << robot->links()[link].name;
      }
    }
  }
}

}  // namespace
}  // namespace chasles
