#pragma once
/// \file
/// ObstacleProximity: for each robot link, the nearest scene obstacle and the pair of nearest
/// points (what a potential field's repulsion needs). Const and thread-safe: one instance serves
/// all threads.

#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "chasles/collision/collision_checker.h"
#include "chasles/collision/scene.h"
#include "chasles/robot/robot_model.h"

namespace chasles {

/// The nearest obstacle of one robot link.
struct LinkProximity {
  int link = -1;  ///< index into RobotModel::links()
  /// Index of the obstacle: scene objects first (Scene::objects() order), then occupancy maps
  /// (Scene::occupancy_maps() order); -1 when no obstacle is within the query's max_distance.
  int obstacle = -1;
  std::string obstacle_name;  ///< the scene object or occupancy map name; empty when none
  /// Distance between the link's collision shapes and the obstacle [m]; 0 on contact or
  /// overlap (no penetration depth), +inf when none.
  double distance = std::numeric_limits<double>::infinity();
  /// Nearest point on the link's shapes and on the obstacle, world frame [m]. On contact both
  /// are a contact point (or, if FCL reports none, the link shape's and the obstacle's bounding
  /// centres). Undefined (zero) when none.
  Eigen::Vector3d link_point = Eigen::Vector3d::Zero();
  Eigen::Vector3d obstacle_point = Eigen::Vector3d::Zero();
  bool found() const { return obstacle >= 0; }
};

/// Per-link nearest-obstacle queries by FCL distance with nearest points. The robot's and the
/// scene's FCL geometry is built once (occupancy maps as fcl::OcTree, whose occupied leaves are
/// the obstacles). Distances are to the unpadded shapes (CollisionOptions::padding is not
/// applied) and ignore self-distance. A link the scene allows to touch an obstacle
/// (Scene::allowed_collisions) does not see that obstacle.
class ObstacleProximity {
 public:
  /// With more than 32 obstacles and broad_phase (the default), their bounding spheres are
  /// indexed in a bounding-volume hierarchy so a query visits only the obstacles within reach of
  /// each link shape; the answers are the same either way (false: tests, benchmarks).
  /// \throws Error(kInvalidArgument) when robot is null. A null scene is an empty one.
  ObstacleProximity(std::shared_ptr<const RobotModel> robot, std::shared_ptr<const Scene> scene,
                    bool broad_phase = true);
  /// The checker's robot and scene (the checker is kept alive by this object).
  /// \throws Error(kInvalidArgument) when checker is null.
  explicit ObstacleProximity(std::shared_ptr<const CollisionChecker> checker);
  ~ObstacleProximity();
  ObstacleProximity(const ObstacleProximity&) = delete;
  ObstacleProximity& operator=(const ObstacleProximity&) = delete;

  const RobotModel& robot() const { return *robot_; }

  /// Indices of the links that carry collision geometry, in link order: the links Query reports.
  const std::vector<int>& links() const { return links_; }

  /// For configuration q, one entry per link of links() (same order): its nearest obstacle at a
  /// distance < max_distance [m], or an entry with obstacle = -1 (none) beyond it.
  /// max_distance may be +inf. Thread-safe; allocates only `out`'s storage and FK poses (the
  /// broad phase's list of nearby obstacles is reused per thread).
  /// \throws Error(kInvalidArgument) when q.size() != num_dofs() or max_distance is nan or <= 0.
  void Query(const Eigen::VectorXd& q, double max_distance, std::vector<LinkProximity>* out) const;
  std::vector<LinkProximity> Query(const Eigen::VectorXd& q,
                                   double max_distance = std::numeric_limits<double>::infinity()) const;

 private:
  struct Impl;
  std::shared_ptr<const CollisionChecker> checker_;  // may be null
  std::shared_ptr<const RobotModel> robot_;
  std::shared_ptr<const Scene> scene_;
  std::vector<int> links_;
  std::unique_ptr<Impl> impl_;
};

/// Distances between groups of links of one robot — the robots of a team composite
/// (ComposeRobots): the smallest distance between the collision shapes of two different groups,
/// by FCL distance on the unpadded shapes. Shape pairs whose bounding spheres are farther apart
/// than the best distance so far are skipped. Const and thread-safe.
class LinkGroupDistance {
 public:
  /// `groups`: disjoint lists of link indices (links without collision geometry are ignored).
  /// \throws Error(kInvalidArgument) for a null robot or a link index out of range.
  LinkGroupDistance(std::shared_ptr<const RobotModel> robot, std::vector<std::vector<int>> groups);
  ~LinkGroupDistance();
  LinkGroupDistance(const LinkGroupDistance&) = delete;
  LinkGroupDistance& operator=(const LinkGroupDistance&) = delete;

  /// The smallest distance [m] between shapes of two different groups at q: 0 on contact or
  /// overlap, `max_distance` when no pair is nearer (also with fewer than two groups).
  /// *group_a < *group_b (optional) receive the nearest pair of groups, -1 when none is nearer.
  /// \throws Error(kInvalidArgument) when q.size() != num_dofs() or max_distance is not > 0.
  double Min(const Eigen::VectorXd& q, double max_distance, int* group_a = nullptr, int* group_b = nullptr) const;

 private:
  struct Impl;
  std::shared_ptr<const RobotModel> robot_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace chasles
