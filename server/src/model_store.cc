#include "chasles/server/model_store.h"

#include <malloc.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include <google/protobuf/util/json_util.h>

#include "chasles/collision/shape_spheres.h"
#include "chasles/robot/attached_objects.h"
#include "chasles/robot/error.h"
#include "chasles/server/content_hash.h"
#include "chasles/server/convert.h"
#include "chasles/server/default_assets.h"
#include "chasles/server/heap_tracking.h"

namespace chasles {

v1::RobotModel DefaultRobotProto() {
  v1::RobotModel robot;
  robot.set_name("panda");
  robot.mutable_urdf()->set_urdf(std::string(kDefaultRobotUrdf));
  robot.mutable_urdf()->set_srdf(std::string(kDefaultRobotSrdf));
  return robot;
}

v1::Scene DefaultSceneProto() {
  v1::Scene scene;
  const auto status = google::protobuf::util::JsonStringToMessage(std::string(kDefaultSceneJson), &scene);
  if (!status.ok()) {
    throw std::runtime_error("embedded default scene (examples/scenes/table.json) does not parse: " +
                             status.ToString());
  }
  return scene;
}
namespace {

/// Bytes malloc holds for the whole process (heap blocks in use plus mmapped blocks).
std::int64_t MallocBytesInUse() {
  const struct mallinfo2 info = mallinfo2();
  return static_cast<std::int64_t>(info.uordblks) + static_cast<std::int64_t>(info.hblkhd);
}

/// Runs `make` and returns its result with an estimate of the bytes it left allocated: the larger
/// of this thread's operator-new bytes (exact, but blind to malloc: Eigen's aligned buffers in
/// FCL's BVHs, C libraries) and the process's malloc growth over the call (sees everything, but
/// other threads' traffic too), and at least `message_bytes`.
template <typename Make>
auto Measured(std::size_t message_bytes, std::uint64_t* bytes, Make make) {
  const std::int64_t malloc_before = MallocBytesInUse();
  HeapScope scope;
  auto value = make();
  const std::int64_t grown = std::max(scope.live_bytes(), MallocBytesInUse() - malloc_before);
  *bytes = std::max<std::uint64_t>(message_bytes, static_cast<std::uint64_t>(std::max<std::int64_t>(0, grown)));
  return value;
}

}  // namespace

ModelStore::ModelStore(const v1::RobotModel& default_robot, const v1::Scene& default_scene,
                       std::uint64_t cache_bytes, const InputLimits& limits)
    : limits_(limits), cache_(cache_bytes) {
  default_robot_.id = ProtoContentId(default_robot);
  default_robot_.model = RobotFromProto(default_robot, "default robot");
  default_scene_ = {ProtoContentId(default_scene), SceneFromProto(default_scene, "default scene")};
}

StoredRobot ModelStore::AddRobot(const v1::RobotModel& robot, const std::string& field) {
  std::string id = ProtoContentId(robot);
  if (id == default_robot_.id) return default_robot_;
  if (auto stored = cache_.Get<StoredRobot>("robot:" + id)) return *stored;
  std::uint64_t bytes = 0;
  auto parsed = Measured(robot.ByteSizeLong(), &bytes, [&] {
    auto entry = std::make_shared<StoredRobot>();
    entry->id = id;
    entry->model = RobotFromProto(robot, field, limits_);
    if (robot.description_case() == v1::RobotModel::kUrdf && !robot.urdf().srdf().empty()) {
      std::vector<std::string> warnings;
      try {
        entry->groups = ReadPlanningGroups(*entry->model, robot.urdf().srdf(), robot.urdf().strict_srdf(), &warnings);
      } catch (const Error& e) {
        throw Error(e.code(), field + ".urdf." + e.what());
      }
      for (std::string& warning : warnings) entry->group_warnings.push_back(field + ".urdf." + warning);
    }
    // A URDF with meshes: its shapes covered by spheres, once, here (not per request).
    if (robot.description_case() == v1::RobotModel::kUrdf && !robot.urdf().exact_meshes()) {
      RobotSphereFit fit = FitRobotSpheres(*entry->model);
      if (fit.model != nullptr) {
        entry->exact = std::move(entry->model);
        entry->model = fit.model;
        entry->fit = std::make_shared<const RobotSphereFit>(std::move(fit));
      }
    }
    return std::shared_ptr<const StoredRobot>(std::move(entry));
  });
  if (redis_ != nullptr) Share("chasles:robot:" + id, robot.SerializeAsString());
  return *cache_.Put<StoredRobot>("robot:" + id, std::move(parsed), bytes);
}

StoredRobot ModelStore::Carrying(const StoredRobot& robot,
                                 const google::protobuf::RepeatedPtrField<v1::AttachedObject>& objects,
                                 const std::string& field, std::vector<std::string>* warnings) {
  if (objects.empty()) return robot;
  std::string bytes;
  for (const v1::AttachedObject& object : objects) bytes += object.SerializeAsString();
  const std::string id = robot.id + "+" + ContentId(bytes);
  const std::string key = "carrying:" + id;
  struct Carried {
    StoredRobot robot;
    std::vector<std::string> warnings;
  };
  if (auto stored = cache_.Get<Carried>(key)) {
    warnings->insert(warnings->end(), stored->warnings.begin(), stored->warnings.end());
    return stored->robot;
  }
  std::uint64_t size = 0;
  auto built = Measured(bytes.size(), &size, [&] {
    auto entry = std::make_shared<Carried>();
    const std::vector<AttachedObject> exact = AttachedObjectsFromProto(objects, *robot.model, field);
    std::vector<AttachedObject> carried = exact;
    bool spheres = true;
    for (const Link& link : robot.model->links()) {
      for (const Shape& shape : link.collision) spheres = spheres && shape.type == ShapeType::kSphere;
    }
    if (spheres) {
      for (std::size_t i = 0; i < carried.size(); ++i) {
        std::vector<Shape> covered;
        double reach = 0.0;
        for (const Shape& shape : carried[i].shapes) {
          if (shape.type == ShapeType::kSphere) {
            covered.push_back(shape);
            continue;
          }
          const FittedSpheres fit = FitShapeSpheres(shape);
          reach = std::max(reach, fit.reach);
          for (std::size_t k = 0; k < fit.centres.size(); ++k) {
            covered.push_back(Shape::Sphere(fit.radii[k], shape.pose * Eigen::Translation3d(fit.centres[k])));
          }
        }
        if (reach > 0.0) {
          entry->warnings.push_back(field + "[" + std::to_string(i) + "] ('" + carried[i].name + "'): covered by " +
                                    std::to_string(covered.size()) + " spheres reaching at most " +
                                    FormatNumber(std::ceil(reach * 1e4) / 1e4) +  // rounded up: still a bound
                                    " m outside its shapes (the robot is checked as spheres)");
        }
        carried[i].shapes = std::move(covered);
      }
    }
    entry->robot = robot;
    entry->robot.id = id;
    entry->robot.model = AttachObjects(*robot.model, carried, field);
    if (robot.exact != nullptr) entry->robot.exact = AttachObjects(*robot.exact, exact, field);
    return std::shared_ptr<const Carried>(std::move(entry));
  });
  const auto stored = cache_.Put<Carried>(key, std::move(built), std::max<std::uint64_t>(size, 1));
  warnings->insert(warnings->end(), stored->warnings.begin(), stored->warnings.end());
  return stored->robot;
}

StoredScene ModelStore::AddScene(const v1::Scene& scene, const std::string& field) {
  std::string id = ProtoContentId(scene);
  if (id == default_scene_.id) return default_scene_;
  if (auto stored = cache_.Get<Scene>("scene:" + id)) return {id, stored};
  std::uint64_t bytes = 0;
  auto parsed = Measured(scene.ByteSizeLong(), &bytes, [&] { return SceneFromProto(scene, field, limits_); });
  if (redis_ != nullptr) Share("chasles:scene:" + id, scene.SerializeAsString());
  auto stored = cache_.Put<Scene>("scene:" + id, std::move(parsed), bytes);
  return {std::move(id), std::move(stored)};
}

StoredScene ModelStore::PutScene(const std::string& id, std::shared_ptr<const Scene> scene, std::uint64_t bytes) {
  if (id == default_scene_.id) return default_scene_;
  return {id, cache_.Put<Scene>("scene:" + id, std::move(scene), std::max<std::uint64_t>(bytes, 1))};
}

StoredRobot ModelStore::FindRobot(const std::string& id) {
  if (id == default_robot_.id) return default_robot_;
  if (auto stored = cache_.Get<StoredRobot>("robot:" + id)) return *stored;
  v1::RobotModel shared;
  if (Fetch("chasles:robot:" + id, &shared)) return AddRobot(shared, "robot_id '" + id + "' (from the shared store)");
  throw Error(ErrorCode::kNotFound, "robot_id '" + id +
                                        "' is not stored on this server (never uploaded here, or evicted); "
                                        "re-send the robot inline (the request's robot field) or call UploadRobot again");
}

StoredScene ModelStore::FindScene(const std::string& id) {
  if (id == default_scene_.id) return default_scene_;
  if (auto scene = cache_.Get<Scene>("scene:" + id)) return {id, scene};
  v1::Scene shared;
  if (Fetch("chasles:scene:" + id, &shared)) return AddScene(shared, "scene_id '" + id + "' (from the shared store)");
  throw Error(ErrorCode::kNotFound, "scene_id '" + id +
                                        "' is not stored on this server (never uploaded here, or evicted); "
                                        "send the scene inline (the request's scene field) or call UploadScene again");
}

std::shared_ptr<const CollisionChecker> ModelStore::Checker(const StoredRobot& robot, const StoredScene& scene,
                                                        double padding) {
  // The padding exactly (hex float), so no two paddings share a key; none keeps the old key.
  std::string key = "checker:" + robot.id + "/" + scene.id;
  if (padding != 0.0) {
    char text[40];
    std::snprintf(text, sizeof(text), "/padding=%a", padding);
    key += text;
  }
  if (auto checker = cache_.Get<CollisionChecker>(key)) return checker;
  CollisionOptions options;
  options.padding = padding;
  std::uint64_t bytes = 0;
  auto built = Measured(0, &bytes, [&] {
    return std::make_shared<const CollisionChecker>(robot.model, scene.scene, options);
  });
  return cache_.Put<CollisionChecker>(key, std::move(built), std::max<std::uint64_t>(bytes, 1));
}

void ModelStore::UseShared(std::shared_ptr<RedisClient> redis) { redis_ = std::move(redis); }

void ModelStore::Share(const std::string& key, const std::string& bytes) { redis_->Command({"SET", key, bytes, "NX"}); }

bool ModelStore::Fetch(const std::string& key, google::protobuf::Message* message) {
  if (redis_ == nullptr) return false;
  const RedisReply reply = redis_->Command({"GET", key});
  if (reply.type != RedisReply::Type::kString) return false;
  if (!message->ParseFromString(reply.str)) {
    throw Error(ErrorCode::kFailedPrecondition, "the shared store holds an unreadable " + key);
  }
  return true;
}

}  // namespace chasles
