#include "chasles/multi/fleet_lattice.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <utility>

#include "chasles/collision/collision_checker.h"
#include "chasles/robot/error.h"

namespace chasles {
namespace {

constexpr double kMaxNodes = 1e7;

std::string Point(const Eigen::Vector2d& p) {
  return "(" + FormatNumber(p.x()) + ", " + FormatNumber(p.y()) + ")";
}

/// Horizontal distance from the z axis.
double Planar(const Eigen::Vector3d& p) { return std::hypot(p.x(), p.y()); }

/// Grows [reach, z_min, z_max] by one shape placed at `pose` (world frame at q = 0).
void CoverShape(const Shape& shape, const Eigen::Isometry3d& pose, Footprint* cover) {
  const Eigen::Isometry3d placed = pose * shape.pose;
  const Eigen::Vector3d c = placed.translation();
  const auto grow = [&](const Eigen::Vector3d& p, double r) {
    cover->radius = std::max(cover->radius, Planar(p) + r);
    cover->z_min = std::min(cover->z_min, p.z() - r);
    cover->z_max = std::max(cover->z_max, p.z() + r);
  };
  switch (shape.type) {
    case ShapeType::kSphere:
      grow(c, shape.radius);
      break;
    case ShapeType::kBox:
      // A convex function (distance from an axis, height) is largest at a corner.
      for (int corner = 0; corner < 8; ++corner) {
        const Eigen::Vector3d local(((corner & 1) ? 0.5 : -0.5) * shape.size.x(),
                                    ((corner & 2) ? 0.5 : -0.5) * shape.size.y(),
                                    ((corner & 4) ? 0.5 : -0.5) * shape.size.z());
        grow(placed * local, 0.0);
      }
      break;
    case ShapeType::kCapsule: {
      const Eigen::Vector3d axis = placed.linear().col(2) * (0.5 * shape.length);
      grow(c + axis, shape.radius);
      grow(c - axis, shape.radius);
      break;
    }
    case ShapeType::kCylinder: {
      // Each end circle lies in the ball of its radius about its centre: conservative in the
      // plane (exact when upright); its height span is exact: ± r·sin(tilt).
      const Eigen::Vector3d unit = placed.linear().col(2);
      const Eigen::Vector3d axis = unit * (0.5 * shape.length);
      const double rim = shape.radius * std::sqrt(std::max(0.0, 1.0 - unit.z() * unit.z()));
      for (const Eigen::Vector3d& end : {Eigen::Vector3d(c + axis), Eigen::Vector3d(c - axis)}) {
        cover->radius = std::max(cover->radius, Planar(end) + shape.radius);
        cover->z_min = std::min(cover->z_min, end.z() - rim);
        cover->z_max = std::max(cover->z_max, end.z() + rim);
      }
      break;
    }
    case ShapeType::kMesh:
      if (shape.mesh) {
        for (const Eigen::Vector3d& v : shape.mesh->vertices) grow(placed * v, 0.0);
      }
      break;
  }
}

/// A robot whose only geometry is `shape`, carried by prismatic x and y joints within
/// [lower, upper]: its configuration is where `shape`'s frame sits in the plane.
std::shared_ptr<const RobotModel> ProbeRobot(const std::string& name, const Shape& shape,
                                             const Eigen::Vector2d& lower, const Eigen::Vector2d& upper) {
  std::vector<Link> links(3);
  links[0].name = "world";
  links[1].name = "slider";
  links[1].parent_joint = 0;
  links[2].name = "probe";
  links[2].parent_joint = 1;
  links[2].collision.push_back(shape);
  std::vector<Joint> joints(2);
  for (int i = 0; i < 2; ++i) {
    joints[i].name = i == 0 ? "x" : "y";
    joints[i].type = JointType::kPrismatic;
    joints[i].parent_link = i;
    joints[i].child_link = i + 1;
    joints[i].axis = Eigen::Vector3d::Unit(i);
    joints[i].limits.lower = lower[i];
    joints[i].limits.upper = upper[i];
    joints[i].limits.velocity = 1.0;
  }
  return RobotModel::FromTree(name, std::move(links), std::move(joints));
}

void AppendBits(std::string* key, double value) {
  char bytes[sizeof(double)];
  std::memcpy(bytes, &value, sizeof(double));
  key->append(bytes, sizeof(double));
}

}  // namespace

Footprint PlanarFootprint(const RobotModel& robot) {
  if (robot.kind() != RobotKind::kPlanar || robot.num_dofs() != 3) {
    ThrowInvalid("robot '" + robot.name() + "' is " + ToString(robot.kind()) + " with " +
                 std::to_string(robot.num_dofs()) + " coordinates; a fleet footprint needs a planar robot (x, y, theta)");
  }
  // x and y translate along the world axes, θ turns about the z axis through the origin (as
  // RobotFromMobile builds them), so the body's origin is at (x, y) and it turns about it.
  using Screw = Eigen::Matrix<double, 6, 1>;
  const Screw expected[3] = {(Screw() << 0, 0, 0, 1, 0, 0).finished(), (Screw() << 0, 0, 0, 0, 1, 0).finished(),
                             (Screw() << 0, 0, 1, 0, 0, 0).finished()};
  for (int dof = 0; dof < 3; ++dof) {
    const int m = robot.moving_index(robot.dof_joint(dof));
    if (robot.has_mimic_joints() || m < 0 || !robot.space_screw_axis(m).isApprox(expected[dof], 1e-9)) {
      ThrowInvalid("robot '" + robot.name() + "': coordinate " + std::to_string(dof) + " ('" + robot.dof_names()[dof] +
                   "') is not " + (dof == 0 ? "x along the world x axis" : dof == 1 ? "y along the world y axis"
                                                                                  : "theta about the z axis through the origin") +
                   "; a fleet footprint needs the planar (x, y, theta) chain RobotFromMobile builds");
    }
  }
  std::vector<Eigen::Isometry3d> poses;
  robot.ForwardKinematics(Eigen::VectorXd::Zero(3), &poses);
  Footprint cover;
  cover.z_min = std::numeric_limits<double>::infinity();
  cover.z_max = -std::numeric_limits<double>::infinity();
  bool any = false;
  for (int l = 0; l < robot.num_links(); ++l) {
    for (const Shape& shape : robot.links()[l].collision) {
      CoverShape(shape, poses[l], &cover);
      any = true;
    }
  }
  if (!any) ThrowInvalid("robot '" + robot.name() + "' has no collision geometry, so no footprint");
  return cover;
}

Footprint CoverFootprints(const std::vector<Footprint>& footprints) {
  if (footprints.empty()) ThrowInvalid("footprints is empty");
  Footprint cover = footprints.front();
  for (const Footprint& f : footprints) {
    cover.radius = std::max(cover.radius, f.radius);
    cover.z_min = std::min(cover.z_min, f.z_min);
    cover.z_max = std::max(cover.z_max, f.z_max);
  }
  return cover;
}

std::pair<Eigen::Vector2d, Eigen::Vector2d> FleetBounds(const std::vector<std::shared_ptr<const RobotModel>>& robots) {
  if (robots.empty()) ThrowInvalid("robots is empty: fleet bounds need at least one robot");
  Eigen::Vector2d lower = Eigen::Vector2d::Constant(-std::numeric_limits<double>::infinity());
  Eigen::Vector2d upper = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
  for (std::size_t i = 0; i < robots.size(); ++i) {
    const RobotModel* robot = robots[i].get();
    if (robot == nullptr || robot->kind() != RobotKind::kPlanar || robot->num_dofs() != 3) {
      ThrowInvalid("robots[" + std::to_string(i) + "] is " + (robot == nullptr ? std::string("null") : "not a planar robot") +
                   "; fleet bounds need planar robots (x, y, theta)");
    }
    lower = lower.cwiseMax(robot->lower_limits().head<2>());
    upper = upper.cwiseMin(robot->upper_limits().head<2>());
  }
  if (!(lower.array() <= upper.array()).all()) {
    ThrowInvalid("the robots' x/y joint limits do not overlap: lower " + Point(lower) + " > upper " + Point(upper));
  }
  return {lower, upper};
}

Eigen::Vector2d LatticeGeometry::Position(GridCell cell) const {
  return origin + spacing * Eigen::Vector2d(cell % width, cell / width);
}

GridCell LatticeGeometry::Neighbour(GridCell cell, LatticeDirection direction) const {
  const int ix = cell % width, iy = cell / width;
  switch (direction) {
    case LatticeDirection::kEast: return ix + 1 < width ? cell + 1 : -1;
    case LatticeDirection::kNorth: return iy + 1 < height ? cell + width : -1;
    case LatticeDirection::kWest: return ix > 0 ? cell - 1 : -1;
    case LatticeDirection::kSouth: return iy > 0 ? cell - width : -1;
  }
  return -1;
}

GridCell LatticeGeometry::NodeAt(const Eigen::Vector2d& xy, const std::string& field) const {
  const double scale = std::max({std::abs(origin.x()), std::abs(origin.y()), spacing * std::max(width, height)});
  const double tolerance = std::max(1e-6, 1e-9 * scale);
  if (!xy.allFinite()) ThrowInvalid(field + " = " + Point(xy) + " must be finite");
  const Eigen::Vector2d index = (xy - origin) / spacing;
  const long ix = std::lround(std::clamp(index.x(), -1.0, static_cast<double>(width)));
  const long iy = std::lround(std::clamp(index.y(), -1.0, static_cast<double>(height)));
  const bool inside = ix >= 0 && ix < width && iy >= 0 && iy < height;
  const long cx = std::clamp<long>(ix, 0, width - 1), cy = std::clamp<long>(iy, 0, height - 1);
  const GridCell cell = static_cast<GridCell>(cy * width + cx);
  const Eigen::Vector2d node = Position(cell);
  const double distance = (xy - node).norm();
  if (inside && distance <= tolerance) return cell;
  ThrowInvalid(field + " = " + Point(xy) + " is not on a lattice node: the nearest node is cell " +
               std::to_string(cell) + " at " + Point(node) + ", " + FormatNumber(distance) + " m away (tolerance " +
               FormatNumber(tolerance) + " m; lattice " + std::to_string(width) + " x " + std::to_string(height) +
               " nodes from " + Point(origin) + ", spacing " + FormatNumber(spacing) + " m)");
}

void FleetLatticeRequest::Validate() const {
  if (!anchor.allFinite()) ThrowInvalid("lattice.anchor = " + Point(anchor) + " must be finite");
  if (!(spacing > 0.0) || !std::isfinite(spacing)) {
    ThrowInvalid("lattice.spacing = " + FormatNumber(spacing) + " must be > 0 and finite");
  }
  for (int i = 0; i < 2; ++i) {
    const std::string axis = i == 0 ? "x" : "y";
    if (!std::isfinite(lower[i]) || !std::isfinite(upper[i]) || !(lower[i] <= upper[i])) {
      ThrowInvalid("lattice.lower." + axis + " = " + FormatNumber(lower[i]) + " and lattice.upper." + axis + " = " +
                   FormatNumber(upper[i]) + " must be finite with lower <= upper");
    }
  }
  if (!(footprint.radius > 0.0) || !std::isfinite(footprint.radius)) {
    ThrowInvalid("lattice.footprint.radius = " + FormatNumber(footprint.radius) + " must be > 0 and finite");
  }
  if (!std::isfinite(footprint.z_min) || !std::isfinite(footprint.z_max) || !(footprint.z_min < footprint.z_max)) {
    ThrowInvalid("lattice.footprint.z_min = " + FormatNumber(footprint.z_min) + " must be < z_max = " +
                 FormatNumber(footprint.z_max) + ", both finite");
  }
  const double nodes = (std::floor((upper.x() - lower.x()) / spacing) + 2.0) *
                       (std::floor((upper.y() - lower.y()) / spacing) + 2.0);
  if (nodes > kMaxNodes) {
    ThrowResourceExhausted("lattice of about " + FormatNumber(nodes) + " nodes (bounds / spacing " +
                           FormatNumber(spacing) + " m) is more than the cap of 1e7 nodes; raise lattice.spacing");
  }
}

FleetLattice::FleetLattice(LatticeGeometry geometry, Footprint footprint, std::vector<std::uint8_t> free_edges,
                           std::vector<std::uint8_t> blocked_nodes)
    : geometry_(std::move(geometry)), footprint_(footprint), free_edges_(std::move(free_edges)) {
  const int n = geometry_.num_cells();
  if (geometry_.width <= 0 || geometry_.height <= 0 || static_cast<int>(free_edges_.size()) != n ||
      static_cast<int>(blocked_nodes.size()) != n) {
    ThrowInvalid("fleet lattice: " + std::to_string(geometry_.width) + " x " + std::to_string(geometry_.height) +
                 " nodes need that many edge masks and node flags (got " + std::to_string(free_edges_.size()) +
                 " and " + std::to_string(blocked_nodes.size()) + ")");
  }
  map_.width = geometry_.width;
  map_.height = geometry_.height;
  map_.blocked = std::move(blocked_nodes);
  // An edge is free when both ends are free nodes and both ends' masks say so.
  const std::vector<std::uint8_t> given = free_edges_;
  for (GridCell c = 0; c < n; ++c) {
    free_edges_[c] = 0;
    for (int d = 0; d < 4; ++d) {
      const GridCell other = geometry_.Neighbour(c, static_cast<LatticeDirection>(d));
      if (other < 0 || map_.blocked[c] != 0 || map_.blocked[other] != 0) continue;
      if (((given[c] >> d) & 1u) != 0 && ((given[other] >> ((d + 2) % 4)) & 1u) != 0) {
        free_edges_[c] |= static_cast<std::uint8_t>(1u << d);
      }
    }
  }
  for (GridCell c = 0; c < n; ++c) {
    for (int d = 0; d < 2; ++d) {
      const GridCell other = geometry_.Neighbour(c, static_cast<LatticeDirection>(d));
      if (other < 0 || map_.blocked[c] != 0 || map_.blocked[other] != 0) continue;
      if (((free_edges_[c] >> d) & 1u) == 0) blocked_edges_.push_back({c, static_cast<LatticeDirection>(d)});
    }
  }
}

bool FleetLattice::node_free(GridCell cell) const {
  return cell >= 0 && cell < geometry_.num_cells() && map_.blocked[cell] == 0;
}

bool FleetLattice::edge_free(GridCell cell, LatticeDirection direction) const {
  if (cell < 0 || cell >= geometry_.num_cells()) return false;
  return ((free_edges_[cell] >> static_cast<int>(direction)) & 1u) != 0;
}

GridMap FleetLattice::NodeBlockingMap() const {
  GridMap result = map_;
  const auto free_degree = [&](GridCell c) {
    int degree = 0;
    for (int d = 0; d < 4; ++d) {
      const GridCell other = geometry_.Neighbour(c, static_cast<LatticeDirection>(d));
      if (other >= 0 && result.blocked[other] == 0 && ((free_edges_[c] >> d) & 1u) != 0) ++degree;
    }
    return degree;
  };
  // One pass: once an end of an edge is blocked it stays blocked.
  for (const BlockedEdge& edge : blocked_edges_) {
    const GridCell a = edge.cell, b = geometry_.Neighbour(a, edge.direction);
    if (result.blocked[a] != 0 || result.blocked[b] != 0) continue;
    result.blocked[free_degree(a) < free_degree(b) ? a : b] = 1;
  }
  return result;
}

FleetLattice BuildFleetLattice(const Scene& scene, const FleetLatticeRequest& request, FleetLatticeStats* stats) {
  request.Validate();
  const auto started = std::chrono::steady_clock::now();
  const double s = request.spacing;
  // Nodes anchor + s·(i, j) inside the bounds; a node within 1e-9 of a bound counts as inside.
  LatticeGeometry geometry;
  geometry.spacing = s;
  Eigen::Vector2d first;
  int count[2];
  for (int i = 0; i < 2; ++i) {
    const double lo = std::ceil((request.lower[i] - request.anchor[i]) / s - 1e-9);
    const double hi = std::floor((request.upper[i] - request.anchor[i]) / s + 1e-9);
    if (hi < lo) {
      ThrowInvalid(std::string("lattice: no node of the lattice through lattice.anchor = ") + Point(request.anchor) +
                   " with spacing " + FormatNumber(s) + " m lies within [lattice.lower." + (i == 0 ? "x" : "y") +
                   ", lattice.upper." + (i == 0 ? "x" : "y") + "] = [" + FormatNumber(request.lower[i]) + ", " +
                   FormatNumber(request.upper[i]) + "]");
    }
    first[i] = request.anchor[i] + lo * s;
    count[i] = static_cast<int>(hi - lo) + 1;
  }
  geometry.origin = first;
  geometry.width = count[0];
  geometry.height = count[1];
  const int n = geometry.num_cells();

  // The scene without its allowed pairs (they name links of some robot, not of these probes).
  auto obstacles = std::make_shared<Scene>();
  for (const SceneObject& object : scene.objects()) obstacles->AddObject(object);
  for (const OccupancyMap& map : scene.occupancy_maps()) obstacles->AddOccupancyMap(map);

  const Footprint& f = request.footprint;
  const double height = f.z_max - f.z_min, zc = 0.5 * (f.z_min + f.z_max), r = f.radius;
  const Eigen::Vector2d lo = first - Eigen::Vector2d::Constant(1.0);
  const Eigen::Vector2d hi = geometry.Position(n - 1) + Eigen::Vector2d::Constant(1.0);
  const auto placed = [](double x, double y, double z) {
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.translation() = Eigen::Vector3d(x, y, z);
    return pose;
  };
  const CollisionChecker node_checker(ProbeRobot("footprint", Shape::Cylinder(r, height, placed(0, 0, zc)), lo, hi),
                                      obstacles);
  const CollisionChecker east_checker(
      ProbeRobot("east_edge", Shape::Box(Eigen::Vector3d(s, 2.0 * r, height), placed(0.5 * s, 0, zc)), lo, hi),
      obstacles);
  const CollisionChecker north_checker(
      ProbeRobot("north_edge", Shape::Box(Eigen::Vector3d(2.0 * r, s, height), placed(0, 0.5 * s, zc)), lo, hi),
      obstacles);

  FleetLatticeStats counted;
  std::vector<std::uint8_t> blocked(n, 0), edges(n, 0);
  Eigen::VectorXd q(2);
  for (GridCell c = 0; c < n; ++c) {
    q = geometry.Position(c);
    ++counted.node_checks;
    blocked[c] = node_checker.IsValid(q) ? 0 : 1;
  }
  for (GridCell c = 0; c < n; ++c) {
    if (blocked[c] != 0) continue;
    q = geometry.Position(c);
    for (const LatticeDirection d : {LatticeDirection::kEast, LatticeDirection::kNorth}) {
      const GridCell other = geometry.Neighbour(c, d);
      if (other < 0 || blocked[other] != 0) continue;
      ++counted.edge_checks;
      const bool free = (d == LatticeDirection::kEast ? east_checker : north_checker).IsValid(q);
      if (!free) continue;
      const int bit = static_cast<int>(d);
      edges[c] |= static_cast<std::uint8_t>(1u << bit);
      edges[other] |= static_cast<std::uint8_t>(1u << (bit + 2));
    }
  }
  counted.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  if (stats != nullptr) *stats = counted;
  return FleetLattice(geometry, f, std::move(edges), std::move(blocked));
}

std::string FleetLatticeKey(const std::string& scene_id, const FleetLatticeRequest& request) {
  std::string key = scene_id;
  key.push_back('\0');
  for (const double v : {request.anchor.x(), request.anchor.y(), request.spacing, request.lower.x(),
                         request.lower.y(), request.upper.x(), request.upper.y(), request.footprint.radius,
                         request.footprint.z_min, request.footprint.z_max}) {
    AppendBits(&key, v);
  }
  return key;
}

std::shared_ptr<const FleetLattice> FleetLatticeCache::GetOrBuild(const std::string& scene_id, const Scene& scene,
                                                                  const FleetLatticeRequest& request, bool* was_cached) {
  const std::string key = FleetLatticeKey(scene_id, request);
  if (was_cached != nullptr) *was_cached = true;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto it = index_.find(key);
    if (it != index_.end()) {
      entries_.splice(entries_.begin(), entries_, it->second);
      return it->second->second;
    }
  }
  if (was_cached != nullptr) *was_cached = false;
  auto built = std::make_shared<const FleetLattice>(BuildFleetLattice(scene, request));
  std::lock_guard<std::mutex> lock(mutex_);
  const auto it = index_.find(key);
  if (it != index_.end()) return it->second->second;  // another thread built it meanwhile
  if (capacity_ == 0) return built;
  entries_.emplace_front(key, built);
  index_[key] = entries_.begin();
  while (entries_.size() > capacity_) {
    index_.erase(entries_.back().first);
    entries_.pop_back();
  }
  return built;
}

std::size_t FleetLatticeCache::size() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return entries_.size();
}

}  // namespace chasles
