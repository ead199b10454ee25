#pragma once
/// \file
/// Parsed robots, scenes and collision checkers by content-hash id. Thread-safe; bounded in
/// bytes (one LRU over all three kinds).

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "chasles/collision/collision_checker.h"
#include "chasles/collision/robot_spheres.h"
#include "chasles/robot/input_limits.h"
#include "chasles/server/lru_cache.h"
#include "chasles/server/redis_client.h"
#include "chasles/robot/planning_groups.h"
#include "chasles/v1/chasles.pb.h"

namespace chasles {

struct StoredRobot {
  std::string id;
  /// What planning, checking and every other use of the robot see: the robot as described, or,
  /// for a URDF with meshes (UrdfRobot.exact_meshes false), the same robot with its collision
  /// shapes covered by spheres (FitRobotSpheres, once per stored robot).
  std::shared_ptr<const RobotModel> model;
  /// When model is fitted: the robot as described (its exact shapes) and the fit's figures.
  std::shared_ptr<const RobotModel> exact;
  std::shared_ptr<const RobotSphereFit> fit;
  /// The SRDF's planning groups (ReadPlanningGroups) and what reading them skipped, each
  /// warning naming the proto field (`robot.urdf.srdf: group 'arm' …`).
  std::vector<PlanningGroup> groups;
  std::vector<std::string> group_warnings;
};

struct StoredScene {
  std::string id;
  std::shared_ptr<const Scene> scene;
};

/// The default robot (examples/robots/panda.urdf/.srdf) and scene (examples/scenes/table.json),
/// embedded at build time, as messages. \throws std::runtime_error if the scene does not parse.
v1::RobotModel DefaultRobotProto();
v1::Scene DefaultSceneProto();

class ModelStore {
 public:
  /// Parses the default robot and scene (used when a request names none); they are never
  /// evicted. \throws Error when either does not parse.
  /// `cache_bytes` bounds the estimated bytes of every cached robot, scene and checker together
  /// (the defaults are outside it). An entry's estimate is the largest of its message size, the
  /// operator-new bytes its parsing/construction left allocated on this thread, and the process's
  /// malloc growth over that construction.
  /// `limits` caps every robot and scene parsed here (documents, links, DOF, meshes, maps).
  ModelStore(const v1::RobotModel& default_robot, const v1::Scene& default_scene,
             std::uint64_t cache_bytes = 256ull << 20, const InputLimits& limits = {});

  /// Parses (unless its id is already stored) and stores a robot. \throws Error naming `field`.
  StoredRobot AddRobot(const v1::RobotModel& robot, const std::string& field = "robot");
  StoredScene AddScene(const v1::Scene& scene, const std::string& field = "scene");
  /// Stores a scene made on the server (UpdateScene) under its content id `id`. When `id` is
  /// stored already, keeps and returns the stored scene (same id, same content).
  /// `bytes` is its estimated size (e.g. measured with a HeapScope around its making).
  StoredScene PutScene(const std::string& id, std::shared_ptr<const Scene> scene, std::uint64_t bytes);
  /// \throws Error(kNotFound) telling the client to re-send the robot/scene inline.
  /// With a shared store, an id not cached here is read from Redis (and parsed once here).
  StoredRobot FindRobot(const std::string& id);
  StoredScene FindScene(const std::string& id);
  const StoredRobot& default_robot() const { return default_robot_; }
  const StoredScene& default_scene() const { return default_scene_; }

  /// `robot` carrying `objects` (AttachObjects), built once per (robot, objects) and cached: its
  /// id is robot.id + "+" + the objects' content id, so checkers are cached per load. On a robot
  /// whose shapes are all spheres (the fast, certified path) each object's shapes are covered by
  /// spheres (FitShapeSpheres), and `warnings` gets how far they reach outside the shapes. The
  /// same as `robot` for no objects. \throws Error(kInvalidArgument) naming `field[i]`.
  StoredRobot Carrying(const StoredRobot& robot, const google::protobuf::RepeatedPtrField<v1::AttachedObject>& objects,
                       const std::string& field, std::vector<std::string>* warnings);

  /// The checker for (robot, scene) with `padding` [m] around every robot shape
  /// (CollisionOptions::padding, validated by the caller), built once per (robot, scene,
  /// padding) and cached: a checker is never shared between paddings.
  std::shared_ptr<const CollisionChecker> Checker(const StoredRobot& robot, const StoredScene& scene,
                                                  double padding = 0.0);

  CacheStats cache_stats() const { return cache_.stats(); }
  const InputLimits& limits() const { return limits_; }

  /// Shares uploaded robots and scenes through Redis from now on (before serving): each parsed
  /// robot or scene is kept there under "chasles:robot:<id>" / "chasles:scene:<id>" (its message,
  /// content-addressed, never expiring), and an id this replica does not hold is read from there.
  /// Scenes made by UpdateScene stay on the replica that made them.
  void UseShared(std::shared_ptr<RedisClient> redis);

 private:
  void Share(const std::string& key, const std::string& bytes);
  bool Fetch(const std::string& key, google::protobuf::Message* message);

  std::shared_ptr<RedisClient> redis_;
  StoredRobot default_robot_;
  StoredScene default_scene_;
  InputLimits limits_;
  mutable LruCache cache_;
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
