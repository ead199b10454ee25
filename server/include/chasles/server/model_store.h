#pragma once
/// \file
/// Parsed robots, scenes and collision checkers by content-hash id. Thread-safe; bounded (LRU).

#include <cstddef>
#include <memory>
#include <string>

#include "chasles/collision/collision_checker.h"
#include "chasles/server/lru_cache.h"
#include "chasles/v1/chasles.pb.h"

namespace chasles {

struct StoredRobot {
  std::string id;
  std::shared_ptr<const RobotModel> model;
};

struct StoredScene {
  std::string id;
  std::shared_ptr<const Scene> scene;
};

class ModelStore {
 public:
  /// Parses the default robot and scene (used when a request names none); they are never
  /// evicted. \throws Error when either does not parse.
  ModelStore(const v1::RobotModel& default_robot, const v1::Scene& default_scene,
             std::size_t capacity = 64);

  /// Parses (unless its id is already stored) and stores a robot. \throws Error naming `field`.
  StoredRobot AddRobot(const v1::RobotModel& robot, const std::string& field = "robot");
  StoredScene AddScene(const v1::Scene& scene, const std::string& field = "scene");
  /// Stores a scene made on the server (UpdateScene) under its content id `id`. When `id` is
  /// stored already, keeps and returns the stored scene (same id, same content).
  StoredScene PutScene(const std::string& id, std::shared_ptr<const Scene> scene);
  /// \throws Error(kNotFound) telling the client to re-send the robot/scene inline.
  StoredRobot FindRobot(const std::string& id) const;
  StoredScene FindScene(const std::string& id) const;
  const StoredRobot& default_robot() const { return default_robot_; }
  const StoredScene& default_scene() const { return default_scene_; }

  /// The checker for (robot, scene), built once per pair and cached.
  std::shared_ptr<const CollisionChecker> Checker(const StoredRobot& robot, const StoredScene& scene);

 private:
  StoredRobot default_robot_;
  StoredScene default_scene_;
  mutable LruCache<RobotModel> robots_;
  mutable LruCache<Scene> scenes_;
  LruCache<CollisionChecker> checkers_;
};

/// The request's robot: inline (parsed and cached; errors name `field`), by id, or the store's
/// default. Works for every request with a `robot_source` oneof of `robot` / `robot_id`.
template <typename Request>
StoredRobot RobotOfRequest(ModelStore& store, const Request& request, const std::string& field = "robot") {
  switch (request.robot_source_case()) {
    case Request::kRobot: return store.AddRobot(request.robot(), field);
    case Request::kRobotId: return store.FindRobot(request.robot_id());
    default: return store.default_robot();
  }
}

/// The request's scene: inline (parsed and cached; errors name `field`), by id, or the default.
template <typename Request>
StoredScene SceneOfRequest(ModelStore& store, const Request& request, const std::string& field = "scene") {
  switch (request.scene_source_case()) {
    case Request::kScene: return store.AddScene(request.scene(), field);
    case Request::kSceneId: return store.FindScene(request.scene_id());
    default: return store.default_scene();
  }
}

}  // namespace chasles
