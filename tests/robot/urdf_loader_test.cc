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

TEST(UrdfLoaderTest, NamesEveryCollisionMeshThatWasNotSuppliedInOneError) {
  const std::string mesh = [](const char* file) {
    return std::string("<collision><geometry><mesh filename=\"") + file + "\"/></geometry></collision>";
  }("package://r/a.stl");
  const std::string urdf = Urdf(std::string("  <link name=\"base\">") + mesh + "</link>\n" +
                                "  <link name=\"arm\"><collision><geometry><mesh filename=\"package://r/b.stl\"/>"
                                "</geometry></collision><visual><geometry><mesh filename=\"package://r/v.dae\"/>"
                                "</geometry></visual></link>\n" +
                                RevoluteJoint("j", "base", "arm"));
  ExpectInvalid([&] { RobotModel::FromUrdf(urdf); },
                "urdf: 2 collision meshes are not in the supplied meshes: link 'base' collision[0] mesh filename "
                "'package://r/a.stl'; link 'arm' collision[0] mesh filename 'package://r/b.stl'");
  // The resolver is asked for collision meshes only (never the visual one), once per use.
  std::vector<std::string> asked;
  const auto cube = std::make_shared<TriangleMesh>();
  cube->vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  cube->triangles = {{0, 1, 2}, {0, 1, 3}, {0, 2, 3}, {1, 2, 3}};
  const auto model = RobotModel::FromUrdfResolvingMeshes(urdf, {}, [&](const std::string& name) {
    asked.push_back(name);
    return cube;
  });
  EXPECT_EQ(asked, (std::vector<std::string>{"package://r/a.stl", "package://r/b.stl"}));
  EXPECT_EQ(model->links()[0].collision.size(), 1u);
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
                "urdf: 1 collision mesh is not in the supplied meshes: link 'a' collision[1] mesh filename "
                "'package://r/hand.stl'");
  ExpectInvalid(
      [] {
        RobotModel::FromUrdf(Urdf(R"(<link name="a"><collision><geometry><box size="0.1 0 0.1"/></geometry></collision></link>)"));
      },
      "urdf: link 'a' collision[0] box size y = 0 must be > 0 and finite");
}

std::string Mimic(const std::string& joint, const std::string& multiplier = "1", const std::string& offset = "0") {
  return "<mimic joint=\"" + joint + "\" multiplier=\"" + multiplier + "\" offset=\"" + offset + "\"/>";
}
const char* kLimit = "<limit lower=\"-1\" upper=\"1\" velocity=\"1\" effort=\"5\"/>";

TEST(UrdfLoaderTest, AMimicJointHasNoCoordinateOfItsOwn) {
  // right_finger = -left_finger + 0.25 has no coordinate; left_finger's limits [-1, 1] are
  // narrowed to [-0.75, 1] so that right_finger stays within its own [-1, 1].
  const std::string urdf =
      Urdf(Links({"base", "left", "right"}) + RevoluteJoint("left_finger", "base", "left") +
               RevoluteJoint("right_finger", "base", "right", kLimit + Mimic("left_finger", "-1", "0.25")),
           "gripper");
  const auto robot = RobotModel::FromUrdf(urdf);
  EXPECT_EQ(robot->num_dofs(), 1);
  EXPECT_EQ(robot->num_moving_joints(), 2);
  EXPECT_EQ(robot->dof_names(), std::vector<std::string>{"left_finger"});
  const Joint& right = robot->joints()[1];
  ASSERT_TRUE(right.mimic.has_value());
  EXPECT_EQ(right.mimic->joint, 0);
  EXPECT_EQ(right.mimic->multiplier, -1.0);
  EXPECT_EQ(right.mimic->offset, 0.25);
  EXPECT_EQ(right.dof, 0);
  EXPECT_EQ(right.Position(Eigen::VectorXd::Constant(1, 0.5)), -0.25);
  EXPECT_EQ(robot->lower_limits()[0], -0.75);
  EXPECT_EQ(robot->upper_limits()[0], 1.0);
  EXPECT_EQ(robot->joints()[1].limits.lower, -1.0);  // the mimic joint keeps its own
  EXPECT_EQ(robot->link_chain(2), std::vector<int>{1});  // moving joint 1 (right_finger) moves 'right'
  EXPECT_EQ(robot->load_warnings(),
            std::vector<std::string>{"robot 'gripper': joint 'left_finger' limits [-1, 1] narrowed to [-0.75, 1] so "
                                     "that its mimic joint 'right_finger' = -1 · 'left_finger' + 0.25 stays within [-1, 1]"});
  // A configuration of the narrowed range is the one validated.
  ExpectInvalid([&] { robot->ValidateConfiguration(Eigen::VectorXd::Constant(1, -0.8), "q"); },
                "q[0] = -0.8 must be within [-0.75, 1] (joint 'left_finger')");
}

