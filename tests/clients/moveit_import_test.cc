// The MoveIt YAML importer (clients/src/moveit_import.h) and `chasles import-moveit`: every field it
// reads from hand-written PlanningScene / MotionPlanRequest files (tests/clients/data/), composed
// poses and quaternion order checked numerically, allowed-collision pairs, the start overlay and
// goal, named errors, problem directories, the CLI's JSON, and the example problems
// (examples/moveit/) planned through an in-process server.

#include "moveit_import.h"

#include <google/protobuf/util/json_util.h>
#include <google/protobuf/util/message_differencer.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <octomap/AbstractOcTree.h>
#include <octomap/OcTree.h>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "../server/server_fixture.h"
#include "chasles/collision/collision_checker.h"
#include "chasles/collision/mesh.h"
#include "chasles/robot/error.h"
#include "chasles/server/convert.h"

namespace chasles {
namespace {

using moveit::DefaultRobot;
using moveit::ImportMotionPlanRequest;
using moveit::ImportPlanningScene;
using moveit::RobotInfo;

constexpr double kTight = 1e-12;

std::string DataPath(const std::string& name) {
  return std::string(CHASLES_SOURCE_DIR) + "/tests/clients/data/" + name;
}
std::string ExamplesDir() { return std::string(CHASLES_SOURCE_DIR) + "/examples/moveit"; }
std::string Data(const std::string& name) { return testing::ReadText(DataPath(name)); }

const RobotInfo& Panda() {
  static const RobotInfo robot = DefaultRobot();
  return robot;
}

/// The message of the Error(kInvalidArgument) that `call` throws ("" and a failure when none).
std::string ErrorOf(const std::function<void()>& call) {
  try {
    call();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument) << e.what();
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "not a chasles::Error: " << e.what();
    return e.what();
  }
  ADD_FAILURE() << "no error thrown";
  return "";
}

std::string SceneError(const std::string& yaml) {
  return ErrorOf([&] { ImportPlanningScene(yaml, Panda(), "scene.yaml"); });
}

/// The request error with the full scene and a request text.
std::string RequestError(const std::string& scene, const std::string& request) {
  return ErrorOf([&] { ImportMotionPlanRequest(scene, request, Panda(), "scene.yaml", "request.yaml"); });
}

/// `text` with the first occurrence of `from` replaced by `to` (the edit must apply).
std::string Replace(std::string text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << "'" << from << "' not in the fixture";
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

Eigen::Isometry3d ToIsometry(const v1::Pose& pose) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() = Eigen::Vector3d(pose.position().x(), pose.position().y(), pose.position().z());
  const v1::Quaternion& q = pose.orientation();
  t.linear() = Eigen::Quaterniond(q.w(), q.x(), q.y(), q.z()).toRotationMatrix();
  return t;
}

template <typename Shapes>
const typename Shapes::value_type* Named(const Shapes& shapes, const std::string& name) {
  for (const auto& shape : shapes) {
    if (shape.name() == name) return &shape;
  }
  ADD_FAILURE() << "no shape named '" << name << "'";
  return nullptr;
}

std::vector<double> Values(const google::protobuf::RepeatedField<double>& values) {
  return std::vector<double>(values.begin(), values.end());
}

// ---------------------------------------------------------------------------------------------
// Robot

TEST(MoveItRobot, DefaultIsThePandaInConfigurationOrder) {
  const RobotInfo& robot = Panda();
  EXPECT_EQ(robot.joint_names, (std::vector<std::string>{"panda_joint1", "panda_joint2", "panda_joint3", "panda_joint4",
                                                         "panda_joint5", "panda_joint6", "panda_joint7"}));
  EXPECT_EQ(robot.root_link, "panda_link0");
  EXPECT_EQ(robot.link_names.front(), "panda_link0");
  EXPECT_NE(std::find(robot.link_names.begin(), robot.link_names.end(), "panda_hand"), robot.link_names.end());
  EXPECT_TRUE(robot.model.has_urdf());
  // SRDF pair and an adjacent pair are known as allowed; sorted for lookup.
  EXPECT_TRUE(std::binary_search(robot.allowed_link_pairs.begin(), robot.allowed_link_pairs.end(),
                                 std::make_pair(std::string("panda_hand"), std::string("panda_link7"))));
  EXPECT_TRUE(std::binary_search(robot.allowed_link_pairs.begin(), robot.allowed_link_pairs.end(),
                                 std::make_pair(std::string("panda_link0"), std::string("panda_link1"))));
  EXPECT_TRUE(std::is_sorted(robot.allowed_link_pairs.begin(), robot.allowed_link_pairs.end()));
}

TEST(MoveItRobot, FromUrdfReadsAnotherRobot) {
  const std::string urdf = testing::ReadText(std::string(CHASLES_SOURCE_DIR) + "/examples/robots/ur5.urdf");
  const std::string srdf = testing::ReadText(std::string(CHASLES_SOURCE_DIR) + "/examples/robots/ur5.srdf");
  const RobotInfo robot = moveit::RobotFromUrdf(urdf, srdf);
  EXPECT_EQ(robot.joint_names.size(), 6u);
  EXPECT_EQ(robot.model.urdf().urdf(), urdf);
  EXPECT_EQ(robot.model.urdf().srdf(), srdf);
  EXPECT_NE(ErrorOf([] { moveit::RobotFromUrdf("<robot", ""); }).find("robot.urdf"), std::string::npos);
}

// ---------------------------------------------------------------------------------------------
// Scene: shapes and poses

class FullScene : public ::testing::Test {
 protected:
  void SetUp() override { scene_ = ImportPlanningScene(Data("scene_full.yaml"), Panda(), "scene_full.yaml"); }
  v1::Scene scene_;
};

TEST_F(FullScene, EveryObjectBecomesNamedShapes) {
  std::vector<std::string> boxes, spheres, cylinders, meshes;
  for (const auto& b : scene_.boxes()) boxes.push_back(b.name());
  for (const auto& s : scene_.spheres()) spheres.push_back(s.name());
  for (const auto& c : scene_.cylinders()) cylinders.push_back(c.name());
  for (const auto& m : scene_.meshes()) meshes.push_back(m.name());
  EXPECT_EQ(boxes, (std::vector<std::string>{"rotated_box", "quarter_turn", "tray/0"}));
  EXPECT_EQ(spheres, (std::vector<std::string>{"ball", "tray/1"}));
  EXPECT_EQ(cylinders, (std::vector<std::string>{"can", "cup"}));
  EXPECT_EQ(meshes, (std::vector<std::string>{"wedge"}));
  EXPECT_EQ(scene_.capsules_size(), 0);
  EXPECT_EQ(scene_.octomaps_size(), 0);  // the scene's octomap has no data
  // The server accepts the scene as it is.
  EXPECT_NO_THROW(SceneFromProto(scene_, "scene"));
}

TEST_F(FullScene, ObjectPoseComposesWithPrimitivePose) {
  // object: (1, 0, 0), 90° about z; primitive: (0.1, 0.2, 0.3), 90° about x.
  const v1::Box* box = Named(scene_.boxes(), "rotated_box");
  ASSERT_NE(box, nullptr);
  const v1::Pose& pose = box->pose();
  EXPECT_NEAR(pose.position().x(), 0.8, kTight);  // 1 + Rz(90°)·(0.1, 0.2, 0.3) = (0.8, 0.1, 0.3)
  EXPECT_NEAR(pose.position().y(), 0.1, kTight);
  EXPECT_NEAR(pose.position().z(), 0.3, kTight);
  // Rz(90°)·Rx(90°) = quaternion (x, y, z, w) = (0.5, 0.5, 0.5, 0.5).
  EXPECT_NEAR(pose.orientation().x(), 0.5, kTight);
  EXPECT_NEAR(pose.orientation().y(), 0.5, kTight);
  EXPECT_NEAR(pose.orientation().z(), 0.5, kTight);
  EXPECT_NEAR(pose.orientation().w(), 0.5, kTight);
  const Eigen::Matrix3d r = ToIsometry(pose).linear();
  EXPECT_TRUE(r.col(0).isApprox(Eigen::Vector3d(0, 1, 0), 1e-12)) << r;  // local x -> world y
  EXPECT_TRUE(r.col(1).isApprox(Eigen::Vector3d(0, 0, 1), 1e-12)) << r;  // local y -> world z
  EXPECT_TRUE(r.col(2).isApprox(Eigen::Vector3d(1, 0, 0), 1e-12)) << r;  // local z -> world x
}

TEST_F(FullScene, QuaternionsAreXyzw) {
  // {x: 0, y: 0, z: 0.7071, w: 0.7071} is 90° about z (read as w, x, y, z it would be a half turn).
  const v1::Box* box = Named(scene_.boxes(), "quarter_turn");
  ASSERT_NE(box, nullptr);
  const Eigen::Matrix3d r = ToIsometry(box->pose()).linear();
  EXPECT_TRUE((r * Eigen::Vector3d::UnitX()).isApprox(Eigen::Vector3d::UnitY(), 1e-12)) << r;
  EXPECT_TRUE((r * Eigen::Vector3d::UnitZ()).isApprox(Eigen::Vector3d::UnitZ(), 1e-12)) << r;
  // Normalised on import.
  const v1::Quaternion& q = box->pose().orientation();
  EXPECT_NEAR(q.x() * q.x() + q.y() * q.y() + q.z() * q.z() + q.w() * q.w(), 1.0, 1e-15);
  EXPECT_NEAR(q.z(), std::sqrt(0.5), 1e-15);
}

TEST_F(FullScene, BoxDimensionsAreFullExtents) {
  const v1::Box* box = Named(scene_.boxes(), "rotated_box");
  ASSERT_NE(box, nullptr);
  EXPECT_EQ(box->size().x(), 0.1);
  EXPECT_EQ(box->size().y(), 0.2);
  EXPECT_EQ(box->size().z(), 0.3);
}

TEST_F(FullScene, SphereAndCylinderDimensions) {
  const v1::Sphere* ball = Named(scene_.spheres(), "ball");
  ASSERT_NE(ball, nullptr);
  EXPECT_EQ(ball->radius(), 0.05);
  EXPECT_EQ(ball->pose().position().x(), 0.4);
  EXPECT_EQ(ball->pose().position().y(), -0.4);
  // CYLINDER dimensions are [height, radius].
  const v1::Cylinder* can = Named(scene_.cylinders(), "can");
  ASSERT_NE(can, nullptr);
  EXPECT_EQ(can->length(), 0.5);
  EXPECT_EQ(can->radius(), 0.1);
}

TEST_F(FullScene, FramesFromFixedFrameTransforms) {
  // cup: in "bench" (0.5 m up): (0.6, 0, 0.05) -> (0.6, 0, 0.55).
  const v1::Cylinder* cup = Named(scene_.cylinders(), "cup");
  ASSERT_NE(cup, nullptr);
  EXPECT_NEAR(cup->pose().position().x(), 0.6, kTight);
  EXPECT_NEAR(cup->pose().position().y(), 0.0, kTight);
  EXPECT_NEAR(cup->pose().position().z(), 0.55, kTight);
  // tray: tray_frame = bench · (0.1, 0, 0) turned 90° about z. tray/1 at (0.1, 0, 0.02) in it:
  // (0.1, 0, 0.5) + Rz(90°)·(0.1, 0, 0.02) = (0.1, 0.1, 0.52).
  const v1::Sphere* knob = Named(scene_.spheres(), "tray/1");
  ASSERT_NE(knob, nullptr);
  EXPECT_NEAR(knob->pose().position().x(), 0.1, kTight);
  EXPECT_NEAR(knob->pose().position().y(), 0.1, kTight);
  EXPECT_NEAR(knob->pose().position().z(), 0.52, kTight);
  const v1::Box* tray = Named(scene_.boxes(), "tray/0");
  ASSERT_NE(tray, nullptr);
  const Eigen::Matrix3d r = ToIsometry(tray->pose()).linear();
  EXPECT_TRUE((r * Eigen::Vector3d::UnitX()).isApprox(Eigen::Vector3d::UnitY(), 1e-12)) << r;
}

TEST_F(FullScene, MeshBecomesObjText) {
  const v1::Mesh* wedge = Named(scene_.meshes(), "wedge");
  ASSERT_NE(wedge, nullptr);
  std::istringstream lines(wedge->data());
  int vertices = 0, faces = 0;
  std::vector<std::string> face_lines;
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind("v ", 0) == 0) ++vertices;
    if (line.rfind("f ", 0) == 0) {
      ++faces;
      face_lines.push_back(line);
    }
  }
  EXPECT_EQ(vertices, 4);
  EXPECT_EQ(faces, 4);
  EXPECT_EQ(face_lines.front(), "f 1 3 2");  // OBJ indices count from 1
  EXPECT_NE(wedge->data().find("v 0.1 0 0\n"), std::string::npos) << wedge->data();
  EXPECT_EQ(wedge->pose().position().x(), -0.5);
  // Chasles' own mesh reader sees the same tetrahedron.
  const auto mesh = ParseMesh(wedge->data(), Eigen::Vector3d::Ones(), "wedge");
  EXPECT_EQ(mesh->vertices.size(), 4u);
  EXPECT_EQ(mesh->triangles.size(), 4u);
}

