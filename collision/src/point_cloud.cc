// Scene::InsertPointCloud: OctoMap ray-casting insertion into a copy of one of a scene's maps.
#include <chrono>
#include <cmath>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <octomap/OcTree.h>
#include <octomap/Pointcloud.h>

#include "chasles/collision/scene.h"
#include "chasles/robot/error.h"

namespace chasles {
namespace {

constexpr char kNewMapName[] = "points";
constexpr double kDefaultResolution = 0.05;   // [m] of a new map when the request gives 0
constexpr double kMinResolution = 0.001;      // [m]
constexpr double kMaxResolution = 10.0;       // [m]
constexpr double kHalfKeyRange = 32768.0;     // octomap::OcTree's tree_max_val (16 levels)
// [m] longest ray: octomap cuts a ray at max_range in float arithmetic (its squared length
// overflows above about 1.8e19 m, and the direction becomes NaN), so points beyond max_range
// are still refused beyond this distance from the sensor.
constexpr double kMaxRayLength = 1e9;
// [cells] a ray may cross: octomap's KeyRay holds 100000 keys and, without NDEBUG, only asserts
// before writing past them (a heap overflow in release builds). Each step of its voxel walk
// moves one cell along one axis, so |Δkey|₁ + 1 keys at most, plus a margin for rounding.
constexpr double kMaxRayCells = 99000.0;

const char* Axis(int a) { return a == 0 ? "x" : a == 1 ? "y" : "z"; }

std::string MapList(const std::vector<OccupancyMap>& maps) {
  std::string list;
  for (const OccupancyMap& map : maps) list += (list.empty() ? "'" : ", '") + map.name + "'";
  return list;
}

void Validate(const PointCloudInsertion& in) {
  const std::size_t n = in.points.size();
  if (n % 3 != 0) {
    ThrowInvalid("points has " + std::to_string(n) + " values, must be a multiple of 3 (x, y, z triples)");
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(in.points[i])) {
      ThrowInvalid("points[" + std::to_string(i) + "] = " + FormatNumber(in.points[i]) + " must be finite (point " +
                   std::to_string(i / 3) + ", " + Axis(static_cast<int>(i % 3)) + ")");
    }
  }
  for (int a = 0; a < 3; ++a) {
    if (!std::isfinite(in.sensor_origin[a])) {
      ThrowInvalid(std::string("sensor_origin.") + Axis(a) + " = " + FormatNumber(in.sensor_origin[a]) +
                   " must be finite");
    }
  }
  if (!std::isfinite(in.max_range) || in.max_range < 0.0) {
    ThrowInvalid("max_range = " + FormatNumber(in.max_range) + " must be finite and >= 0 (0 = unlimited)");
  }
  if (in.resolution != 0.0 && !(in.resolution >= kMinResolution && in.resolution <= kMaxResolution)) {
    ThrowInvalid("resolution = " + FormatNumber(in.resolution) + " must be within [" + FormatNumber(kMinResolution) +
                 ", " + FormatNumber(kMaxResolution) + "] (0 = " + FormatNumber(kDefaultResolution) + ")");
  }
}

// True when `c` (map frame) has an OctoMap key in `tree`: checked in double first, so huge
// values never reach octomap's float/int conversions.
bool InKeyRange(const octomap::OcTree& tree, const Eigen::Vector3d& c) {
  const double extent = kHalfKeyRange * tree.getResolution();
  for (int a = 0; a < 3; ++a) {
    if (!(c[a] >= -extent && c[a] < extent)) return false;
  }
  octomap::OcTreeKey key;
  return tree.coordToKeyChecked(octomap::point3d(static_cast<float>(c.x()), static_cast<float>(c.y()),
                                                 static_cast<float>(c.z())),
                                key);
}

std::string RangeRule(const OccupancyMap& map, const octomap::OcTree& tree) {
  const double extent = kHalfKeyRange * tree.getResolution();
  return "must lie within [" + FormatNumber(-extent) + ", " + FormatNumber(extent) + ") m of map '" + map.name +
         "' in its frame (the key range of an OctoMap at resolution " + FormatNumber(tree.getResolution()) + " m)";
}

}  // namespace

