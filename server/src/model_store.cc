#include "chasles/server/model_store.h"

#include "chasles/robot/error.h"
#include "chasles/server/convert.h"

namespace chasles {

ModelStore::ModelStore(const v1::RobotModel& default_robot, const v1::Scene& default_scene,
                       std::size_t capacity)
    : robots_(capacity), scenes_(capacity), checkers_(capacity) {
  default_robot_ = {ProtoContentId(default_robot), RobotFromProto(default_robot, "default robot")};
  default_scene_ = {ProtoContentId(default_scene), SceneFromProto(default_scene, "default scene")};
}

StoredRobot ModelStore::AddRobot(const v1::RobotModel& robot, const std::string& field) {
  std::string id = ProtoContentId(robot);
  if (id == default_robot_.id) return default_robot_;
  if (auto model = robots_.Get(id)) return {id, model};
  auto model = robots_.Put(id, RobotFromProto(robot, field));
  return {std::move(id), std::move(model)};
}

StoredScene ModelStore::AddScene(const v1::Scene& scene, const std::string& field) {
  std::string id = ProtoContentId(scene);
  if (id == default_scene_.id) return default_scene_;
  if (auto stored = scenes_.Get(id)) return {id, stored};
  auto stored = scenes_.Put(id, SceneFromProto(scene, field));
  return {std::move(id), std::move(stored)};
}

StoredScene ModelStore::PutScene(const std::string& id, std::shared_ptr<const Scene> scene) {
  if (id == default_scene_.id) return default_scene_;
  return {id, scenes_.Put(id, std::move(scene))};
}

StoredRobot ModelStore::FindRobot(const std::string& id) const {
  if (id == default_robot_.id) return default_robot_;
  if (auto model = robots_.Get(id)) return {id, model};
  throw Error(ErrorCode::kNotFound, "robot_id '" + id +
                                        "' is not stored on this server (never uploaded here, or evicted); "
                                        "re-send the robot inline (the request's robot field) or call UploadRobot again");
}

StoredScene ModelStore::FindScene(const std::string& id) const {
  if (id == default_scene_.id) return default_scene_;
  if (auto scene = scenes_.Get(id)) return {id, scene};
  throw Error(ErrorCode::kNotFound, "scene_id '" + id +
                                        "' is not stored on this server (never uploaded here, or evicted); "
                                        "send the scene inline (the request's scene field) or call UploadScene again");
}

std::shared_ptr<const CollisionChecker> ModelStore::Checker(const StoredRobot& robot, const StoredScene& scene) {
  const std::string key = robot.id + "/" + scene.id;
  if (auto checker = checkers_.Get(key)) return checker;
  return checkers_.Put(key, std::make_shared<const CollisionChecker>(robot.model, scene.scene));
}

}  // namespace chasles