// ---------------------------------------------------------------------------------------------
// Scene: allowed collisions

std::set<std::pair<std::string, std::string>> Pairs(const v1::Scene& scene) {
  std::set<std::pair<std::string, std::string>> pairs;
  for (const v1::LinkPair& pair : scene.allowed_collisions()) {
    EXPECT_TRUE(pairs.emplace(pair.link1(), pair.link2()).second) << pair.link1() << " " << pair.link2() << " twice";
  }
  return pairs;
}

TEST_F(FullScene, AllowedCollisionMatrixBecomesPairs) {
  const auto pairs = Pairs(scene_);
  std::set<std::pair<std::string, std::string>> expected = {
      {"panda_hand", "cup"},  // an entry between a link and an object
      {"panda_link7", "tray/0"},
      {"panda_link7", "tray/1"},       // an object with two shapes
      {"panda_link5", "panda_link7"},  // a link pair the SRDF does not have
  };
  // "ball" is allowed by default against every link but panda_link8, whose default is false
  // (two defaults: both must allow).
  for (const std::string& link : Panda().link_names) {
    if (link != "panda_link8") expected.emplace(link, "ball");
  }
  EXPECT_EQ(pairs, expected);
  // Not there: panda_hand-panda_link7 (already allowed by the SRDF), link7-cup (false), the
  // finger link (not a link of this robot).
  EXPECT_EQ(pairs.count({"panda_hand", "panda_link7"}), 0u);
}

TEST(MoveItScene, RobowflexLayout) {
  const v1::Scene scene = ImportPlanningScene(Data("robowflex_scene.yaml"), Panda(), "robowflex_scene.yaml");
  ASSERT_EQ(scene.boxes_size(), 1);
  EXPECT_EQ(scene.boxes(0).name(), "Table");
  EXPECT_EQ(scene.boxes(0).size().y(), 1.2);
  EXPECT_NEAR(scene.boxes(0).pose().orientation().z(), std::sqrt(0.5), 1e-15);  // [x, y, z, w] lists
  EXPECT_NEAR(scene.boxes(0).pose().orientation().w(), std::sqrt(0.5), 1e-15);
  ASSERT_EQ(scene.cylinders_size(), 1);
  EXPECT_EQ(scene.cylinders(0).length(), 0.12);
  EXPECT_EQ(scene.cylinders(0).radius(), 0.04);
  ASSERT_EQ(scene.meshes_size(), 1);
  const auto mesh = ParseMesh(scene.meshes(0).data(), Eigen::Vector3d::Ones(), "Slab");
  EXPECT_EQ(mesh->triangles.size(), 4u);
  ASSERT_EQ(scene.allowed_collisions_size(), 1);
  EXPECT_EQ(scene.allowed_collisions(0).link1(), "panda_link0");
  EXPECT_EQ(scene.allowed_collisions(0).link2(), "Table");
}

// world.octomap: the message's tree data (octomap's own writeBinaryData / writeData, made here
// with the octomap library) becomes an OctoMap of the scene that octomap reads back with the same
// occupied cells, at frame ∘ origin, and that the server's scene reader accepts.
TEST(MoveItScene, TheWorldsOctomapBecomesAnOctoMap) {
  octomap::OcTree tree(0.05);
  for (double x = 0.4; x <= 0.6; x += 0.05) tree.updateNode(octomap::point3d(x, 0.1, 0.5), true);
  tree.updateNode(octomap::point3d(0.5, -0.3, 0.2), false);
  for (const bool binary : {true, false}) {
    SCOPED_TRACE(binary ? "binary" : "full");
    std::stringstream stream;
    if (binary) {
      tree.writeBinaryData(stream);
    } else {
      tree.writeData(stream);
    }
    const std::string bytes = stream.str();
    std::string list;
    for (const char c : bytes) list += (list.empty() ? "" : ", ") + std::to_string(static_cast<int>(static_cast<signed char>(c)));
    std::string yaml = Replace(Data("scene_full.yaml"), "data: []", "data: [" + list + "]");
    yaml = Replace(yaml, "binary: true", binary ? "binary: true" : "binary: false");
    yaml = Replace(yaml, "      position: {x: 0, y: 0, z: 0}\n      orientation: {x: 0, y: 0, z: 0, w: 1}\n    octomap:",
                   "      position: {x: 0.1, y: 0, z: 0}\n      orientation: {x: 0, y: 0, z: 0, w: 1}\n    octomap:");
    const v1::Scene scene = ImportPlanningScene(yaml, Panda(), "scene.yaml");
    ASSERT_EQ(scene.octomaps_size(), 1);
    EXPECT_EQ(scene.octomaps(0).name(), "octomap");
    EXPECT_NEAR(scene.octomaps(0).pose().position().x(), 0.1, kTight);
    std::istringstream in(scene.octomaps(0).data());
    std::unique_ptr<octomap::OcTree> tree_read;
    if (binary) {
      tree_read = std::make_unique<octomap::OcTree>(0.05);
      ASSERT_TRUE(tree_read->readBinary(in));
    } else {
      std::unique_ptr<octomap::AbstractOcTree> read(octomap::AbstractOcTree::read(in));
      ASSERT_NE(read, nullptr);
      tree_read.reset(dynamic_cast<octomap::OcTree*>(read.release()));
      ASSERT_NE(tree_read, nullptr);
    }
    EXPECT_EQ(tree_read->size(), tree.size());
    EXPECT_EQ(tree_read->getResolution(), 0.05);
    for (double x = 0.4; x <= 0.6; x += 0.05) {
      const octomap::OcTreeNode* node = tree_read->search(octomap::point3d(x, 0.1, 0.5));
      ASSERT_NE(node, nullptr);
      EXPECT_TRUE(tree_read->isNodeOccupied(node));
    }
    EXPECT_NO_THROW(SceneFromProto(scene, "scene"));
  }
}