TEST(UrdfLoaderTest, MimicChainsResolveToTheActuatedJointWhateverTheDocumentOrder) {
  // c = 0.5·b + 0.1, b = 2·a − 0.2 (b listed before a, c before b): c = a − 0.1 + 0.1 = a.
  const std::string limit = "<limit lower=\"-3\" upper=\"3\" velocity=\"5\" effort=\"5\"/>";
  const std::string urdf = Urdf(Links({"base", "la", "lb", "lc"}) +
                                RevoluteJoint("c", "base", "lc", limit + Mimic("b", "0.5", "0.1")) +
                                RevoluteJoint("b", "base", "lb", limit + Mimic("a", "2", "-0.2")) +
                                RevoluteJoint("a", "base", "la"));
  const auto robot = RobotModel::FromUrdf(urdf);
  ASSERT_EQ(robot->dof_names(), std::vector<std::string>{"a"});
  const Joint& c = robot->joints()[0];
  ASSERT_EQ(c.name, "c");
  ASSERT_TRUE(c.mimic.has_value());
  EXPECT_EQ(robot->joints()[c.mimic->joint].name, "a");
  EXPECT_EQ(c.mimic->multiplier, 1.0);
  EXPECT_NEAR(c.mimic->offset, 0.0, 1e-16);
  EXPECT_EQ(c.dof, 0);
  // b = 2a − 0.2 within [-3, 3]: a within [-1.4, 1.6] ⊇ [-1, 1]; no narrowing, no warning.
  EXPECT_TRUE(robot->load_warnings().empty());
  // Continuous and fixed: a continuous mimic has no position limits to narrow with; <mimic> on a
  // fixed joint is ignored (it does not move).
  const auto cont = RobotModel::FromUrdf(
      Urdf(Links({"base", "la", "lb", "lf"}) + RevoluteJoint("a", "base", "la") +
           RevoluteJoint("b", "base", "lb", "<limit velocity=\"3\" effort=\"1\"/>" + Mimic("a", "3"), "continuous") +
           "<joint name=\"f\" type=\"fixed\"><parent link=\"base\"/><child link=\"lf\"/>" + Mimic("a") + "</joint>\n"));
  EXPECT_EQ(cont->num_dofs(), 1);
  EXPECT_EQ(cont->lower_limits()[0], -1.0);
  EXPECT_FALSE(cont->joints()[2].mimic.has_value());
  EXPECT_EQ(cont->joints()[2].dof, -1);
  EXPECT_TRUE(cont->load_warnings().empty());
}

TEST(UrdfLoaderTest, AMimicWithAFasterMultiplierLowersTheVelocityLimit) {
  // b = 3·a at most 1 rad/s: a at most 1/3 rad/s.
  const std::string urdf =
      Urdf(Links({"base", "la", "lb"}) + RevoluteJoint("a", "base", "la") +
           RevoluteJoint("b", "base", "lb", "<limit lower=\"-3\" upper=\"3\" velocity=\"1\" effort=\"5\"/>" + Mimic("a", "3")));
  const auto robot = RobotModel::FromUrdf(urdf);
  EXPECT_DOUBLE_EQ(robot->velocity_limits()[0], 1.0 / 3.0);
  ASSERT_EQ(robot->load_warnings().size(), 1u);
  EXPECT_EQ(robot->load_warnings()[0].rfind("robot 'r': joint 'a' velocity limit 1 lowered to 0.333", 0), 0u)
      << robot->load_warnings()[0];
}

