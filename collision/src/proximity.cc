#include "chasles/collision/proximity.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include <fcl/fcl.h>
#include <fcl/geometry/octree/octree.h>
#include <octomap/OcTree.h>

#include "broad_phase.h"
#include "chasles/robot/error.h"
#include "fcl_geometry.h"

// Design notes
// ------------
// * Every query calls the geometry+transform overload of fcl::distance, which builds its
//   traversal on the stack over shared, immutable geometry: nothing is mutated, so one instance
//   serves all threads (as CollisionChecker's FCL path).
// * Each pair is pruned by bounding spheres against the best distance so far (starting at
//   max_distance), and the DistanceResult starts at that bound, so an octree traversal skips
//   every voxel that cannot be nearer.
// * Order of the nearest points: FCL puts them in the order of the objects it actually
//   traverses. An occupancy map is passed first (FCL's octree–shape traversal reports the voxel
//   point first whichever order it is called in); FCL swaps a (shape, mesh) call into
//   (mesh, shape) without swapping the points back. Pair() undoes both, and for mesh pairs
//   also FCL 0.7's mixed frames (see there).
// * Overlap: FCL reports a negative or implementation-defined distance without meaningful
//   points; the query reports 0 and takes a contact point from fcl::collide.

namespace chasles {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

using Geom = FclGeom;

struct LinkShape {
  Geom g;
  Eigen::Isometry3d local;  // shape pose in the link frame
};

struct Obstacle {
  std::string name;
  int index = -1;
  Geom g;
  fcl::Transform3d tf;
  Eigen::Vector3d center;  // bounding centre, world
  double radius = 0.0;
  bool octree = false;
  std::vector<char> allowed_links;  // per robot link, 1 = the scene allows it to touch; empty = none
};

}  // namespace

struct ObstacleProximity::Impl {
  std::vector<std::vector<LinkShape>> link_shapes;  // parallel to links_
  std::vector<Obstacle> obstacles;
  // With more than kBroadPhaseObstacles obstacles, their bounding spheres in a BVH
  // (broad_phase.h): a link shape then visits only the obstacles whose bound's box overlaps its
  // own bound grown by max_distance — the others fail the bounding-sphere test anyway, so the
  // answers are the same.
  static constexpr std::size_t kBroadPhaseObstacles = 32;
  bool broad_phase = false;
  detail::SphereBvh obstacle_bvh;

  /// Distance from one placed link shape to one obstacle, if below `bound`: fills d and the
  /// points (link, obstacle) and returns true.
  bool Pair(const LinkShape& s, const fcl::Transform3d& tf, const Obstacle& o, double bound, double* d,
            Eigen::Vector3d* p_link, Eigen::Vector3d* p_obstacle) const {
    const fcl::CollisionGeometryd* a = o.octree ? o.g.geom.get() : s.g.geom.get();
    const fcl::CollisionGeometryd* b = o.octree ? s.g.geom.get() : o.g.geom.get();
    const fcl::Transform3d& ta = o.octree ? o.tf : tf;
    const fcl::Transform3d& tb = o.octree ? tf : o.tf;
    // Points come back in the order FCL traversed the pair (see the design notes).
    const bool swapped = a->getObjectType() == fcl::OT_GEOM && b->getObjectType() == fcl::OT_BVH;
    const bool link_first = o.octree ? false : !swapped;

    fcl::DistanceRequestd request(/*enable_nearest_points=*/true);
    fcl::DistanceResultd result(bound);
    fcl::distance(a, ta, b, tb, request, result);
    if (result.o1 == nullptr || !(result.min_distance < bound)) return false;
    if (result.min_distance > 0.0) {
      *d = result.min_distance;
      *p_link = link_first ? result.nearest_points[0] : result.nearest_points[1];
      *p_obstacle = link_first ? result.nearest_points[1] : result.nearest_points[0];
      if (a->getObjectType() == fcl::OT_BVH || b->getObjectType() == fcl::OT_BVH) {
        // Mesh pairs: some of FCL 0.7's shape–triangle routines return each point in its own
        // object's frame, others in the world frame. Keep the reading whose points are `d` apart.
        const Eigen::Vector3d local_link = tf * *p_link, local_obstacle = o.tf * *p_obstacle;
        const double world_error = std::abs((*p_link - *p_obstacle).norm() - *d);
        const double local_error = std::abs((local_link - local_obstacle).norm() - *d);
        if (local_error < world_error) {
          *p_link = local_link;
          *p_obstacle = local_obstacle;
        }
      }
      return true;
    }
    // Contact or overlap: distance 0 at a contact point.
    *d = 0.0;
    fcl::CollisionRequestd creq(1, /*enable_contact=*/true);
    fcl::CollisionResultd cres;
    fcl::collide(a, ta, b, tb, creq, cres);
    if (cres.numContacts() > 0) {
      *p_link = cres.getContact(0).pos;
      *p_obstacle = cres.getContact(0).pos;
    } else {  // touching within FCL's tolerances: no contact reported
      *p_link = tf * s.g.center;
      *p_obstacle = o.center;
    }
    return true;
  }
};