TEST(MoveItScene, EmptySceneHasNoObjects) {
  const v1::Scene scene = ImportPlanningScene("name: empty\n", Panda(), "empty.yaml");
  EXPECT_EQ(scene.ByteSizeLong(), 0u);
}

// ---------------------------------------------------------------------------------------------
// Request: start, goal, budget

TEST(MoveItRequest, StartOverlayGoalAndBudget) {
  const v1::PlanRequest request = ImportMotionPlanRequest(Data("scene_full.yaml"), Data("request_full.yaml"), Panda(),
                                                          "scene_full.yaml", "request_full.yaml");
  // The scene's state with joint2 and joint7 from the request (finger joints ignored).
  EXPECT_EQ(Values(request.start().positions()), (std::vector<double>{0.1, -0.5, 0.2, -2.3, 0.3, 1.5, 0.9}));
  // joint7 is unconstrained: it keeps its start position.
  EXPECT_EQ(Values(request.goal().positions()), (std::vector<double>{-1.0, -0.3, 0.1, -2.2, 0.2, 1.9, 0.9}));
  // min(above, below) over the robot's joints: joint2's 0.005 (the finger's 1e-4 is not the robot's).
  EXPECT_EQ(request.goal().tolerance(), 0.005);
  EXPECT_EQ(request.time_budget(), 2.5);
  EXPECT_TRUE(request.has_scene());
  EXPECT_EQ(request.scene().boxes_size(), 3);
  // Robot and planner are the caller's.
  EXPECT_FALSE(request.has_robot());
  EXPECT_TRUE(request.robot_id().empty());
  EXPECT_FALSE(request.has_planner());
  // The same scene as importing it alone.
  const v1::Scene scene = ImportPlanningScene(Data("scene_full.yaml"), Panda(), "scene_full.yaml");
  EXPECT_TRUE(google::protobuf::util::MessageDifferencer::Equals(request.scene(), scene));
}

TEST(MoveItRequest, RobowflexLayoutWithoutTolerances) {
  const v1::PlanRequest request = ImportMotionPlanRequest(Data("robowflex_scene.yaml"), Data("robowflex_request.yaml"),
                                                          Panda(), "robowflex_scene.yaml", "robowflex_request.yaml");
  EXPECT_EQ(Values(request.start().positions()), (std::vector<double>{0, -0.785, 0, -2.356, 0, 1.571, 0.785}));
  EXPECT_EQ(Values(request.goal().positions()), (std::vector<double>{-1, -0.3, 0, -2.2, 0, 1.9, 0.785}));
  EXPECT_EQ(request.goal().tolerance(), 0.0);  // absent tolerances: Chasles' default
  EXPECT_EQ(request.time_budget(), 0.0);       // allowed_planning_time 0: Chasles' default
}

TEST(MoveItRequest, ToleranceIsCappedAtPointOne) {
  const std::string request =
      "goal_constraints:\n  - joint_constraints:\n"
      "      - {joint_name: panda_joint1, position: 0.5, tolerance_above: 0.5, tolerance_below: 0.25}\n"
      "      - {joint_name: panda_joint2, position: -0.5, tolerance_above: 0.2, tolerance_below: 0.3}\n";
  const v1::PlanRequest plan = ImportMotionPlanRequest(Data("robowflex_scene.yaml"), request, Panda(), "s", "r");
  EXPECT_EQ(plan.goal().tolerance(), 0.1);  // min is 0.2, capped at JointGoal's 0.1
}

TEST(MoveItRequest, StartFromTheSceneAlone) {
  // No start_state in the request: the scene's robot state is the start.
  const std::string request =
      "goal_constraints:\n  - joint_constraints:\n      - {joint_name: panda_joint4, position: -2.0}\n";
  const v1::PlanRequest plan = ImportMotionPlanRequest(Data("scene_full.yaml"), request, Panda(), "s", "r");
  EXPECT_EQ(Values(plan.start().positions()), (std::vector<double>{0.1, -0.7, 0.2, -2.3, 0.3, 1.5, 0.7}));
  EXPECT_EQ(Values(plan.goal().positions()), (std::vector<double>{0.1, -0.7, 0.2, -2.0, 0.3, 1.5, 0.7}));
}

// ---------------------------------------------------------------------------------------------
// Named errors

TEST(MoveItErrors, MalformedYamlNamesFileAndLine) {
  const std::string message = ErrorOf([] { ImportPlanningScene(Data("malformed.yaml"), Panda(), "malformed.yaml"); });
  EXPECT_TRUE(
      std::regex_search(message, std::regex("^malformed\\.yaml: malformed YAML at line [0-9]+, column [0-9]+: ")))
      << message;
  const std::string request = ErrorOf(
      [] { ImportMotionPlanRequest(Data("scene_full.yaml"), "goal_constraints: [\n", Panda(), "s.yaml", "r.yaml"); });
  EXPECT_NE(request.find("r.yaml: malformed YAML at line 2"), std::string::npos) << request;
}

TEST(MoveItErrors, NotAMap) {
  EXPECT_EQ(SceneError(""), "scene.yaml is empty (expected a moveit_msgs/PlanningScene)");
  EXPECT_NE(SceneError("- 1\n- 2\n").find("scene.yaml is not a YAML map"), std::string::npos);
}

TEST(MoveItErrors, ConeIsNotSupported) {
  const std::string scene = Replace(Data("scene_full.yaml"), "type: 3\n          dimensions: [0.5, 0.1]",
                                    "type: 4\n          dimensions: [0.5, 0.1]");
  EXPECT_EQ(SceneError(scene),
            "scene.yaml: world.collision_objects[3].primitives[0].type = 4 (CONE) is not supported "
            "(BOX, SPHERE, CYLINDER and meshes are)");
  const std::string named = Replace(Data("robowflex_scene.yaml"), "type: Cylinder", "type: cone");
  EXPECT_EQ(SceneError(named),
            "scene.yaml: world.collision_objects[1].primitives[0].type = 4 (CONE) is not supported "
            "(BOX, SPHERE, CYLINDER and meshes are)");
  EXPECT_NE(SceneError(Replace(named, "type: cone", "type: torus")).find("type = 'torus' is not a primitive type"),
            std::string::npos);
}

TEST(MoveItErrors, OnlyAddOperations) {
  const std::string remove = Replace(Data("scene_full.yaml"), "operation: 0", "operation: 1");
  EXPECT_EQ(SceneError(remove),
            "scene.yaml: world.collision_objects[0].operation = 1 (REMOVE) is not supported: a scene is read as a "
            "whole, so every object must be ADD (0)");
  const std::string move = Replace(Data("robowflex_scene.yaml"), "operation: add", "operation: move");
  EXPECT_NE(SceneError(move).find("world.collision_objects[1].operation = 'move' (MOVE) is not supported"),
            std::string::npos);
}

TEST(MoveItErrors, WrongDimensionCounts) {
  const std::string box = Replace(Data("scene_full.yaml"), "dimensions: [0.1, 0.2, 0.3]", "dimensions: [0.1, 0.2]");
  EXPECT_EQ(SceneError(box),
            "scene.yaml: world.collision_objects[0].primitives[0].dimensions has 2 values: a BOX has 3 "
            "([x, y, z] full extents)");
  const std::string cylinder = Replace(Data("scene_full.yaml"), "dimensions: [0.5, 0.1]", "dimensions: [0.5]");
  EXPECT_NE(SceneError(cylinder).find("dimensions has 1 values: a CYLINDER has 2 ([height, radius])"),
            std::string::npos);
  const std::string negative = Replace(Data("scene_full.yaml"), "dimensions: [0.05]", "dimensions: [-0.05]");
  EXPECT_EQ(SceneError(negative),
            "scene.yaml: world.collision_objects[2].primitives[0].dimensions[0] = -0.05 must be > 0 (SPHERE [radius])");
}

TEST(MoveItErrors, NonNumericValues) {
  const std::string scene =
      Replace(Data("scene_full.yaml"), "position: {x: 0.4, y: -0.4, z: 0.2}", "position: {x: 0.4, y: abc, z: 0.2}");
  EXPECT_EQ(SceneError(scene),
            "scene.yaml: world.collision_objects[2].primitive_poses[0].position.y = 'abc' is not a number");
  const std::string nan = Replace(Data("scene_full.yaml"), "dimensions: [0.05]", "dimensions: [.nan]");
  EXPECT_EQ(SceneError(nan),
            "scene.yaml: world.collision_objects[2].primitives[0].dimensions[0] = .nan must be finite");
  const std::string joint = Replace(Data("request_full.yaml"), "position: -1.0", "position: [1]");
  EXPECT_EQ(RequestError(Data("scene_full.yaml"), joint),
            "request.yaml: goal_constraints[0].joint_constraints[0].position = a list of 1 is not a number");
}

