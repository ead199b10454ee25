// InputLimits through the server's conversions: caps that only the conversion can apply
// (the number of mesh files of a robot or a scene) and the limits reaching the parsers.

#include <string>

#include <gtest/gtest.h>

#include "chasles/robot/error.h"
#include "chasles/server/convert.h"

namespace chasles {
namespace {

void ExpectExhausted(const std::function<void()>& fn, const std::string& message) {
  try {
    fn();
    ADD_FAILURE() << "no Error thrown; expected: " << message;
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kResourceExhausted);
    EXPECT_EQ(std::string(e.what()), message);
  }
}

TEST(ConvertInputLimits, MeshFilesAreCountedBeforeAnyIsParsed) {
  InputLimits limits;
  limits.max_mesh_files = 2;
  v1::Scene scene;
  for (int i = 0; i < 3; ++i) scene.add_meshes()->set_data("v 0 0 0\n");  // never parsed
  ExpectExhausted([&] { SceneFromProto(scene, "scene", limits); },
                  "scene.meshes holds 3 mesh files, more than the cap of 2 (InputLimits::max_mesh_files); merge "
                  "meshes or raise the server's cap");
  v1::RobotModel robot;
  robot.mutable_urdf()->set_urdf("<robot name=\"r\"><link name=\"a\"/></robot>");
  for (const char* name : {"a.obj", "b.obj", "c.obj"}) (*robot.mutable_urdf()->mutable_mesh_files())[name] = "x";
  ExpectExhausted([&] { RobotFromProto(robot, "robot", limits); },
                  "robot.urdf.mesh_files holds 3 mesh files, more than the cap of 2 (InputLimits::max_mesh_files); "
                  "merge meshes or raise the server's cap");
}

TEST(ConvertInputLimits, SceneObjectsAreCountedBeforeAnyIsBuilt) {
  InputLimits limits;
  limits.max_scene_objects = 4;
  v1::Scene scene;
  for (int i = 0; i < 2; ++i) scene.add_boxes();  // zero-sized: never converted
  scene.add_spheres();
  scene.add_cylinders();
  scene.add_meshes()->set_data("v 0 0 0\n");  // never parsed
  ExpectExhausted([&] { SceneFromProto(scene, "scene", limits); },
                  "scene holds 5 objects (2 boxes, 1 spheres, 1 cylinders, 0 capsules, 1 meshes, 0 octomaps), more "
                  "than the cap of 4 (InputLimits::max_scene_objects, --max-scene-objects); merge objects into "
                  "meshes or an OctoMap, or raise the server's cap");
  // At the cap, the scene is read (and its first bad field reported, as without a cap).
  scene.mutable_meshes()->Clear();
  try {
    SceneFromProto(scene, "scene", limits);
    ADD_FAILURE() << "a zero-sized box was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument) << e.what();
  }
}

TEST(ConvertInputLimits, LimitsReachTheUrdfParser) {
  InputLimits limits;
  limits.max_xml_depth = 2;
  v1::RobotModel robot;
  robot.mutable_urdf()->set_urdf("<robot name=\"r\"><link name=\"a\"><inertial/></link></robot>");
  ExpectExhausted([&] { RobotFromProto(robot, "robot", limits); },
                  "robot.urdf.urdf nests XML elements 3 deep, more than the cap of 2 (InputLimits::max_xml_depth); "
                  "flatten the document or raise the server's cap");
}

}  // namespace
}  // namespace chasles
