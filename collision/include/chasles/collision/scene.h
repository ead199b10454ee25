#pragma once
/// \file
/// Scene: the static environment — primitives, triangle meshes and OctoMap occupancy maps,
/// all posed in the world (robot base) frame. SI units.

#include <memory>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "chasles/robot/geometry.h"

namespace octomap {
class OcTree;
}

namespace chasles {

/// One named obstacle (a primitive or a mesh) in the world frame. `shape.pose` is its pose.
struct SceneObject {
  std::string name;
  Shape shape;
};

/// An OctoMap occupancy map placed at `pose` in the world; occupied leaves are obstacles.
struct OccupancyMap {
  std::string name;
  std::shared_ptr<const octomap::OcTree> tree;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
};

/// A value type; cheap to copy (shared immutable maps and meshes).
class Scene {
 public:
  /// Adds a primitive or mesh. \throws Error(kInvalidArgument) naming `field` when a dimension
  /// is not finite and > 0 or the pose is not finite.
  void AddObject(SceneObject object, const std::string& field = "scene.object");
  /// Parses `.bt` (binary) or `.ot` (full) OctoMap bytes, detected by their header.
  /// \throws Error(kInvalidArgument) naming `field` when the bytes are not an OctoMap OcTree.
  void AddOctoMap(const std::string& name, const std::string& bytes, const Eigen::Isometry3d& pose,
                  const std::string& field = "scene.octomaps");
  void AddOccupancyMap(OccupancyMap map);

  const std::vector<SceneObject>& objects() const { return objects_; }
  const std::vector<OccupancyMap>& occupancy_maps() const { return maps_; }
  bool empty() const { return objects_.empty() && maps_.empty(); }

 private:
  std::vector<SceneObject> objects_;
  std::vector<OccupancyMap> maps_;
};

}  // namespace chasles