TEST(MoveItErrors, ZeroQuaternion) {
  const std::string scene =
      Replace(Data("robowflex_scene.yaml"), "orientation: [0, 0, 0, 1]", "orientation: [0, 0, 0, 0]");
  EXPECT_EQ(SceneError(scene),
            "scene.yaml: world.collision_objects[1].primitive_poses[0].orientation = (x 0, y 0, z 0, w 0) has norm 0: "
            "a rotation needs a non-zero quaternion (x, y, z, w)");
  const std::string short_list =
      Replace(Data("robowflex_scene.yaml"), "orientation: [0, 0, 0, 1]", "orientation: [0, 0, 1]");
  EXPECT_NE(SceneError(short_list).find("orientation has 3 numbers, expected 4 (x, y, z, w)"), std::string::npos);
}

TEST(MoveItErrors, UnsupportedSceneContent) {
  const std::string attached = Replace(Data("scene_full.yaml"), "attached_collision_objects: []",
                                       "attached_collision_objects:\n    - link_name: panda_hand");
  EXPECT_NE(SceneError(attached).find("robot_state.attached_collision_objects has 1 objects: a scene alone cannot "
                                      "carry them"),
            std::string::npos);
  const std::string planes = Replace(Data("scene_full.yaml"), "planes: []", "planes:\n        - coef: [0, 0, 1, 0]");
  EXPECT_NE(SceneError(planes).find("world.collision_objects[6].planes has 1 entries: planes are not supported"),
            std::string::npos);
  const std::string octomap = Replace(Data("scene_full.yaml"), "data: []", "data: [1]");
  EXPECT_NE(SceneError(octomap).find("scene.yaml: world.octomap.octomap.data is truncated or corrupt"),
            std::string::npos);
  EXPECT_NE(SceneError(Replace(Data("scene_full.yaml"), "data: []", "data: [1, 2, 3]"))
                .find("scene.yaml: world.octomap.octomap.data holds 1 bytes after its tree"),
            std::string::npos);
  EXPECT_NE(SceneError(Replace(Data("scene_full.yaml"), "data: []", "data: [300]"))
                .find("world.octomap.octomap.data[0] = 300 must be a whole number within [-128, 255]"),
            std::string::npos);
  EXPECT_NE(SceneError(Replace(Replace(Data("scene_full.yaml"), "data: []", "data: [0, 0]"), "id: OcTree",
                               "id: ColorOcTree"))
                .find("world.octomap.octomap.id = 'ColorOcTree': only 'OcTree' maps are supported"),
            std::string::npos);
  const std::string resource =
      Replace(Data("scene_full.yaml"), "- vertices:", "- resource: package://x/y.stl\n          vertices:");
  EXPECT_NE(SceneError(resource).find("world.collision_objects[6].meshes[0].resource = 'package://x/y.stl': mesh "
                                      "resources are not supported"),
            std::string::npos);
}

TEST(MoveItErrors, FramesIdsAndShapeLists) {
  const std::string frame = Replace(Data("scene_full.yaml"), "frame_id: /world", "frame_id: camera_link");
  EXPECT_NE(SceneError(frame).find("world.collision_objects[2].header.frame_id = 'camera_link' is not a known frame"),
            std::string::npos);
  EXPECT_EQ(
      SceneError(Replace(Data("robowflex_scene.yaml"), "- id: Can", "- header: {frame_id: camera}\n      id: Can")),
      "scene.yaml: world.collision_objects[1].header.frame_id = 'camera' is not a known frame: objects must be "
      "given in the robot's base frame ('panda_link0', 'world', '/world' or '') or in a frame that "
      "fixed_frame_transforms lead to from it (there are none)");
  const std::string cycle = Replace(Data("scene_full.yaml"), "frame_id: bench\n    child_frame_id: tray_frame",
                                    "frame_id: tray_frame\n    child_frame_id: tray_frame");
  EXPECT_NE(SceneError(cycle).find("world.collision_objects[5].header.frame_id = 'tray_frame' is not a known frame "
                                   "(fixed_frame_transforms form a cycle)"),
            std::string::npos);
  const std::string duplicate = Replace(Data("scene_full.yaml"), "id: ball", "id: can");
  EXPECT_EQ(SceneError(duplicate),
            "scene.yaml: world.collision_objects[3].id = 'can' repeats world.collision_objects[2].id");
  const std::string link = Replace(Data("scene_full.yaml"), "id: ball", "id: panda_hand");
  EXPECT_NE(SceneError(link).find("id = 'panda_hand' is a link of the robot"), std::string::npos);
  const std::string no_id = Replace(Data("scene_full.yaml"), "id: ball", "name: ball");
  EXPECT_EQ(SceneError(no_id), "scene.yaml: world.collision_objects[2].id is missing");
  const std::string poses =
      Replace(Data("scene_full.yaml"),
              "        - position: {x: 0.1, y: 0, z: 0.02}\n          orientation: {x: 0, y: 0, z: 0, w: 1}\n", "");
  EXPECT_EQ(SceneError(poses),
            "scene.yaml: world.collision_objects[5].primitive_poses has 1 poses for 2 primitives: there must be one "
            "per shape");
  const std::string index = Replace(Data("scene_full.yaml"), "vertex_indices: [1, 2, 3]", "vertex_indices: [1, 2, 4]");
  EXPECT_EQ(SceneError(index),
            "scene.yaml: world.collision_objects[6].meshes[0].triangles[3].vertex_indices[2] = 4 must be a whole "
            "number within [0, 3]");
  const std::string acm = Replace(Data("scene_full.yaml"), "- enabled: [false, true, false, false, false, false]",
                                  "- enabled: [false, true, false]");
  EXPECT_NE(SceneError(acm).find("allowed_collision_matrix.entry_values[2].enabled has 3 values, expected 6"),
            std::string::npos);
}

TEST(MoveItErrors, UnsupportedGoals) {
  // Position/orientation constraints are a pose goal, never mixed with joint constraints.
  const std::string position = Replace(Data("request_full.yaml"), "position_constraints: []",
                                       "position_constraints:\n      - link_name: panda_hand");
  EXPECT_EQ(RequestError(Data("scene_full.yaml"), position),
            "request.yaml: goal_constraints[0] mixes joint constraints with position/orientation constraints: give "
            "one kind");
  const std::string path = Replace(Data("request_full.yaml"), "joint_constraints: []",
                                   "joint_constraints:\n    - {joint_name: panda_joint1, position: 0}");
  EXPECT_NE(RequestError(Data("scene_full.yaml"), path)
                .find("path_constraints.joint_constraints has 1 entries: joint path constraints are not supported "
                      "(orientation and position ones are)"),
            std::string::npos);
  const std::string two =
      Replace(Data("request_full.yaml"), "goal_constraints:\n",
              "goal_constraints:\n  - joint_constraints: [{joint_name: panda_joint1, position: 0}]\n");
  EXPECT_NE(
      RequestError(Data("scene_full.yaml"), two).find("goal_constraints has 2 entries: only one goal is supported"),
      std::string::npos);
  EXPECT_EQ(RequestError(Data("scene_full.yaml"), "planner_id: RRT\n"), "request.yaml: goal_constraints is missing");
  const std::string fingers_only =
      "goal_constraints:\n  - joint_constraints:\n      - {joint_name: panda_finger_joint1, position: 0.01}\n";
  EXPECT_NE(RequestError(Data("scene_full.yaml"), fingers_only)
                .find("goal_constraints[0].joint_constraints constrain none of the robot's joints"),
            std::string::npos);
  const std::string twice = Replace(Data("request_full.yaml"), "joint_name: panda_joint3", "joint_name: panda_joint1");
  EXPECT_EQ(RequestError(Data("scene_full.yaml"), twice),
            "request.yaml: goal_constraints[0].joint_constraints[2].joint_name = 'panda_joint1' is constrained twice");
  const std::string negative = Replace(Data("request_full.yaml"), "tolerance_below: 0.03", "tolerance_below: -0.03");
  EXPECT_EQ(RequestError(Data("scene_full.yaml"), negative),
            "request.yaml: goal_constraints[0].joint_constraints[0].tolerance_below = -0.03 must be >= 0");
  const std::string budget =
      Replace(Data("request_full.yaml"), "allowed_planning_time: 2.5", "allowed_planning_time: 900");
  EXPECT_EQ(RequestError(Data("scene_full.yaml"), budget),
            "request.yaml: allowed_planning_time = 900 must be within [0, 600] s (0 = Chasles' default budget)");
}

