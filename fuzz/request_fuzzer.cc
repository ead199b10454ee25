// Request messages as protobuf bytes -> the server's conversions, as the server runs them:
// the first byte selects the message (modulo 7), the rest is its wire encoding.
//   0 PlanRequest            robot, scene, CollisionChecker, PlanQueryFromProto
//   1 OptimizeRequest        robot, scene, CollisionChecker, OptimizeQueryFromProto
//   2 CoordinateRequest      scene, CoordinationQueryFromProto (each team robot inline or default)
//   3 UploadRobotRequest     RobotFromProto
//   4 UploadSceneRequest     SceneFromProto
//   5 UpdateSceneRequest     PointCloudInsertion into the default scene (Scene::InsertPointCloud)
//   6 InverseKinematicsRequest  robot, IkRequestFromProto (and the scene when collision_free)
//   7 CartesianPathRequest   robot carrying its attached_objects (AttachObjects, exact shapes),
//                            CartesianSpecFromProto, the start (ConfigurationFromProto)
// A robot or scene given by id, or absent, is the server's default (examples/robots/panda.urdf
// and .srdf, examples/scenes/table.json). Nothing is planned or solved: the targets are the parsers.

#include <memory>
#include <string>
#include <vector>

#include <google/protobuf/stubs/logging.h>
#include <google/protobuf/util/json_util.h>

#include "chasles/collision/collision_checker.h"
#include "chasles/planners/registry.h"
#include "chasles/robot/attached_objects.h"
#include "chasles/server/convert.h"
#include "chasles/server/convert_cartesian.h"
#include "chasles/server/convert_multi.h"
#include "fuzz_util.h"

namespace chasles::fuzz {
namespace {

struct Defaults {
  std::shared_ptr<const RobotModel> robot;
  std::shared_ptr<const Scene> scene;
  PlannerRegistry registry;
};

const Defaults& Server() {
  static const Defaults* defaults = [] {
    auto* d = new Defaults;
    v1::RobotModel robot;
    robot.mutable_urdf()->set_urdf(ReadSourceFile("examples/robots/panda.urdf"));
    robot.mutable_urdf()->set_srdf(ReadSourceFile("examples/robots/panda.srdf"));
    d->robot = RobotFromProto(robot);
    v1::Scene scene;
    if (!google::protobuf::util::JsonStringToMessage(ReadSourceFile("examples/scenes/table.json"), &scene).ok()) {
      std::abort();
    }
    d->scene = SceneFromProto(scene);
    RegisterDefaultPlanners(&d->registry);
    return d;
  }();
  return *defaults;
}

template <typename Request>
std::shared_ptr<const RobotModel> RobotOf(const Request& request) {
  return request.robot_source_case() == Request::kRobot ? RobotFromProto(request.robot(), "robot") : Server().robot;
}
template <typename Request>
std::shared_ptr<const Scene> SceneOf(const Request& request) {
  return request.scene_source_case() == Request::kScene ? SceneFromProto(request.scene(), "scene") : Server().scene;
}

template <typename Message>
bool Parse(std::string_view bytes, Message* message) {
  return message->ParseFromArray(bytes.data(), static_cast<int>(bytes.size()));
}

void Convert(int selector, std::string_view bytes) {
  switch (selector) {
    case 0: {
      v1::PlanRequest request;
      if (!Parse(bytes, &request)) return;
      auto checker = std::make_shared<const CollisionChecker>(RobotOf(request), SceneOf(request));
      RequestSettings settings;
      PlanQueryFromProto(request, checker, Server().registry, &settings);
      return;
    }
    case 1: {
      v1::OptimizeRequest request;
      if (!Parse(bytes, &request)) return;
      auto checker = std::make_shared<const CollisionChecker>(RobotOf(request), SceneOf(request));
      RequestSettings settings;
      double input_duration = 0.0;
      OptimizeQueryFromProto(request, checker, &settings, &input_duration);
      return;
    }
    case 2: {
      v1::CoordinateRequest request;
      if (!Parse(bytes, &request)) return;
      std::vector<std::string> warnings;
      CoordinationQueryFromProto(
          request, SceneOf(request),
          [](const v1::TeamRobot& robot, const std::string& field) {
            return robot.robot_source_case() == v1::TeamRobot::kRobot ? RobotFromProto(robot.robot(), field + ".robot")
                                                                      : Server().robot;
          },
          Server().registry, &warnings);
      return;
    }
    case 3: {
      v1::UploadRobotRequest request;
      if (!Parse(bytes, &request)) return;
      RobotFromProto(request.robot(), "robot");
      return;
    }
    case 4: {
      v1::UploadSceneRequest request;
      if (!Parse(bytes, &request)) return;
      SceneFromProto(request.scene(), "scene");
      return;
    }
    case 5: {
      v1::UpdateSceneRequest request;
      if (!Parse(bytes, &request)) return;
      const PointCloudInsertion insertion = PointCloudInsertionFromProto(request);  // as the server does
      PointCloudInsertionStats stats;
      Server().scene->InsertPointCloud(insertion, &stats);
      return;
    }
    case 6: {
      v1::InverseKinematicsRequest request;
      if (!Parse(bytes, &request)) return;
      const auto robot = RobotOf(request);
      IkRequestFromProto(request, *robot);
      if (request.collision_free()) CollisionChecker checker(robot, SceneOf(request));
      return;
    }
    case 7: {
      v1::CartesianPathRequest request;
      if (!Parse(bytes, &request)) return;
      std::shared_ptr<const RobotModel> robot = RobotOf(request);
      if (request.attached_objects_size() > 0) {
        robot = AttachObjects(*robot, AttachedObjectsFromProto(request.attached_objects(), *robot, "attached_objects"));
      }
      CartesianSpecFromProto(request, *robot);
      ConfigurationFromProto(request.start().positions(), *robot, "start.positions");
      return;
    }
  }
}

}  // namespace
}  // namespace chasles::fuzz

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const bool quiet = [] {  // protobuf logs every malformed string field it rejects
    google::protobuf::SetLogHandler(nullptr);
    return true;
  }();
  (void)quiet;
  if (size == 0) return 0;
  chasles::fuzz::Server();
  const std::string_view bytes(reinterpret_cast<const char*>(data) + 1, size - 1);
  chasles::fuzz::Expect([&] { chasles::fuzz::Convert(data[0] % 8, bytes); });
  return 0;
}