ObstacleProximity::ObstacleProximity(std::shared_ptr<const CollisionChecker> checker)
    : ObstacleProximity(checker ? checker->robot_ptr() : nullptr,
                        checker ? std::shared_ptr<const Scene>(checker, &checker->scene()) : nullptr) {
  if (!checker) ThrowInvalid("obstacle proximity: collision checker is null");
  checker_ = std::move(checker);
}

ObstacleProximity::ObstacleProximity(std::shared_ptr<const RobotModel> robot, std::shared_ptr<const Scene> scene,
                                     bool broad_phase)
    : robot_(std::move(robot)), scene_(std::move(scene)), impl_(std::make_unique<Impl>()) {
  if (!robot_) ThrowInvalid("obstacle proximity: robot is null");
  if (!scene_) scene_ = std::make_shared<Scene>();
  Impl& m = *impl_;
  for (int l = 0; l < robot_->num_links(); ++l) {
    const auto& shapes = robot_->links()[l].collision;
    if (shapes.empty()) continue;
    links_.push_back(l);
    std::vector<LinkShape> placed;
    for (const Shape& s : shapes) placed.push_back({MakeGeom(s), s.pose});
    m.link_shapes.push_back(std::move(placed));
  }
  int index = 0;
  for (const SceneObject& o : scene_->objects()) {
    Obstacle ob;
    ob.name = o.name;
    ob.index = index++;
    ob.g = MakeGeom(o.shape);
    ob.tf = o.shape.pose;
    ob.center = o.shape.pose * ob.g.center;
    ob.radius = ob.g.radius;
    m.obstacles.push_back(std::move(ob));
  }
  for (const OccupancyMap& map : scene_->occupancy_maps()) {
    const int map_index = index++;
    // Bound the occupied leaves only (the tree's root box is far larger).
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(kInf), hi = Eigen::Vector3d::Constant(-kInf);
    for (auto it = map.tree->begin_leafs(), end = map.tree->end_leafs(); it != end; ++it) {
      if (!map.tree->isNodeOccupied(*it)) continue;
      const double h = 0.5 * it.getSize();
      const Eigen::Vector3d c(it.getX(), it.getY(), it.getZ());
      lo = lo.cwiseMin(c - Eigen::Vector3d::Constant(h));
      hi = hi.cwiseMax(c + Eigen::Vector3d::Constant(h));
    }
    if (!(lo.array() <= hi.array()).all()) continue;  // nothing occupied: no obstacle
    Obstacle ob;
    ob.name = map.name;
    ob.index = map_index;
    ob.octree = true;
    ob.g.geom = std::make_shared<fcl::OcTreed>(map.tree);
    ob.tf = map.pose;
    ob.center = map.pose * (0.5 * (lo + hi));
    ob.radius = 0.5 * (hi - lo).norm();
    m.obstacles.push_back(std::move(ob));
  }
  // The scene's allowed link–obstacle pairs (names the robot lacks are the checker's to reject).
  for (const AllowedCollision& pair : scene_->allowed_collisions()) {
    const int link = robot_->FindLink(pair.link);
    if (link < 0) continue;
    for (Obstacle& ob : m.obstacles) {
      if (ob.name != pair.other) continue;
      ob.allowed_links.resize(robot_->num_links(), 0);
      ob.allowed_links[link] = 1;
    }
  }
  if (broad_phase && m.obstacles.size() > Impl::kBroadPhaseObstacles) {
    std::vector<double> x, y, z, r;
    for (const Obstacle& o : m.obstacles) {
      x.push_back(o.center.x());
      y.push_back(o.center.y());
      z.push_back(o.center.z());
      r.push_back(o.radius);
    }
    m.obstacle_bvh = detail::SphereBvh(x.data(), y.data(), z.data(), r.data(), m.obstacles.size());
    m.broad_phase = true;
  }
}