/// request_full.yaml with its goal replaced by a region: a position constraint (`region`, one
/// primitive at (0.4, 0.1, 0.5)) and an orientation constraint with the axis tolerances `axes`.
std::string PoseGoalRequest(const std::string& region, const std::string& axes, const std::string& frame = "world") {
  std::string text = Data("request_full.yaml");
  const std::size_t at = text.find("goal_constraints:");
  const std::size_t end = text.find("\npath_constraints:");
  EXPECT_NE(at, std::string::npos);
  EXPECT_NE(end, std::string::npos);
  return text.substr(0, at) +
         "goal_constraints:\n"
         "  - position_constraints:\n"
         "      - header: {frame_id: " + frame + "}\n"
         "        link_name: panda_hand\n"
         "        target_point_offset: {x: 0, y: 0, z: 0}\n"
         "        constraint_region:\n"
         "          primitives: [" + region + "]\n"
         "          primitive_poses: [{position: [0.4, 0.1, 0.5], orientation: [0, 0, 0, 1]}]\n"
         "    orientation_constraints:\n"
         "      - header: {frame_id: " + frame + "}\n"
         "        link_name: panda_hand\n"
         "        orientation: [1, 0, 0, 0]\n" + axes + text.substr(end);
}

TEST(MoveItRequest, APositionAndOrientationRegionIsAPoseGoalWithinIt) {
  const std::string axes =
      "        absolute_x_axis_tolerance: 0.1\n        absolute_y_axis_tolerance: 0.05\n"
      "        absolute_z_axis_tolerance: 3.14\n";
  const v1::PlanRequest box =
      ImportMotionPlanRequest(Data("scene_full.yaml"), PoseGoalRequest("{type: 1, dimensions: [0.02, 0.06, 0.04]}", axes),
                              Panda(), "s", "r");
  ASSERT_EQ(box.target_case(), v1::PlanRequest::kPoseGoal);
  const v1::PoseGoal& goal = box.pose_goal();
  EXPECT_EQ(goal.link(), "panda_hand");
  EXPECT_NEAR(goal.pose().position().x(), 0.4, kTight);
  EXPECT_NEAR(goal.pose().position().y(), 0.1, kTight);
  EXPECT_NEAR(goal.pose().position().z(), 0.5, kTight);
  EXPECT_NEAR(std::abs(goal.pose().orientation().x()), 1.0, kTight);  // pointing down
  EXPECT_EQ(goal.position_tolerance(), 0.01);      // half the box's least extent: the ball fits inside
  EXPECT_EQ(goal.orientation_tolerance(), 0.05);   // the least axis tolerance
  const v1::PlanRequest sphere = ImportMotionPlanRequest(
      Data("scene_full.yaml"), PoseGoalRequest("{type: 2, dimensions: [0.5]}", axes), Panda(), "s", "r");
  EXPECT_EQ(sphere.pose_goal().position_tolerance(), 0.1);  // capped at PoseGoal's range
  // In the scene's "bench" frame (0.5 m up): the centre moves with it.
  const v1::PlanRequest bench = ImportMotionPlanRequest(
      Data("scene_full.yaml"), PoseGoalRequest("{type: 2, dimensions: [0.01]}", axes, "bench"), Panda(), "s", "r");
  EXPECT_NEAR(bench.pose_goal().pose().position().z(), 1.0, kTight);
  // Named errors.
  EXPECT_NE(RequestError(Data("scene_full.yaml"), PoseGoalRequest("{type: 4, dimensions: [0.1, 0.1]}", axes))
                .find("is not a goal region here"),
            std::string::npos);
  EXPECT_NE(RequestError(Data("scene_full.yaml"),
                         Replace(PoseGoalRequest("{type: 2, dimensions: [0.01]}", axes), "absolute_y_axis_tolerance: 0.05",
                                 "absolute_y_axis_tolerance: 0"))
                .find("orientation_constraints[0].absolute_y_axis_tolerance = 0 must be > 0"),
            std::string::npos);
  EXPECT_NE(RequestError(Data("scene_full.yaml"),
                         Replace(PoseGoalRequest("{type: 2, dimensions: [0.01]}", axes), "target_point_offset: {x: 0, y: 0, z: 0}",
                                 "target_point_offset: {x: 0, y: 0, z: 0.1}"))
                .find("target_point_offset is not supported"),
            std::string::npos);
  const std::string no_orientation = PoseGoalRequest("{type: 2, dimensions: [0.01]}", axes);
  const std::size_t cut = no_orientation.find("    orientation_constraints:");
  const std::size_t resume = no_orientation.find("\npath_constraints:");
  EXPECT_NE(RequestError(Data("scene_full.yaml"), no_orientation.substr(0, cut) + no_orientation.substr(resume + 1))
                .find("has 1 position and 0 orientation constraints"),
            std::string::npos);
}

TEST(MoveItErrors, MissingStartJoint) {
  // joint3 neither in the scene's state nor in the request's start state.
  const std::string scene = Replace(Replace(Data("scene_full.yaml"), "panda_joint3, ", ""), "0.2, -2.3", "-2.3");
  EXPECT_EQ(RequestError(scene, Data("request_full.yaml")),
            "request.yaml: start_state.joint_state has no position for joint 'panda_joint3' (nor has scene.yaml: "
            "robot_state.joint_state); the robot's joints are panda_joint1, panda_joint2, panda_joint3, panda_joint4, "
            "panda_joint5, panda_joint6, panda_joint7");
  // In the request's start state alone it is enough.
  const std::string request =
      Replace(Data("request_full.yaml"),
              "name: [panda_joint7, panda_finger_joint1, panda_joint2]\n    position: [0.9, 0.01, -0.5]",
              "name: [panda_joint7, panda_joint3, panda_joint2]\n    position: [0.9, 0.25, -0.5]");
  const v1::PlanRequest plan = ImportMotionPlanRequest(scene, request, Panda(), "s", "r");
  EXPECT_EQ(plan.start().positions(2), 0.25);
  // Names and positions must pair up.
  const std::string mismatch =
      Replace(Data("request_full.yaml"), "position: [0.9, 0.01, -0.5]", "position: [0.9, 0.01]");
  EXPECT_EQ(RequestError(Data("scene_full.yaml"), mismatch),
            "request.yaml: start_state.joint_state has 3 names and 2 positions: they must match one to one");
  const std::string attached =
      Replace(Data("request_full.yaml"), "is_diff: true", "attached_collision_objects:\n    - link_name: panda_hand");
  EXPECT_NE(RequestError(Data("scene_full.yaml"), attached).find("start_state.attached_collision_objects[0]"),
            std::string::npos);
}

/// request_full.yaml with one attached cup (a cylinder) given in `frame` at `position`.
std::string WithCup(const std::string& frame, const std::string& position, const std::string& extra = "") {
  return Replace(Data("request_full.yaml"), "is_diff: true",
                 "attached_collision_objects:\n"
                 "    - link_name: panda_hand\n"
                 "      touch_links: [panda_leftfinger, panda_link7]\n"
                 "      object:\n"
                 "        id: cup\n"
                 "        header: {frame_id: " + frame + "}\n"
                 "        primitives: [{type: 3, dimensions: [0.1, 0.03]}]\n"
                 "        primitive_poses: [{position: " + position + ", orientation: [0, 0, 0, 1]}]\n" + extra);
}

TEST(MoveItRequest, AttachedObjectsBecomeTheRobotsLoad) {
  const v1::PlanRequest in_link = ImportMotionPlanRequest(Data("scene_full.yaml"),
                                                          WithCup("panda_hand", "[0, 0, 0.1]"), Panda(), "s", "r");
  ASSERT_EQ(in_link.attached_objects_size(), 1);
  const v1::AttachedObject& cup = in_link.attached_objects(0);
  EXPECT_EQ(cup.name(), "cup");
  EXPECT_EQ(cup.link(), "panda_hand");
  ASSERT_EQ(cup.cylinders_size(), 1);
  EXPECT_EQ(cup.cylinders(0).length(), 0.1);
  EXPECT_EQ(cup.cylinders(0).radius(), 0.03);
  EXPECT_NEAR(cup.cylinders(0).pose().position().z(), 0.1, kTight);
  // MoveIt's finger link is not a link of Chasles' Panda: dropped, as in the ACM.
  ASSERT_EQ(cup.touch_links_size(), 1);
  EXPECT_EQ(cup.touch_links(0), "panda_link7");
  // The same cup given in the base frame, where the hand is at the start: the same pose in the hand.
  const auto robot = RobotFromProto(Panda().model, "robot");
  Eigen::VectorXd q(7);
  for (int i = 0; i < 7; ++i) q[i] = in_link.start().positions(i);
  std::vector<Eigen::Isometry3d> poses;
  robot->ForwardKinematics(q, &poses);
  const Eigen::Vector3d world =
      poses[static_cast<std::size_t>(robot->FindLink("panda_hand"))] * Eigen::Vector3d(0.0, 0.0, 0.1);
  char position[128];
  std::snprintf(position, sizeof(position), "[%.17g, %.17g, %.17g]", world.x(), world.y(), world.z());
  const v1::PlanRequest in_world =
      ImportMotionPlanRequest(Data("scene_full.yaml"), WithCup("world", position), Panda(), "s", "r");
  ASSERT_EQ(in_world.attached_objects_size(), 1);
  const v1::Pose& pose = in_world.attached_objects(0).cylinders(0).pose();
  EXPECT_NEAR(pose.position().x(), 0.0, 1e-12);
  EXPECT_NEAR(pose.position().y(), 0.0, 1e-12);
  EXPECT_NEAR(pose.position().z(), 0.1, 1e-12);
  // Named errors: a mesh, an unknown link.
  EXPECT_NE(RequestError(Data("scene_full.yaml"),
                         WithCup("panda_hand", "[0, 0, 0.1]", "        meshes: [{vertices: [], triangles: []}]\n"))
                .find("meshes of attached objects are not supported"),
            std::string::npos);
  EXPECT_NE(RequestError(Data("scene_full.yaml"),
                         Replace(WithCup("panda_hand", "[0, 0, 0.1]"), "link_name: panda_hand", "link_name: gripper"))
                .find("start_state.attached_collision_objects[0].link_name = 'gripper' is not a link of the robot"),
            std::string::npos);
}

