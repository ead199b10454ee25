#pragma once
/// \file
/// Scene: the static environment — primitives, triangle meshes and OctoMap occupancy maps,
/// all posed in the world (robot base) frame. SI units.

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "chasles/robot/geometry.h"
#include "chasles/robot/input_limits.h"

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

/// A pair that may touch without it counting as a collision (MoveIt's allowed collision matrix).
/// `link` names a robot link; `other` names another robot link, or a scene object or occupancy
/// map of the scene (every object and map of that name). Names are resolved against a robot by
/// CollisionChecker; a name that is both a link and an object allows both contacts.
struct AllowedCollision {
  std::string link;
  std::string other;
};

/// A point cloud to insert into one of a scene's OctoMaps (Scene::InsertPointCloud).
struct PointCloudInsertion {
  /// The map to update; empty = the scene's only map, or a new map "points" when it has none.
  std::string octomap;
  /// Points in the world frame [m], flattened: x0, y0, z0, x1, … (a multiple of 3, finite).
  std::vector<double> points;
  /// Where the rays start, world frame [m]; finite.
  Eigen::Vector3d sensor_origin = Eigen::Vector3d::Zero();
  /// [m] rays are cut at this length (their end cells then stay unmarked); 0 = unlimited; >= 0.
  /// Points beyond it are still refused when they lie more than 1e9 m from the sensor.
  double max_range = 0.0;
  /// [m] voxel size of a new map; 0 = 0.05; otherwise within [0.001, 10]. Ignored by existing maps.
  double resolution = 0.0;
};

/// What Scene::InsertPointCloud did.
struct PointCloudInsertionStats {
  std::string octomap;              ///< the map that was updated (or created)
  bool created = false;             ///< true when the map was created by this insertion
  std::size_t points_inserted = 0;  ///< rays cast (one per point)
  std::size_t occupied_leaves = 0;  ///< occupied leaves of the updated map (pruned leaves count once)
  double resolution = 0.0;          ///< [m] of the updated map
  double seconds = 0.0;             ///< [s] wall time of the insertion (copy, ray casting, counting)
};

/// A value type; cheap to copy (shared immutable maps and meshes).
/// The bytes of an OctoMap file holding the node data `data` of an octomap_msgs/Octomap message
/// (`binary`: octomap's writeBinaryData, a .bt file; else writeData, a .ot file), with the header
/// octomap's readers expect: id, resolution and the node count, counted here by walking the data
/// (depth <= 16, every byte present) — the file Scene::AddOctoMap reads.
/// \throws Error(kInvalidArgument) naming `field`: an id other than "OcTree", a resolution outside
///         [1e-4, 1e3] m, data that is empty, truncated, too deep or with bytes after the tree.
std::string OctoMapFileFromMessage(bool binary, const std::string& id, double resolution, const std::string& data,
                                   const std::string& field);

class Scene {
 public:
  /// Adds a primitive or mesh. \throws Error(kInvalidArgument) naming `field` when a dimension
  /// is not finite and > 0 or the pose is not finite.
  void AddObject(SceneObject object, const std::string& field = "scene.object");
  /// Parses `.bt` (binary) or `.ot` (full) OctoMap bytes, detected by their header. The node
  /// stream is walked and counted before octomap reads it.
  /// \throws Error(kInvalidArgument) naming `field` when the bytes are not an OctoMap OcTree
  ///         (bad header, truncated or corrupt node data, a node count that differs from the header).
  /// \throws Error(kResourceExhausted) when the bytes are more than `limits.max_document_bytes`
  ///         or the tree holds more than `limits.max_octomap_nodes` nodes.
  void AddOctoMap(const std::string& name, const std::string& bytes, const Eigen::Isometry3d& pose,
                  const std::string& field = "scene.octomaps", const InputLimits& limits = {});
  void AddOccupancyMap(OccupancyMap map);

  /// Lets robot link `link` touch `other` (a robot link, or an object or occupancy map of this
  /// scene): CollisionChecker then ignores that pair in every check and in Clearance. The names
  /// are checked against the robot (and this scene's objects) when a CollisionChecker is built,
  /// since a scene does not know its robot; here only empty names are rejected.
  /// \throws Error(kInvalidArgument) naming `field` + ".link1" / ".link2" when a name is empty;
  ///         an empty `field` means `scene.allowed_collisions[i]`, i the pair's index.
  void AllowCollision(const std::string& link, const std::string& other, const std::string& field = "");

  /// Returns a copy of this scene whose map `insertion.octomap` holds the point cloud, inserted
  /// with OctoMap's ray casting (OcTree::insertPointCloud): the cells along each ray from the
  /// sensor become freer, the end cells more occupied. Points and origin are moved into the
  /// map's frame (its pose inverse). The map's tree is copied; this scene, its trees and every
  /// scene sharing them stay unchanged. Fills `stats` when given.
  /// \throws Error(kInvalidArgument) naming the field, index, value and rule when a value is
  ///         malformed or a point lies outside the map's key range, or when `octomap` is empty
  ///         and the scene has several maps; Error(kNotFound) listing the scene's maps when
  ///         `octomap` names none of them; Error(kResourceExhausted) when the cloud holds more
  ///         than `limits.max_cloud_points` points (checked first).
  Scene InsertPointCloud(const PointCloudInsertion& insertion, PointCloudInsertionStats* stats = nullptr,
                         const InputLimits& limits = {}) const;

  const std::vector<SceneObject>& objects() const { return objects_; }
  const std::vector<OccupancyMap>& occupancy_maps() const { return maps_; }
  /// The allowed pairs, in the order they were added.
  const std::vector<AllowedCollision>& allowed_collisions() const { return allowed_; }
  /// True when the scene holds no object and no map (allowed pairs are not counted).
  bool empty() const { return objects_.empty() && maps_.empty(); }

 private:
  std::vector<SceneObject> objects_;
  std::vector<OccupancyMap> maps_;
  std::vector<AllowedCollision> allowed_;
};

}  // namespace chasles