TEST(UrdfLoaderTest, RejectsMimicJointsThatCannotBeModelled) {
  const auto gripper = [](const std::string& mimic, const std::string& limit = kLimit) {
    return Urdf(Links({"base", "left", "right", "palm"}) + RevoluteJoint("left", "base", "left") +
                "<joint name=\"palm_joint\" type=\"fixed\"><parent link=\"base\"/><child link=\"palm\"/></joint>\n" +
                RevoluteJoint("right", "base", "right", limit + mimic));
  };
  ExpectInvalid([&] { RobotModel::FromUrdf(gripper(Mimic("thumb"))); },
                "urdf: joint 'right' mimics joint 'thumb', which is not a joint of robot 'r'; a mimic joint must "
                "follow a revolute, continuous or prismatic joint of the robot");
  ExpectInvalid([&] { RobotModel::FromUrdf(gripper(Mimic("palm_joint"))); },
                "urdf: joint 'right' mimics joint 'palm_joint', which is fixed; a mimic joint must follow a revolute, "
                "continuous or prismatic joint");
  ExpectInvalid([&] { RobotModel::FromUrdf(gripper(Mimic("right"))); },
                "urdf: joint 'right' mimics itself; a mimic joint must follow another joint");
  ExpectInvalid([&] { RobotModel::FromUrdf(gripper(Mimic("left", "0"))); },
                "urdf: joint 'right' mimic multiplier = 0 must be finite and non-zero (a joint that never moves is a "
                "fixed joint)");
  ExpectInvalid([&] { RobotModel::FromUrdf(gripper(Mimic("left", "nan"))); },
                "urdf: joint 'right' mimic multiplier = nan must be finite and non-zero (a joint that never moves is a "
                "fixed joint)");
  ExpectInvalid([&] { RobotModel::FromUrdf(gripper(Mimic("left", "1e400"))); },
                "urdf: joint 'right' mimic multiplier = inf must be finite and non-zero (a joint that never moves is a "
                "fixed joint)");
  ExpectInvalid([&] { RobotModel::FromUrdf(gripper(Mimic("left", "1", "-inf"))); },
                "urdf: joint 'right' mimic offset = -inf must be finite");
  // right = left + 5 within [-1, 1] needs left within [-6, -4]: outside left's [-1, 1].
  ExpectInvalid([&] { RobotModel::FromUrdf(gripper(Mimic("left", "1", "5"))); },
                "robot 'r': joint[2] 'right' is a mimic joint ('right' = 1 · 'left' + 5) and no value of 'left' "
                "within [-1, 1] keeps it within its limits [-1, 1]");
  // Two joints that mimic each other: nothing drives them.
  ExpectInvalid(
      [] {
        RobotModel::FromUrdf(Urdf(Links({"base", "la", "lb"}) + RevoluteJoint("a", "base", "la", kLimit + Mimic("b")) +
                                  RevoluteJoint("b", "base", "lb", kLimit + Mimic("a"))));
      },
      "robot 'r': joint[0] 'a' follows a cycle of mimic joints ('a' -> 'b' -> 'a'); a chain of mimic joints must end "
      "at a joint that is not a mimic");
}

TEST(UrdfLoaderTest, FromTreeValidatesMimicJoints) {
  Link base, a, b;
  base.name = "base";
  a.name = "a";
  b.name = "b";
  Joint ja, jb;
  ja.name = "ja";
  ja.type = JointType::kRevolute;
  ja.parent_link = 0;
  ja.child_link = 1;
  ja.limits = {-1.0, 1.0, 1.0, 0.0};
  jb = ja;
  jb.name = "jb";
  jb.child_link = 2;
  jb.mimic = JointMimic{7, 1.0, 0.0};
  ExpectInvalid([&] { RobotModel::FromTree("t", {base, a, b}, {ja, jb}); },
                "robot 't': joint[1] 'jb' mimic.joint = 7 must be the index of another joint, within [0, 2)");
  jb.mimic = JointMimic{0, 0.0, 0.0};
  ExpectInvalid([&] { RobotModel::FromTree("t", {base, a, b}, {ja, jb}); },
                "robot 't': joint[1] 'jb' mimic multiplier = 0 must be finite and non-zero (a joint that never moves "
                "is a fixed joint)");
  jb.mimic = JointMimic{0, 1e300, 0.0};
  Joint jc = jb;
  jc.name = "jc";
  jc.child_link = 3;
  jc.mimic = JointMimic{1, 1e300, 0.0};  // 1e300 · 1e300 overflows
  Link c;
  c.name = "c";
  ExpectInvalid([&] { RobotModel::FromTree("t", {base, a, b, c}, {ja, jb, jc}); },
                "robot 't': joint[2] 'jc' follows joint 'ja' through a chain of mimic joints with multiplier inf and "
                "offset 0; both must be finite and the multiplier non-zero");
  // A model rebuilt from a model's joints is the same model, with no warning repeated.
  jb.mimic = JointMimic{0, -2.0, 0.5};
  const auto first = RobotModel::FromTree("t", {base, a, b}, {ja, jb});
  ASSERT_EQ(first->load_warnings().size(), 2u);  // position and velocity limits narrowed
  const auto again = RobotModel::FromTree("t", first->links(), first->joints(), {}, {}, first->load_warnings());
  EXPECT_EQ(again->load_warnings(), first->load_warnings());
  EXPECT_EQ(again->lower_limits(), first->lower_limits());
  EXPECT_EQ(again->upper_limits(), first->upper_limits());
  EXPECT_EQ(again->velocity_limits(), first->velocity_limits());
  EXPECT_EQ(first->lower_limits()[0], -0.25);  // −2a + 0.5 ∈ [-1, 1] ⇔ a ∈ [-0.25, 0.75]
  EXPECT_EQ(first->upper_limits()[0], 0.75);
  EXPECT_EQ(first->velocity_limits()[0], 0.5);
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
  for (const char* name : {"planar_2r", "ur5", "panda", "dual_arm", "ur5_gripper"}) {
    const auto robot = testing::LoadExampleRobot(name);
    EXPECT_EQ(robot->name(), name);
  }
}

}  // namespace
}  // namespace chasles