Scene Scene::InsertPointCloud(const PointCloudInsertion& insertion, PointCloudInsertionStats* stats,
                              const InputLimits& limits) const {
  const auto start = std::chrono::steady_clock::now();
  const std::size_t values = insertion.points.size();
  if (values / 3 > limits.max_cloud_points) {
    ThrowResourceExhausted("points holds " + std::to_string(values / 3) + " points (" + std::to_string(values) +
                           " values), more than the cap of " + std::to_string(limits.max_cloud_points) +
                           " points per insertion (InputLimits::max_cloud_points); send the cloud in parts or "
                           "downsample it, or raise the server's cap");
  }
  Validate(insertion);

  // 1. Which map: the named one, the only one, or a new one.
  int index = -1;
  if (!insertion.octomap.empty()) {
    for (std::size_t i = 0; i < maps_.size() && index < 0; ++i) {
      if (maps_[i].name == insertion.octomap) index = static_cast<int>(i);
    }
    if (index < 0) {
      throw Error(ErrorCode::kNotFound,
                  "octomap = '" + insertion.octomap + "' names no OctoMap of the scene (" +
                      (maps_.empty() ? std::string("it has none; leave octomap empty to create a new map '") +
                                           kNewMapName + "'"
                                     : "its maps: " + MapList(maps_)) +
                      ")");
    }
  } else if (maps_.size() == 1) {
    index = 0;
  } else if (maps_.size() > 1) {
    ThrowInvalid("octomap is empty but the scene has " + std::to_string(maps_.size()) + " OctoMaps (" +
                 MapList(maps_) + "): name the one to update");
  }

  OccupancyMap map;
  std::shared_ptr<octomap::OcTree> tree;
  if (index >= 0) {
    map = maps_[index];
    tree = std::make_shared<octomap::OcTree>(*map.tree);  // deep copy; the shared tree stays as is
  } else {
    map.name = kNewMapName;
    map.pose = Eigen::Isometry3d::Identity();
    tree = std::make_shared<octomap::OcTree>(insertion.resolution > 0.0 ? insertion.resolution
                                                                        : kDefaultResolution);
  }

  // 2. World -> map frame; every ray end (cut at max_range as octomap cuts it) and the origin
  //    must have a key, or octomap would drop the ray silently.
  const Eigen::Isometry3d world_to_map = map.pose.inverse();
  const Eigen::Vector3d origin = world_to_map * insertion.sensor_origin;
  if (!InKeyRange(*tree, origin)) {
    ThrowInvalid("sensor_origin = (" + FormatNumber(insertion.sensor_origin.x()) + ", " +
                 FormatNumber(insertion.sensor_origin.y()) + ", " + FormatNumber(insertion.sensor_origin.z()) +
                 ") " + RangeRule(map, *tree));
  }
  const std::size_t count = insertion.points.size() / 3;
  octomap::Pointcloud cloud;
  cloud.reserve(count);
  const octomap::point3d origin_f(static_cast<float>(origin.x()), static_cast<float>(origin.y()),
                                  static_cast<float>(origin.z()));
  for (std::size_t i = 0; i < count; ++i) {
    const Eigen::Vector3d world(insertion.points[3 * i], insertion.points[3 * i + 1], insertion.points[3 * i + 2]);
    const Eigen::Vector3d p = world_to_map * world;
    Eigen::Vector3d end = p;
    const double length = (p - origin).norm();
    if (!(length <= kMaxRayLength)) {
      ThrowInvalid("points[" + std::to_string(3 * i) + ".." + std::to_string(3 * i + 2) + "] (point " +
                   std::to_string(i) + ") = (" + FormatNumber(world.x()) + ", " + FormatNumber(world.y()) + ", " +
                   FormatNumber(world.z()) + ") lies " + FormatNumber((p - origin).stableNorm()) +
                   " m from sensor_origin; rays must be at most " +
                   FormatNumber(kMaxRayLength) + " m long");
    }
    if (insertion.max_range > 0.0 && length > insertion.max_range) end = origin + (p - origin) * (insertion.max_range / length);
    if (!InKeyRange(*tree, end)) {
      ThrowInvalid("points[" + std::to_string(3 * i) + ".." + std::to_string(3 * i + 2) + "] (point " +
                   std::to_string(i) + ") = (" + FormatNumber(world.x()) + ", " + FormatNumber(world.y()) + ", " +
                   FormatNumber(world.z()) + ")" + (end == p ? " " : " cut at max_range ") + RangeRule(map, *tree));
    }
    const double cells = ((end - origin).cwiseAbs() / tree->getResolution()).sum() + 3.0;
    if (!(cells <= kMaxRayCells)) {
      ThrowInvalid("points[" + std::to_string(3 * i) + ".." + std::to_string(3 * i + 2) + "] (point " +
                   std::to_string(i) + ") = (" + FormatNumber(world.x()) + ", " + FormatNumber(world.y()) + ", " +
                   FormatNumber(world.z()) + ")" + (end == p ? "" : " cut at max_range") + " is a ray across about " +
                   std::to_string(static_cast<long long>(cells)) + " cells of map '" + map.name + "' (resolution " +
                   FormatNumber(tree->getResolution()) + " m); a ray may cross at most " +
                   FormatNumber(kMaxRayCells) + " cells (octomap's ray buffer): use a shorter max_range or a coarser map");
    }
    cloud.push_back(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()));
  }

  // 3. Ray casting: free cells along each ray, occupied end cells (octomap prefers occupied
  //    when a cell is both), inner nodes updated and pruned as it goes.
  tree->insertPointCloud(cloud, origin_f, insertion.max_range > 0.0 ? insertion.max_range : -1.0);

  std::size_t occupied = 0;
  for (auto it = tree->begin_leafs(), end = tree->end_leafs(); it != end; ++it) {
    if (tree->isNodeOccupied(*it)) ++occupied;
  }
  if (stats != nullptr) {
    stats->octomap = map.name;
    stats->created = index < 0;
    stats->points_inserted = count;
    stats->occupied_leaves = occupied;
    stats->resolution = tree->getResolution();
  }

  Scene updated = *this;
  map.tree = std::move(tree);
  if (index >= 0) {
    updated.maps_[index] = std::move(map);
  } else {
    updated.maps_.push_back(std::move(map));
  }
  if (stats != nullptr) {
    stats->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  return updated;
}

}  // namespace chasles