// ---------------------------------------------------------------------------------------------
// Directories

TEST(MoveItDirectory, PairsInNumericOrder) {
  const auto problems = moveit::ImportProblemDirectory(DataPath("problems"), Panda());
  ASSERT_EQ(problems.size(), 2u);  // scene_sensed2.yaml and README.md are not problems
  EXPECT_EQ(problems[0].name, "scene2");
  EXPECT_EQ(problems[1].name, "scene10");
  EXPECT_EQ(problems[0].request.scene().boxes(0).name(), "box_two");
  EXPECT_EQ(problems[0].request.goal().positions(0), 0.2);
  EXPECT_EQ(problems[1].request.scene().boxes(0).name(), "box_ten");
  EXPECT_EQ(problems[1].request.goal().positions(0), 1.0);
  EXPECT_EQ(problems[1].request.time_budget(), 1.0);
}

TEST(MoveItDirectory, MissingPartnersAndEmptyDirectories) {
  const std::string unpaired = DataPath("problems_unpaired");
  EXPECT_EQ(ErrorOf([&] { moveit::ImportProblemDirectory(unpaired, Panda()); }),
            unpaired + ": scene0003.yaml has no request0003.yaml beside it");

  const std::filesystem::path dir = std::filesystem::path(::testing::TempDir()) / "moveit_import_test_dir";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  EXPECT_EQ(ErrorOf([&] { moveit::ImportProblemDirectory(dir.string(), Panda()); }),
            dir.string() + ": no sceneNNNN.yaml / requestNNNN.yaml pairs found");
  std::filesystem::copy_file(DataPath("problems/request2.yaml"), dir / "request0007.yaml");
  EXPECT_EQ(ErrorOf([&] { moveit::ImportProblemDirectory(dir.string(), Panda()); }),
            dir.string() + ": request0007.yaml has no scene0007.yaml beside it");
  // A conversion error names the file by its path.
  std::ofstream(dir / "scene0007.yaml") << "world:\n  collision_objects:\n    - id: x\n";
  EXPECT_EQ(ErrorOf([&] { moveit::ImportProblemDirectory(dir.string(), Panda()); }),
            (dir / "scene0007.yaml").string() +
                ": world.collision_objects[0] (id 'x') has no primitives and no meshes: it needs a shape");
  std::filesystem::remove_all(dir);
  EXPECT_NE(ErrorOf([&] { moveit::ImportProblemDirectory(dir.string(), Panda()); }).find("is not a readable directory"),
            std::string::npos);
}

// ---------------------------------------------------------------------------------------------
// CLI

struct CommandResult {
  int exit_code = -1;
  std::string out;
  std::string err;
};

CommandResult RunCli(const std::string& arguments) {
  // ctest runs these tests as parallel processes sharing TempDir(): every call gets its own files.
  static int call = 0;
  const std::string stem = "moveit_cli_" + std::to_string(::getpid()) + "_" + std::to_string(++call);
  const std::filesystem::path dir = std::filesystem::path(::testing::TempDir());
  const std::string out = (dir / (stem + "_out.txt")).string();
  const std::string err = (dir / (stem + "_err.txt")).string();
  const std::string command = std::string(CHASLES_CLI) + " import-moveit " + arguments + " > " + out + " 2> " + err;
  const int status = std::system(command.c_str());
  CommandResult result;
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  result.out = testing::ReadText(out);
  result.err = testing::ReadText(err);
  std::filesystem::remove(out);
  std::filesystem::remove(err);
  return result;
}

TEST(MoveItCli, PrintsAPlanRequestWithTheSameScene) {
  const std::string scene = ExamplesDir() + "/scene0001.yaml";
  const std::string request = ExamplesDir() + "/request0001.yaml";
  const CommandResult result = RunCli(scene + " " + request);
  ASSERT_EQ(result.exit_code, 0) << result.err;
  v1::PlanRequest parsed;
  const auto status = google::protobuf::util::JsonStringToMessage(result.out, &parsed);
  ASSERT_TRUE(status.ok()) << status.ToString() << "\n" << result.out;
  const v1::PlanRequest expected =
      ImportMotionPlanRequest(testing::ReadText(scene), testing::ReadText(request), Panda(), scene, request);
  EXPECT_TRUE(google::protobuf::util::MessageDifferencer::Equals(parsed.scene(), expected.scene()));
  EXPECT_TRUE(google::protobuf::util::MessageDifferencer::Equals(parsed, expected));
  EXPECT_FALSE(parsed.has_robot());  // the server's default robot
}

TEST(MoveItCli, EmbedsTheRobotAndWritesOut) {
  const std::string urdf = std::string(CHASLES_SOURCE_DIR) + "/examples/robots/panda.urdf";
  const std::string srdf = std::string(CHASLES_SOURCE_DIR) + "/examples/robots/panda.srdf";
  const std::string out = (std::filesystem::path(::testing::TempDir()) /
                           ("moveit_cli_request_" + std::to_string(::getpid()) + ".json"))
                              .string();
  std::filesystem::remove(out);
  const CommandResult result = RunCli(ExamplesDir() + "/scene0002.yaml " + ExamplesDir() +
                                      "/request0002.yaml --robot " + urdf + " --srdf " + srdf + " --out " + out);
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_NE(result.out.find("wrote"), std::string::npos);
  v1::PlanRequest parsed;
  ASSERT_TRUE(google::protobuf::util::JsonStringToMessage(testing::ReadText(out), &parsed).ok());
  ASSERT_TRUE(parsed.has_robot());
  EXPECT_EQ(parsed.robot().urdf().urdf(), testing::ReadText(urdf));
  EXPECT_EQ(parsed.robot().urdf().srdf(), testing::ReadText(srdf));
  EXPECT_EQ(parsed.start().positions_size(), 7);
}

TEST(MoveItCli, OverridesPlannerBudgetSeedAndSamplePeriod) {
  const std::string scene = ExamplesDir() + "/scene0001.yaml";
  const std::string request = ExamplesDir() + "/request0001.yaml";
  // Without flags: no planner (the server's default), the budget from allowed_planning_time (5).
  const CommandResult plain = RunCli(scene + " " + request);
  ASSERT_EQ(plain.exit_code, 0) << plain.err;
  v1::PlanRequest unchanged;
  ASSERT_TRUE(google::protobuf::util::JsonStringToMessage(plain.out, &unchanged).ok());
  EXPECT_FALSE(unchanged.has_planner());
  EXPECT_EQ(unchanged.time_budget(), 5.0);

  const CommandResult result =
      RunCli(scene + " " + request + " --planner rrt_star --budget 0.75 --seed 42 --sample-period 0.02");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  v1::PlanRequest parsed;
  ASSERT_TRUE(google::protobuf::util::JsonStringToMessage(result.out, &parsed).ok()) << result.out;
  EXPECT_EQ(parsed.planner().planner_id(), "rrt_star");
  EXPECT_EQ(parsed.time_budget(), 0.75);
  EXPECT_EQ(parsed.seed(), 42u);
  EXPECT_EQ(parsed.trajectory().sample_period(), 0.02);
  // Everything else is as imported.
  v1::PlanRequest rest = parsed;
  rest.clear_planner();
  rest.set_time_budget(unchanged.time_budget());
  rest.clear_seed();
  rest.clear_trajectory();
  EXPECT_TRUE(google::protobuf::util::MessageDifferencer::Equals(rest, unchanged));

  // Bad values: exit 2, the flag, the value and the rule on stderr, nothing on stdout.
  const struct {
    const char* flags;
    const char* expected;
  } cases[] = {
      {"--budget -1", "--budget '-1' must be a number of seconds in (0, 600]"},
      {"--seed x", "--seed 'x' must be a whole number"},
      {"--sample-period 0", "--sample-period '0' must be a number of seconds in [0.0001, 1]"},
      {"--planner 'rrt connect'", "--planner 'rrt connect' must be a planner id without spaces"},
      {"--budget", "--budget needs a value"},
  };
  for (const auto& c : cases) {
    const CommandResult bad = RunCli(scene + " " + request + " " + c.flags);
    EXPECT_EQ(bad.exit_code, 2) << c.flags;
    EXPECT_NE(bad.err.find(c.expected), std::string::npos) << c.flags << "\n" << bad.err;
    EXPECT_TRUE(bad.out.empty()) << c.flags;
  }
}

