// MoveIt YAML (chasles import-moveit): a PlanningScene, then optionally the separator
// "\n--REQUEST--\n" and a MotionPlanRequest (or a GetCartesianPath request: one with waypoints),
// read against the default Panda; the resulting scene goes through SceneFromProto as the server
// would read it.

#include "chasles/server/convert.h"
#include "fuzz_util.h"
#include "moveit_import.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const chasles::moveit::RobotInfo* robot = new chasles::moveit::RobotInfo(chasles::moveit::DefaultRobot());
  const std::string_view input(reinterpret_cast<const char*>(data), size);
  const auto [scene_yaml, request_yaml] = chasles::fuzz::Split(input, "\n--REQUEST--\n");
  chasles::fuzz::Expect([&, scene_yaml = scene_yaml, request_yaml = request_yaml] {
    const chasles::v1::Scene scene = chasles::moveit::ImportPlanningScene(std::string(scene_yaml), *robot, "scene.yaml");
    chasles::SceneFromProto(scene, "scene");
    if (!request_yaml.empty() && chasles::moveit::IsCartesianPathRequest(std::string(request_yaml))) {
      chasles::moveit::ImportCartesianPathRequest(std::string(scene_yaml), std::string(request_yaml), *robot,
                                                  "scene.yaml", "request.yaml");
    } else if (!request_yaml.empty()) {
      chasles::moveit::ImportMotionPlanRequest(std::string(scene_yaml), std::string(request_yaml), *robot, "scene.yaml",
                                               "request.yaml");
    }
  });
  return 0;
}