ObstacleProximity::~ObstacleProximity() = default;

void ObstacleProximity::Query(const Eigen::VectorXd& q, double max_distance, std::vector<LinkProximity>* out) const {
  if (q.size() != robot_->num_dofs()) {
    ThrowInvalid("proximity query: q has " + std::to_string(q.size()) + " values, robot '" + robot_->name() +
                 "' has " + std::to_string(robot_->num_dofs()) + " joints");
  }
  if (!(max_distance > 0.0)) {
    ThrowInvalid("proximity query: max_distance = " + FormatNumber(max_distance) + " must be > 0");
  }
  std::vector<Eigen::Isometry3d> poses;
  robot_->ForwardKinematics(q, &poses);
  const Impl& m = *impl_;
  thread_local std::vector<std::uint32_t> near_list;  // reused: queries run in the field's loop
  out->assign(links_.size(), LinkProximity{});
  for (std::size_t i = 0; i < links_.size(); ++i) {
    LinkProximity& best = (*out)[i];
    best.link = links_[i];
    double bound = max_distance;
    for (const LinkShape& s : m.link_shapes[i]) {
      const Eigen::Isometry3d pose = poses[links_[i]] * s.local;
      const fcl::Transform3d& tf = pose;
      const Eigen::Vector3d c = pose * s.g.center;
      std::size_t count = m.obstacles.size();
      const std::uint32_t* near = nullptr;  // nullptr: every obstacle, in order
      if (m.broad_phase) {
        detail::Box3 box = detail::Box3::None();
        box.Include(c.data(), s.g.radius + max_distance);
        m.obstacle_bvh.Overlapping(box, &near_list);
        count = near_list.size();
        near = near_list.data();
      }
      for (std::size_t j = 0; j < count; ++j) {
        const Obstacle& o = m.obstacles[near != nullptr ? near[j] : j];
        if (!o.allowed_links.empty() && o.allowed_links[links_[i]]) continue;
        if ((c - o.center).norm() - s.g.radius - o.radius >= bound) continue;
        double d;
        Eigen::Vector3d p_link, p_obstacle;
        if (!m.Pair(s, tf, o, bound, &d, &p_link, &p_obstacle)) continue;
        bound = d;
        best.obstacle = o.index;
        best.obstacle_name = o.name;
        best.distance = d;
        best.link_point = p_link;
        best.obstacle_point = p_obstacle;
        if (d <= 0.0) break;
      }
      if (bound <= 0.0) break;
    }
  }
}

std::vector<LinkProximity> ObstacleProximity::Query(const Eigen::VectorXd& q, double max_distance) const {
  std::vector<LinkProximity> out;
  Query(q, max_distance, &out);
  return out;
}

struct LinkGroupDistance::Impl {
  struct Placed {
    int link = -1;
    LinkShape shape;
  };
  std::vector<std::vector<Placed>> groups;  // shapes per group
};