TEST(MoveItCli, AGetCartesianPathRequestBecomesACartesianPathRequest) {
  const std::string scene = ExamplesDir() + "/scene0001.yaml";
  const std::string request = ExamplesDir() + "/cartesian0001.yaml";
  const CommandResult result = RunCli(scene + " " + request + " --sample-period 0.02 --padding 0.01");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  v1::CartesianPathRequest parsed;
  ASSERT_TRUE(google::protobuf::util::JsonStringToMessage(result.out, &parsed).ok()) << result.out;
  EXPECT_EQ(parsed.waypoints_size(), 3);
  EXPECT_EQ(parsed.options().sample_period(), 0.02);
  EXPECT_EQ(parsed.padding(), 0.01);
  const CommandResult planner = RunCli(scene + " " + request + " --planner prm");
  EXPECT_EQ(planner.exit_code, 2);
  EXPECT_NE(planner.err.find("do not apply to a Cartesian path"), std::string::npos) << planner.err;
}

TEST(MoveItCli, ExitCodes) {
  // 1: the YAML does not convert, with the named error.
  const CommandResult bad = RunCli(DataPath("malformed.yaml") + " " + DataPath("request_full.yaml"));
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.err.find("malformed.yaml: malformed YAML at line"), std::string::npos) << bad.err;
  EXPECT_TRUE(bad.out.empty());
  // 2: unreadable files and bad arguments.
  EXPECT_EQ(RunCli(DataPath("no_such_scene.yaml") + " " + DataPath("request_full.yaml")).exit_code, 2);
  EXPECT_EQ(RunCli(DataPath("scene_full.yaml")).exit_code, 2);
  EXPECT_EQ(RunCli(DataPath("scene_full.yaml") + " " + DataPath("request_full.yaml") + " --frobnicate").exit_code, 2);
  EXPECT_EQ(RunCli(DataPath("scene_full.yaml") + " " + DataPath("request_full.yaml") + " --out x.txt").exit_code, 2);
  EXPECT_EQ(RunCli("--help").exit_code, 0);
}

// ---------------------------------------------------------------------------------------------
// The example problems (examples/moveit/) plan with rrt_connect

class MoveItExamples : public testing::SharedServerTest<> {};

TEST_F(MoveItExamples, StartsAndGoalsAreClearAndEveryProblemPlans) {
  const auto problems = moveit::ImportProblemDirectory(ExamplesDir(), Panda());
  ASSERT_EQ(problems.size(), 3u);
  EXPECT_EQ(problems[0].name, "scene0001");
  EXPECT_EQ(problems[1].name, "scene0002");
  EXPECT_EQ(problems[2].name, "scene0003");
  EXPECT_EQ(problems[2].request.scene().meshes_size(), 1);  // the ramp
  const auto robot = RobotFromProto(Panda().model, "robot");
  for (const moveit::MoveItProblem& problem : problems) {
    SCOPED_TRACE(problem.name);
    // Start and goal are free, with room to spare (the planner is not asked to thread a needle).
    const CollisionChecker checker(robot, SceneFromProto(problem.request.scene(), "scene"));
    const Eigen::VectorXd start =
        Eigen::Map<const Eigen::VectorXd>(problem.request.start().positions().data(), robot->num_dofs());
    const Eigen::VectorXd goal =
        Eigen::Map<const Eigen::VectorXd>(problem.request.goal().positions().data(), robot->num_dofs());
    EXPECT_GT(checker.Clearance(start), 0.02);
    EXPECT_GT(checker.Clearance(goal), 0.02);
    // The straight line collides: the problem needs a planner.
    EXPECT_FALSE(checker.IsMotionValid(start, goal, 0.005));

    v1::PlanRequest request = problem.request;
    request.mutable_planner()->set_planner_id("rrt_connect");
    request.set_seed(7);
    request.set_time_budget(5.0);
    v1::PlanResponse response;
    const grpc::Status status = server_->Plan(request, &response);
    ASSERT_TRUE(status.ok()) << status.error_message();
    EXPECT_EQ(response.outcome(), v1::SUCCESS) << response.message();
    EXPECT_GT(response.trajectory().points_size(), 1);
  }
}

