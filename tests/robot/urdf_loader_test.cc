// RobotModel::FromUrdf: what is read, in which order, and every validation rule with its message.

#include <cmath>

#include <gtest/gtest.h>

#include "chasles/robot/robot_model.h"
#include "test_util.h"

namespace chasles {
namespace {

using testing::ExpectInvalid;

// A small URDF whose joint and link elements are deliberately out of tree order.
std::string Urdf(const std::string& body, const std::string& name = "r") {
  return "<?xml version=\"1.0\"?>\n<robot name=\"" + name + "\">\n" + body + "</robot>\n";
}

std::string RevoluteJoint(const std::string& name, const std::string& parent, const std::string& child,
                          const std::string& limit = "<limit lower=\"-1\" upper=\"1\" velocity=\"1\" effort=\"5\"/>",
                          const std::string& type = "revolute") {
  return "  <joint name=\"" + name + "\" type=\"" + type + "\"><parent link=\"" + parent +
         "\"/><child link=\"" + child + "\"/><origin xyz=\"0 0 0.1\"/><axis xyz=\"0 0 1\"/>" + limit +
         "</joint>\n";
}

std::string Links(std::initializer_list<const char*> names) {
  std::string s;
  for (const char* n : names) s += std::string("  <link name=\"") + n + "\"/>\n";
  return s;
}

TEST(UrdfLoaderTest, JointOrderIsDepthFirstFromTheRootWithChildrenInDocumentOrder) {
  // Document order: z_joint (base->z), b_to_c (b->c), a_joint (base->b).
  // Depth-first from base: z_joint, a_joint, b_to_c. (urdfdom alone would sort by name.)
  const std::string urdf =
      Urdf(Links({"c", "base", "z", "b"}) + RevoluteJoint("z_joint", "base", "z") +
           RevoluteJoint("b_to_c", "b", "c") + RevoluteJoint("a_joint", "base", "b"));
  const auto robot = RobotModel::FromUrdf(urdf);
  EXPECT_EQ(robot->name(), "r");
  EXPECT_EQ(robot->dof_names(), (std::vector<std::string>{"z_joint", "a_joint", "b_to_c"}));
  ASSERT_EQ(robot->num_links(), 4);
  EXPECT_EQ(robot->links()[0].name, "base");
  EXPECT_EQ(robot->root_link(), 0);
  // Link i + 1 is the child of joint i.
  for (size_t j = 0; j < robot->joints().size(); ++j) {
    EXPECT_EQ(robot->joints()[j].child_link, static_cast<int>(j) + 1);
  }
  EXPECT_EQ(robot->links()[3].name, "c");
  EXPECT_EQ(robot->link_chain(3), (std::vector<int>{1, 2}));
}

TEST(UrdfLoaderTest, ReadsGeometryInertiaLimitsAndJointTypes) {
  auto mesh = std::make_shared<TriangleMesh>();
  mesh->vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  mesh->triangles = {{0, 1, 2}};
  const std::string urdf = Urdf(R"(
  <link name="base">
    <inertial><origin xyz="0.1 0.2 0.3" rpy="0 0 1.5707963267948966"/><mass value="2.5"/>
      <inertia ixx="1" ixy="0" ixz="0" iyy="2" iyz="0" izz="3"/></inertial>
    <collision><origin xyz="0 0 0.1"/><geometry><sphere radius="0.2"/></geometry></collision>
    <collision><geometry><box size="0.1 0.2 0.3"/></geometry></collision>
    <collision><geometry><cylinder radius="0.05" length="0.4"/></geometry></collision>
    <collision><geometry><mesh filename="package://r/tri.stl" scale="2 3 4"/></geometry></collision>
  </link>
  <link name="a"/><link name="b"/><link name="c"/>
  <joint name="spin" type="continuous"><parent link="base"/><child link="a"/>
    <axis xyz="0 0 2"/><limit velocity="3" effort="1"/></joint>
  <joint name="slide" type="prismatic"><parent link="a"/><child link="b"/>
    <axis xyz="1 0 0"/><limit lower="-0.5" upper="0.25" velocity="0.5" effort="100"/></joint>
  <joint name="weld" type="fixed"><parent link="b"/><child link="c"/><origin xyz="1 2 3"/></joint>
)");
  const auto robot = RobotModel::FromUrdf(urdf, {}, {{"package://r/tri.stl", mesh}});
  ASSERT_EQ(robot->num_dofs(), 2);
  const Link& base = robot->links()[0];
  ASSERT_EQ(base.collision.size(), 4u);
  EXPECT_EQ(base.collision[0].type, ShapeType::kSphere);
  EXPECT_DOUBLE_EQ(base.collision[0].radius, 0.2);
  EXPECT_DOUBLE_EQ(base.collision[0].pose.translation().z(), 0.1);
  EXPECT_EQ(base.collision[1].type, ShapeType::kBox);
  EXPECT_EQ(base.collision[1].size, Eigen::Vector3d(0.1, 0.2, 0.3));
  EXPECT_EQ(base.collision[2].type, ShapeType::kCylinder);
  EXPECT_DOUBLE_EQ(base.collision[2].radius, 0.05);
  EXPECT_DOUBLE_EQ(base.collision[2].length, 0.4);
  EXPECT_EQ(base.collision[3].type, ShapeType::kMesh);
  ASSERT_TRUE(base.collision[3].mesh);
  EXPECT_EQ(base.collision[3].mesh->vertices[1], Eigen::Vector3d(2, 0, 0));
  EXPECT_EQ(base.collision[3].mesh->vertices[2], Eigen::Vector3d(0, 3, 0));
  EXPECT_EQ(mesh->vertices[1], Eigen::Vector3d(1, 0, 0)) << "the supplied mesh is not modified";
  ASSERT_TRUE(base.inertial.has_value());
  EXPECT_DOUBLE_EQ(base.inertial->mass, 2.5);
  EXPECT_LT((base.inertial->com - Eigen::Vector3d(0.1, 0.2, 0.3)).norm(), 1e-15);
  // Inertia frame turned by 90° about z: ixx and iyy swap in link axes.
  EXPECT_NEAR(base.inertial->inertia(0, 0), 2.0, 1e-12);
  EXPECT_NEAR(base.inertial->inertia(1, 1), 1.0, 1e-12);
  EXPECT_NEAR(base.inertial->inertia(2, 2), 3.0, 1e-12);
  EXPECT_FALSE(robot->links()[1].inertial.has_value());

  EXPECT_EQ(robot->joints()[0].type, JointType::kContinuous);
  EXPECT_EQ(robot->joints()[0].axis, Eigen::Vector3d::UnitZ());
  EXPECT_DOUBLE_EQ(robot->lower_limits()[0], -M_PI);
  EXPECT_DOUBLE_EQ(robot->upper_limits()[0], M_PI);
  EXPECT_DOUBLE_EQ(robot->velocity_limits()[0], 3.0);
  EXPECT_EQ(robot->joints()[1].type, JointType::kPrismatic);
  EXPECT_DOUBLE_EQ(robot->lower_limits()[1], -0.5);
  EXPECT_DOUBLE_EQ(robot->upper_limits()[1], 0.25);
  EXPECT_DOUBLE_EQ(robot->velocity_limits()[1], 0.5);
  EXPECT_DOUBLE_EQ(robot->effort_limits()[1], 100.0);
  EXPECT_EQ(robot->joints()[2].type, JointType::kFixed);
  EXPECT_EQ(robot->joints()[2].dof, -1);
  EXPECT_EQ(robot->home_pose(3).translation(), Eigen::Vector3d(1, 2, 3));
}

TEST(UrdfLoaderTest, RejectsMalformedXmlSayingWhere) {
  ExpectInvalid([] { RobotModel::FromUrdf("<robot name=\"r\">\n  <link name=\"a\">\n</robot>\n"); },
                "urdf: malformed XML at line 3, column 1: Error reading end tag.");
  ExpectInvalid([] { RobotModel::FromUrdf("<robot name=\"r\"><link name=\"a\"/ ></robot>"); },
                "urdf: malformed XML at line 1, column 32: Error: empty tag.");
  ExpectInvalid([] { RobotModel::FromUrdf(" \n"); }, "urdf: document is empty");
}

TEST(UrdfLoaderTest, ReportsUrdfdomErrors) {
  ExpectInvalid([] { RobotModel::FromUrdf("<robot_x name=\"r\"/>"); },
                "urdf: Could not find the 'robot' element in the xml file");
  ExpectInvalid([] { RobotModel::FromUrdf(Urdf(Links({"a", "b"}) + RevoluteJoint("j", "a", "b", ""))); },
                "urdf: Joint [j] is of type REVOLUTE but it does not specify limits");
}

TEST(UrdfLoaderTest, RejectsPlanarAndFloatingJoints) {
  ExpectInvalid(
      [] { RobotModel::FromUrdf(Urdf(Links({"a", "b"}) + RevoluteJoint("base_xy", "a", "b", "", "planar"))); },
      "urdf: joint 'base_xy' has type planar; only revolute, continuous, prismatic and fixed joints "
      "are supported");
  ExpectInvalid(
      [] { RobotModel::FromUrdf(Urdf(Links({"a", "b"}) + RevoluteJoint("free", "a", "b", "", "floating"))); },
      "urdf: joint 'free' has type floating; only revolute, continuous, prismatic and fixed joints "
      "are supported");
}

TEST(UrdfLoaderTest, RejectsBadLimits) {
  auto with_limit = [](const std::string& limit, const std::string& type = "revolute") {
    return Urdf(Links({"a", "b"}) + RevoluteJoint("elbow", "a", "b", limit, type));
  };
  ExpectInvalid([&] { RobotModel::FromUrdf(with_limit(R"(<limit lower="2" upper="1" velocity="1" effort="1"/>)")); },
                "urdf: joint 'elbow' limit lower = 2 > upper = 1");
  ExpectInvalid([&] { RobotModel::FromUrdf(with_limit(R"(<limit lower="0.5" upper="0.25" velocity="1" effort="1"/>)", "prismatic")); },
                "urdf: joint 'elbow' limit lower = 0.5 > upper = 0.25");
  ExpectInvalid([&] { RobotModel::FromUrdf(with_limit(R"(<limit lower="-1" upper="1" velocity="0" effort="1"/>)")); },
                "urdf: joint 'elbow' limit velocity = 0 must be > 0 and finite");
  ExpectInvalid([&] { RobotModel::FromUrdf(with_limit(R"(<limit lower="-1" upper="1" velocity="-2.5" effort="1"/>)")); },
                "urdf: joint 'elbow' limit velocity = -2.5 must be > 0 and finite");
  ExpectInvalid([&] { RobotModel::FromUrdf(with_limit(R"(<limit velocity="0" effort="1"/>)", "continuous")); },
                "urdf: joint 'elbow' limit velocity = 0 must be > 0 and finite");
  ExpectInvalid([&] { RobotModel::FromUrdf(with_limit("", "continuous")); },
                "urdf: joint 'elbow' has no <limit>; limit velocity must be > 0 and finite");
  ExpectInvalid([&] { RobotModel::FromUrdf(with_limit(R"(<limit lower="-1" upper="1" velocity="1" effort="-1"/>)")); },
                "urdf: joint 'elbow' limit effort = -1 must be >= 0 and finite");
  // lower == upper is a legal (locked) joint.
  EXPECT_NO_THROW(RobotModel::FromUrdf(with_limit(R"(<limit lower="0.5" upper="0.5" velocity="1" effort="1"/>)")));
}

TEST(UrdfLoaderTest, RejectsUnknownMeshesAndBadPrimitives) {
  const std::string urdf = Urdf(R"(
  <link name="a"><collision><geometry><sphere radius="0.1"/></geometry></collision>
    <collision><geometry><mesh filename="package://r/hand.stl"/></geometry></collision></link>
)");
  ExpectInvalid([&] { RobotModel::FromUrdf(urdf); },
                "urdf: link 'a' collision[1] mesh filename 'package://r/hand.stl' is not in the "
                "supplied meshes");
  ExpectInvalid(
      [] {
        RobotModel::FromUrdf(Urdf(R"(<link name="a"><collision><geometry><box size="0.1 0 0.1"/></geometry></collision></link>)"));
      },
      "urdf: link 'a' collision[0] box size y = 0 must be > 0 and finite");
}

TEST(UrdfLoaderTest, AMimicJointIsReportedAsPlannedIndependently) {
  // <mimic> is not modelled yet: the joint keeps a coordinate of its own, and the load says so.
  const std::string urdf =
      Urdf(Links({"base", "left", "right"}) + RevoluteJoint("left_finger", "base", "left") +
               RevoluteJoint("right_finger", "base", "right",
                             "<limit lower=\"-1\" upper=\"1\" velocity=\"1\" effort=\"5\"/>"
                             "<mimic joint=\"left_finger\" multiplier=\"-1\" offset=\"0.25\"/>"),
           "gripper");
  const auto robot = RobotModel::FromUrdf(urdf);
  EXPECT_EQ(robot->num_dofs(), 2);
  ASSERT_EQ(robot->load_warnings().size(), 1u);
  EXPECT_EQ(robot->load_warnings()[0],
            "urdf: joint 'right_finger' mimics joint 'left_finger' (multiplier -1, offset 0.25); Chasles plans it "
            "as an independent joint (its own coordinate)");
}

TEST(UrdfLoaderTest, SrdfDisablesPairsAndRejectsUnknownLinks) {
  const std::string urdf = Urdf(Links({"base", "a", "b"}) + RevoluteJoint("j1", "base", "a") +
                                    RevoluteJoint("j2", "a", "b"),
                                "panda");
  const auto robot = RobotModel::FromUrdf(
      urdf, R"(<robot name="panda"><disable_collisions link1="base" link2="b" reason="Never"/></robot>)");
  EXPECT_TRUE(robot->allowed_collisions().IsAllowed(0, 2));
  EXPECT_TRUE(robot->allowed_collisions().IsAllowed(2, 0));

  const std::string srdf = R"(<?xml version="1.0"?>
<robot name="panda">
  <group name="arm"/>
  <disable_collisions link1="base" link2="a"/>
  <disable_collisions link1="a" link2="b"/>
  <disable_collisions link1="base" link2="b"/>
  <disable_collisions link1="a" link2="hand"/>
</robot>)";
  // A pair naming a link the URDF lacks (published SRDFs keep them): skipped with a warning,
  // the other pairs honoured; strict_srdf makes it the error it names.
  const auto lenient = RobotModel::FromUrdf(urdf, srdf);
  ASSERT_EQ(lenient->load_warnings().size(), 1u);
  EXPECT_EQ(lenient->load_warnings()[0],
            "srdf: disable_collisions[3] link2 = 'hand' is not a link of robot 'panda'; the pair is skipped");
  EXPECT_TRUE(lenient->allowed_collisions().IsAllowed(0, 2));
  EXPECT_TRUE(robot->load_warnings().empty());
  ExpectInvalid([&] { RobotModel::FromUrdf(urdf, srdf, {}, {}, /*strict_srdf=*/true); },
                "srdf: disable_collisions[3] link2 = 'hand' is not a link of robot 'panda'");
  const auto both_unknown =
      RobotModel::FromUrdf(urdf, R"(<robot><disable_collisions link1="arm" link2="leg"/></robot>)");
  ASSERT_EQ(both_unknown->load_warnings().size(), 1u);  // one warning per skipped pair
  EXPECT_EQ(both_unknown->load_warnings()[0],
            "srdf: disable_collisions[0] link1 = 'arm' is not a link of robot 'panda'; the pair is skipped");
  ExpectInvalid(
      [&] {
        RobotModel::FromUrdf(urdf, R"(<robot><disable_collisions link1="arm" link2="b"/></robot>)", {}, {}, true);
      },
      "srdf: disable_collisions[0] link1 = 'arm' is not a link of robot 'panda'");
  ExpectInvalid([&] { RobotModel::FromUrdf(urdf, R"(<robot><disable_collisions link1="a"/></robot>)"); },
                "srdf: disable_collisions[0] link2 is missing");
  ExpectInvalid([&] { RobotModel::FromUrdf(urdf, "<robot>\n<disable_collisions link1=\"a\" link2=\"b\">\n</robot>"); },
                "srdf: malformed XML at line 3, column 1: Error reading end tag.");
  ExpectInvalid([&] { RobotModel::FromUrdf(urdf, "<model/>"); },
                "srdf: root element is <model>, expected <robot>");
}

TEST(UrdfLoaderTest, ExampleRobotsLoad) {
  for (const char* name : {"planar_2r", "ur5", "panda"}) {
    const auto robot = testing::LoadExampleRobot(name);
    EXPECT_EQ(robot->name(), name);
  }
}

}  // namespace
}  // namespace chasles