LinkGroupDistance::LinkGroupDistance(std::shared_ptr<const RobotModel> robot, std::vector<std::vector<int>> groups)
    : robot_(std::move(robot)), impl_(std::make_unique<Impl>()) {
  if (!robot_) ThrowInvalid("link group distance: robot is null");
  for (std::size_t g = 0; g < groups.size(); ++g) {
    std::vector<Impl::Placed> shapes;
    for (std::size_t i = 0; i < groups[g].size(); ++i) {
      const int link = groups[g][i];
      if (link < 0 || link >= robot_->num_links()) {
        ThrowInvalid("link group distance: groups[" + std::to_string(g) + "][" + std::to_string(i) + "] = " +
                     std::to_string(link) + " is not a link of robot '" + robot_->name() + "' (" +
                     std::to_string(robot_->num_links()) + " links)");
      }
      for (const Shape& s : robot_->links()[link].collision) shapes.push_back({link, {MakeGeom(s), s.pose}});
    }
    impl_->groups.push_back(std::move(shapes));
  }
}

LinkGroupDistance::~LinkGroupDistance() = default;

double LinkGroupDistance::Min(const Eigen::VectorXd& q, double max_distance, int* group_a, int* group_b) const {
  if (q.size() != robot_->num_dofs()) {
    ThrowInvalid("link group distance: q has " + std::to_string(q.size()) + " values, robot '" + robot_->name() +
                 "' has " + std::to_string(robot_->num_dofs()) + " joints");
  }
  if (!(max_distance > 0.0)) {
    ThrowInvalid("link group distance: max_distance = " + FormatNumber(max_distance) + " must be > 0");
  }
  if (group_a != nullptr) *group_a = -1;
  if (group_b != nullptr) *group_b = -1;
  std::vector<Eigen::Isometry3d> poses;
  robot_->ForwardKinematics(q, &poses);
  struct World {
    fcl::Transform3d tf;
    Eigen::Vector3d center;
    double radius;
    const fcl::CollisionGeometryd* geom;
  };
  std::vector<std::vector<World>> world(impl_->groups.size());
  for (std::size_t g = 0; g < impl_->groups.size(); ++g) {
    for (const Impl::Placed& p : impl_->groups[g]) {
      const Eigen::Isometry3d pose = poses[p.link] * p.shape.local;
      world[g].push_back({pose, pose * p.shape.g.center, p.shape.g.radius, p.shape.g.geom.get()});
    }
  }
  // Each group's bounding sphere (about the mean of its shapes' centres) prunes whole pairs.
  std::vector<Eigen::Vector3d> group_center(world.size(), Eigen::Vector3d::Zero());
  std::vector<double> group_radius(world.size(), -1.0);
  for (std::size_t g = 0; g < world.size(); ++g) {
    if (world[g].empty()) continue;
    for (const World& w : world[g]) group_center[g] += w.center;
    group_center[g] /= static_cast<double>(world[g].size());
    for (const World& w : world[g]) group_radius[g] = std::max(group_radius[g], (w.center - group_center[g]).norm() + w.radius);
  }
  double best = max_distance;
  for (std::size_t g = 0; g < world.size(); ++g) {
    for (std::size_t h = g + 1; h < world.size(); ++h) {
      if (world[g].empty() || world[h].empty()) continue;
      if ((group_center[g] - group_center[h]).norm() - group_radius[g] - group_radius[h] >= best) continue;
      for (const World& a : world[g]) {
        for (const World& b : world[h]) {
          if ((a.center - b.center).norm() - a.radius - b.radius >= best) continue;
          fcl::DistanceRequestd request;
          fcl::DistanceResultd result(best);
          fcl::distance(a.geom, a.tf, b.geom, b.tf, request, result);
          if (result.o1 == nullptr || !(result.min_distance < best)) continue;
          best = std::max(0.0, result.min_distance);
          if (group_a != nullptr) *group_a = static_cast<int>(g);
          if (group_b != nullptr) *group_b = static_cast<int>(h);
          if (best <= 0.0) return 0.0;
        }
      }
    }
  }
  return best;
}

}  // namespace chasles