// glass_request.yaml: its orientation path constraint becomes path_constraints (frame resolved,
// the π tolerance clamped onto π, ROTATION_VECTOR kept) and plans through the server, which keeps
// it (max_constraint_ratio <= 1; tests/server/path_constraints_test.cc re-checks such plans densely).
TEST_F(MoveItExamples, TheGlassPathConstraintConvertsAndPlans) {
  const v1::PlanRequest request =
      moveit::ImportMotionPlanRequest(testing::ReadText(ExamplesDir() + "/glass_scene.yaml"),
                                      testing::ReadText(ExamplesDir() + "/glass_request.yaml"), Panda(),
                                      "glass_scene.yaml", "glass_request.yaml");
  ASSERT_EQ(request.path_constraints().orientation_size(), 1);
  EXPECT_EQ(request.path_constraints().position_size(), 0);
  const v1::OrientationConstraint& c = request.path_constraints().orientation(0);
  EXPECT_EQ(c.link(), "panda_hand");
  EXPECT_NEAR(c.orientation().x(), std::sqrt(0.5), kTight);
  EXPECT_NEAR(c.orientation().z(), std::sqrt(0.5), kTight);
  EXPECT_EQ(c.tolerance().x(), 3.14159265358979323846);
  EXPECT_EQ(c.tolerance().y(), 0.1);
  EXPECT_EQ(c.parameterization(), v1::OrientationConstraint::ROTATION_VECTOR);
  EXPECT_EQ(request.scene().boxes_size(), 8);
  v1::PlanResponse response;
  const grpc::Status status = server_->Plan(request, &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(response.outcome(), v1::SUCCESS) << response.message();
  EXPECT_GT(response.quality().max_constraint_ratio(), 0.0);
  EXPECT_LE(response.quality().max_constraint_ratio(), 1.0);
}

TEST(MoveItErrors, PathConstraintsTheServerCannotKeepAreNamed) {
  const std::string scene = testing::ReadText(ExamplesDir() + "/glass_scene.yaml");
  const std::string glass = testing::ReadText(ExamplesDir() + "/glass_request.yaml");
  const auto error = [&scene](const std::string& yaml) {
    try {
      moveit::ImportMotionPlanRequest(scene, yaml, Panda(), "s.yaml", "request.yaml");
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(error(Replace(Replace(glass, "parameterization: 1", "parameterization: 0"), "absolute_y_axis_tolerance: 0.1",
                          "absolute_y_axis_tolerance: 1.6"))
                .find("absolute_y_axis_tolerance = 1.6 is not supported with XYZ_EULER_ANGLES"),
            std::string::npos);
  EXPECT_NE(error(Replace(glass, "parameterization: 1", "parameterization: 2")).find("parameterization = 2 must be 0"),
            std::string::npos);
  EXPECT_NE(error(Replace(glass, "link_name: panda_hand", "link_name: gripper")).find("link_name = 'gripper' is not a link"),
            std::string::npos);
  const std::string sphere = Replace(glass, "  position_constraints: []\n  orientation_constraints:",
                                     "  position_constraints:\n    - link_name: panda_hand\n      constraint_region:\n"
                                     "        primitives: [{type: 2, dimensions: [0.1]}]\n"
                                     "        primitive_poses: [{position: [0.5, 0, 0.5], orientation: [0, 0, 0, 1]}]\n"
                                     "  orientation_constraints:");
  EXPECT_NE(error(sphere).find("is not a path constraint region here (a BOX [x, y, z] is)"), std::string::npos)
      << error(sphere);
  const std::string box = Replace(sphere, "{type: 2, dimensions: [0.1]}", "{type: 1, dimensions: [2, 2, 0.4]}");
  const v1::PlanRequest request = moveit::ImportMotionPlanRequest(scene, box, Panda(), "s.yaml", "request.yaml");
  ASSERT_EQ(request.path_constraints().position_size(), 1);
  EXPECT_EQ(request.path_constraints().position(0).half_extents().z(), 0.2);
  EXPECT_EQ(request.path_constraints().position(0).region().position().x(), 0.5);
}

// request0001 with its joint goal replaced by a 4 cm box and 0.1 rad axis tolerances about the hand's
// pose at that goal: planned through the server, the goal reached lies in MoveIt's region (checked
// here on the box and the axis angles, not on the PoseGoal the importer made).
TEST_F(MoveItExamples, AGoalRegionPlansIntoTheRegion) {
  const std::string scene = testing::ReadText(ExamplesDir() + "/scene0001.yaml");
  std::string yaml = testing::ReadText(ExamplesDir() + "/request0001.yaml");
  const auto robot = RobotFromProto(Panda().model, "robot");
  Eigen::VectorXd goal(7);
  goal << -0.444, 0.176, -0.179, -1.787, 0.034, 1.96, 0.152;  // request0001's joint goal
  std::vector<Eigen::Isometry3d> poses;
  robot->ForwardKinematics(goal, &poses);
  const Eigen::Isometry3d hand = poses[static_cast<std::size_t>(robot->FindLink("panda_hand"))];
  const Eigen::Quaterniond q(hand.linear());
  char region[1024];
  std::snprintf(region, sizeof(region),
                "goal_constraints:\n"
                "  - position_constraints:\n"
                "      - link_name: panda_hand\n"
                "        constraint_region:\n"
                "          primitives: [{type: 1, dimensions: [0.04, 0.04, 0.04]}]\n"
                "          primitive_poses: [{position: [%.17g, %.17g, %.17g], orientation: [0, 0, 0, 1]}]\n"
                "    orientation_constraints:\n"
                "      - link_name: panda_hand\n"
                "        orientation: [%.17g, %.17g, %.17g, %.17g]\n"
                "        absolute_x_axis_tolerance: 0.1\n"
                "        absolute_y_axis_tolerance: 0.1\n"
                "        absolute_z_axis_tolerance: 0.1\n",
                hand.translation().x(), hand.translation().y(), hand.translation().z(), q.x(), q.y(), q.z(), q.w());
  yaml = yaml.substr(0, yaml.find("goal_constraints:")) + region;
  v1::PlanRequest request = ImportMotionPlanRequest(scene, yaml, Panda(), "scene0001.yaml", "request.yaml");
  ASSERT_EQ(request.target_case(), v1::PlanRequest::kPoseGoal);
  request.set_seed(7);
  v1::PlanResponse response;
  const grpc::Status status = server_->Plan(request, &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  ASSERT_EQ(response.outcome(), v1::SUCCESS) << response.message();
  Eigen::VectorXd reached(7);
  for (int i = 0; i < 7; ++i) reached[i] = response.reached_goal().positions(i);
  robot->ForwardKinematics(reached, &poses);
  const Eigen::Isometry3d at = poses[static_cast<std::size_t>(robot->FindLink("panda_hand"))];
  const Eigen::Vector3d offset = at.translation() - hand.translation();
  EXPECT_LE(offset.cwiseAbs().maxCoeff(), 0.02) << offset.transpose();
  const Eigen::Vector3d turn = Eigen::AngleAxisd(hand.linear().transpose() * at.linear()).angle() *
                               Eigen::AngleAxisd(hand.linear().transpose() * at.linear()).axis();
  EXPECT_LE(turn.cwiseAbs().maxCoeff(), 0.1) << turn.transpose();
}

TEST_F(MoveItExamples, TheCartesianExampleConvertsAndIsDrawnWholeThroughTheServer) {
  const std::string scene = testing::ReadText(ExamplesDir() + "/scene0001.yaml");
  const std::string yaml = testing::ReadText(ExamplesDir() + "/cartesian0001.yaml");
  ASSERT_TRUE(moveit::IsCartesianPathRequest(yaml));
  EXPECT_FALSE(moveit::IsCartesianPathRequest(testing::ReadText(ExamplesDir() + "/request0001.yaml")));
  const v1::CartesianPathRequest request =
      moveit::ImportCartesianPathRequest(scene, yaml, Panda(), "scene0001.yaml", "cartesian0001.yaml");
  EXPECT_EQ(request.link(), "panda_tcp");
  ASSERT_EQ(request.start().positions_size(), 7);  // the finger joints are not the robot's
  EXPECT_EQ(request.start().positions(3), -1.787);
  ASSERT_EQ(request.waypoints_size(), 3);
  EXPECT_NEAR(request.waypoints(1).position().y(), 0.199848877034, kTight);
  EXPECT_NEAR(request.waypoints(2).position().z(), 0.350059929057, kTight);
  EXPECT_EQ(request.max_step(), 0.01);
  EXPECT_FALSE(request.ignore_collisions());
  EXPECT_EQ(request.scene().boxes_size(), ImportPlanningScene(scene, Panda(), "s").boxes_size());
  v1::CartesianPathResponse response;
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
  ASSERT_TRUE(server_->stub().CartesianPath(&context, request, &response).ok());
  EXPECT_EQ(response.stop(), v1::CartesianPathResponse::COMPLETE) << response.message();
  EXPECT_EQ(response.timed().outcome(), v1::SUCCESS) << response.timed().message();
}

TEST(MoveItCartesian, FramesJumpThresholdsAndNamedErrors) {
  const std::string scene = Data("scene_full.yaml");
  const std::string base = testing::ReadText(ExamplesDir() + "/cartesian0001.yaml");
  const auto import = [&](const std::string& yaml) {
    return moveit::ImportCartesianPathRequest(scene, yaml, Panda(), "scene.yaml", "cartesian.yaml");
  };
  const auto error = [&](const std::string& yaml) { return ErrorOf([&] { import(yaml); }); };
  // Waypoints in a scene frame: "bench" is 0.5 m above the base.
  const v1::CartesianPathRequest bench = import(Replace(base, "frame_id: panda_link0", "frame_id: bench"));
  EXPECT_NEAR(bench.waypoints(0).position().z(), 0.950059929057, kTight);
  // Thresholds: relative (0 or >= 1) as is, revolute as max_joint_jump; avoid_collisions false.
  const v1::CartesianPathRequest jumps = import(Replace(
      Replace(Replace(base, "jump_threshold: 0.0", "jump_threshold: 2.5"), "revolute_jump_threshold: 0.0",
              "revolute_jump_threshold: 0.3"),
      "avoid_collisions: true", "avoid_collisions: false"));
  EXPECT_EQ(jumps.jump_threshold(), 2.5);
  EXPECT_EQ(jumps.max_joint_jump(), 0.3);
  EXPECT_TRUE(jumps.ignore_collisions());
  // Absent avoid_collisions: checked (moveit_msgs would default to false).
  EXPECT_FALSE(import(Replace(base, "avoid_collisions: true", "")).ignore_collisions());
  EXPECT_EQ(error(Replace(base, "\njump_threshold: 0.0", "\njump_threshold: 0.5")),
            "cartesian.yaml: jump_threshold = 0.5 must be 0 (off) or >= 1 (a multiple of the mean step)");
  EXPECT_NE(error(Replace(base, "prismatic_jump_threshold: 0.0", "prismatic_jump_threshold: 0.01"))
                .find("cartesian.yaml: prismatic_jump_threshold is not supported"),
            std::string::npos);
  EXPECT_NE(error(Replace(base, "link_name: panda_tcp", "link_name: gripper")).find("link_name = 'gripper' is not a link"),
            std::string::npos);
  EXPECT_NE(error(Replace(base, "frame_id: panda_link0", "frame_id: camera")).find("header.frame_id = 'camera' is not a known frame"),
            std::string::npos);
  EXPECT_NE(error(base + "path_constraints:\n  orientation_constraints:\n    - {link_name: panda_tcp}\n")
                .find("path constraints are not supported"),
            std::string::npos);
  EXPECT_NE(error(Replace(base, "max_step: 0.01", "max_step: 0")).find("max_step = 0 must be > 0"), std::string::npos);
  const std::size_t at = base.find("waypoints:");
  const std::size_t end = base.find("max_step:");
  EXPECT_NE(error(base.substr(0, at) + "waypoints: []\n" + base.substr(end)).find("waypoints is empty"),
            std::string::npos);
}

TEST_F(MoveItExamples, AllowedCollisionsReachTheChecker) {
  // A mounting plate around the Panda's base touches panda_link0: without an ACM entry the start
  // collides; with the entry (imported as the pair panda_link0 / plate) the problem plans.
  const std::string scene =
      "robot_state:\n  joint_state:\n"
      "    name: [panda_joint1, panda_joint2, panda_joint3, panda_joint4, panda_joint5, panda_joint6, panda_joint7]\n"
      "    position: [0, -0.785, 0, -2.356, 0, 1.571, 0.785]\n"
      "world:\n  collision_objects:\n    - id: plate\n"
      "      primitives: [{type: box, dimensions: [0.4, 0.4, 0.05]}]\n"
      "      primitive_poses: [{position: [0, 0, 0.025], orientation: [0, 0, 0, 1]}]\n";
  const std::string acm =
      "allowed_collision_matrix:\n  entry_names: [panda_link0, plate]\n  entry_values: [[false, true], [true, "
      "false]]\n";
  const std::string goal =
      "goal_constraints:\n  - joint_constraints:\n      - {joint_name: panda_joint1, position: -1.0}\n"
      "      - {joint_name: panda_joint2, position: -0.3}\n      - {joint_name: panda_joint4, position: -2.2}\n"
      "      - {joint_name: panda_joint6, position: 1.9}\n";
  for (const bool allowed : {false, true}) {
    SCOPED_TRACE(allowed ? "with the entry" : "without the entry");
    v1::PlanRequest request = ImportMotionPlanRequest(allowed ? scene + acm : scene, goal, Panda(), "s", "r");
    ASSERT_EQ(request.scene().allowed_collisions_size(), allowed ? 1 : 0);
    request.mutable_planner()->set_planner_id("rrt_connect");
    request.set_seed(7);
    v1::PlanResponse response;
    const grpc::Status status = server_->Plan(request, &response);
    ASSERT_TRUE(status.ok()) << status.error_message();
    EXPECT_EQ(response.outcome(), allowed ? v1::SUCCESS : v1::START_IN_COLLISION) << response.message();
  }
}

}  // namespace
}  // namespace chasles
