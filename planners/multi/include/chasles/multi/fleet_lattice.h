#pragma once
/// \file
/// The lattice a fleet of planar mobile bases plans on: nodes spaced s apart on a 4-connected
/// grid, a node free when a robot's footprint disc placed there misses the scene, an edge free
/// when the disc swept along it does. A grid MAPF solver plans on the nodes (GridMap); the
/// fleet schedule (fleet.h) turns its plan into timed trajectories. SI units.

#include <cstddef>
#include <cstdint>
#include <list>
#include <memory>
#include <mutex>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "chasles/collision/scene.h"
#include "chasles/multi/grid_map.h"
#include "chasles/robot/robot_model.h"

namespace chasles {

/// The vertical cylinder about a planar body's origin that holds its collision geometry at
/// every heading: a disc of `radius` in the plane, spanning [z_min, z_max] in height.
struct Footprint {
  double radius = 0.0;  ///< [m] > 0
  double z_min = 0.0;   ///< [m] lowest point of the body (world z; planar bodies move at z = 0)
  double z_max = 0.0;   ///< [m] highest point, > z_min
};

/// The footprint of a planar robot (RobotKind::kPlanar, coordinates x, y, θ as RobotFromMobile
/// builds them): every link's shapes placed at q = 0 and measured from the z axis through the
/// origin, conservatively: spheres and capsules exactly (centre or segment ends plus radius),
/// boxes and meshes exactly (their corners or vertices), cylinders by their end circles bounded
/// as balls in the plane (centre distance + radius; exact for an upright cylinder).
/// \throws Error(kInvalidArgument) when the robot is not kPlanar with 3 coordinates, or has no
///         collision geometry.
Footprint PlanarFootprint(const RobotModel& robot);

/// The footprint that covers all of them: the largest radius, the union of the height spans.
/// \throws Error(kInvalidArgument) for an empty list.
Footprint CoverFootprints(const std::vector<Footprint>& footprints);

/// Where every robot's origin may be: the intersection of the robots' x and y joint limits, as
/// (lower, upper) for FleetLatticeRequest.
/// \throws Error(kInvalidArgument) for an empty list, a null or non-planar robot (naming
///         robots[i]), or an empty intersection.
std::pair<Eigen::Vector2d, Eigen::Vector2d> FleetBounds(const std::vector<std::shared_ptr<const RobotModel>>& robots);

/// The four lattice directions (east = +x, north = +y).
enum class LatticeDirection : std::uint8_t { kEast = 0, kNorth = 1, kWest = 2, kSouth = 3 };

/// Where the nodes are: cell = iy·width + ix sits at origin + spacing·(ix, iy).
struct LatticeGeometry {
  Eigen::Vector2d origin = Eigen::Vector2d::Zero();  ///< node of cell 0 (lower-left) [m]
  double spacing = 0.0;                              ///< [m]
  int width = 0, height = 0;

  int num_cells() const { return width * height; }
  /// The node of `cell` [m]. Precondition: 0 <= cell < num_cells().
  Eigen::Vector2d Position(GridCell cell) const;
  /// The neighbour of `cell` in `direction`, or -1 off the lattice.
  GridCell Neighbour(GridCell cell, LatticeDirection direction) const;
  /// The cell whose node is within the tolerance max(1e-6 m, 1e-9·scale) of `xy` (scale: the
  /// largest absolute node coordinate or lattice extent).
  /// \throws Error(kInvalidArgument) naming `field`, the point, the nearest node (cell and
  ///         position, or that the point lies off the lattice) and the distance, e.g.
  ///         `robots[3].start = (1.2, 0.4) is not on a lattice node: the nearest node is cell 1
  ///         at (1, 0), 0.447… m away (tolerance 1e-06 m; lattice 4 x 3 nodes from (0, 0), …)`.
  GridCell NodeAt(const Eigen::Vector2d& xy, const std::string& field) const;
};

struct FleetLatticeRequest {
  Eigen::Vector2d anchor = Eigen::Vector2d::Zero();  ///< any node of the lattice [m]
  double spacing = 0.0;                              ///< s [m] > 0 (see FleetResolution)
  /// Nodes are the points anchor + spacing·(i, j), i, j integers, inside [lower, upper]
  /// (the robots' x/y joint limits: a node is a place a robot's origin may be).
  Eigen::Vector2d lower = Eigen::Vector2d::Zero(), upper = Eigen::Vector2d::Zero();
  /// The disc checked at nodes and swept along edges (CoverFootprints of the fleet; add any
  /// clearance wanted from obstacles to its radius).
  Footprint footprint;
  /// \throws Error(kInvalidArgument) naming the field; Error(kResourceExhausted) beyond 10^7 nodes.
  void Validate() const;
};

/// An edge between two free nodes along which the swept disc hits the scene.
struct BlockedEdge {
  GridCell cell = 0;                                   ///< its west or south node
  LatticeDirection direction = LatticeDirection::kEast;  ///< kEast or kNorth
};

/// The lattice of one scene and footprint. Immutable, so thread-safe to read.
///
/// A node is free iff the footprint cylinder (radius R, height span [z_min, z_max]) at the node
/// is collision-free against the scene (objects, meshes and OctoMaps; the scene's allowed pairs,
/// which name robot links, are ignored — conservative). An edge is free iff both nodes are free
/// and the cylinder swept along it — the box of length s, width 2R over the same height between
/// the two end cylinders, which with them is exactly the swept volume — is collision-free.
///
/// The MAPF solver only understands node blocking. map() blocks the nodes that are not free and
/// no more; blocked_edges() lists every edge between two free nodes that is blocked (a thin
/// obstacle in the gap between them). The caller chooses: refuse such a scene, plan on
/// NodeBlockingMap() (which blocks nodes until no such edge is left), or plan on map() and let
/// ScheduleFleet (given this lattice) refuse a plan that moves along a blocked edge.
class FleetLattice {
 public:
  /// From per-cell flags (BuildFleetLattice's result, or a hand-made lattice): `free_edges[c]`
  /// bit d set when the edge in LatticeDirection d is free; an edge counts as free only when
  /// both ends say so and both nodes are free. \throws Error(kInvalidArgument) on sizes that
  /// are not width·height.
  FleetLattice(LatticeGeometry geometry, Footprint footprint, std::vector<std::uint8_t> free_edges,
               std::vector<std::uint8_t> blocked_nodes);

  const LatticeGeometry& geometry() const { return geometry_; }
  const Footprint& footprint() const { return footprint_; }
  const GridMap& map() const { return map_; }
  bool node_free(GridCell cell) const;
  /// False off the lattice, when either end is blocked, or when the swept disc collides.
  bool edge_free(GridCell cell, LatticeDirection direction) const;
  const std::vector<BlockedEdge>& blocked_edges() const { return blocked_edges_; }
  /// map() with, for every blocked edge between free nodes, one end blocked too: the end with
  /// fewer free edges left (ties: the higher cell), until no such edge remains. Every move
  /// between free neighbours of the result is along a free edge; it may cut routes map() has.
  GridMap NodeBlockingMap() const;

 private:
  LatticeGeometry geometry_;
  Footprint footprint_;
  std::vector<std::uint8_t> free_edges_;  ///< per cell: bit d set when the edge in direction d is free
  GridMap map_;
  std::vector<BlockedEdge> blocked_edges_;
};

/// Statistics of one build.
struct FleetLatticeStats {
  std::size_t node_checks = 0;  ///< footprint checks (one per node)
  std::size_t edge_checks = 0;  ///< swept-box checks (edges between free nodes)
  double seconds = 0.0;         ///< wall time, checkers included
};

/// Builds the lattice. The checks run through CollisionChecker's FCL path (the footprint and the
/// swept boxes are robots of their own) with its broad phase: a node or edge visits only the
/// scene objects whose bounding boxes overlap its own.
/// \throws what FleetLatticeRequest::Validate throws.
FleetLattice BuildFleetLattice(const Scene& scene, const FleetLatticeRequest& request,
                               FleetLatticeStats* stats = nullptr);

/// The cache key of a lattice: `scene_id` (the scene's content id: one id never names two
/// scenes), a NUL, then the exact bits of anchor, spacing, lower, upper and the footprint's
/// radius, z_min and z_max. Two requests share a lattice iff their keys are equal.
std::string FleetLatticeKey(const std::string& scene_id, const FleetLatticeRequest& request);

/// A small thread-safe cache of lattices under FleetLatticeKey, least recently used first out.
class FleetLatticeCache {
 public:
  explicit FleetLatticeCache(std::size_t capacity = 16) : capacity_(capacity) {}
  /// The cached lattice, or a new one built (outside the lock) and kept; *was_cached (optional)
  /// says which.
  std::shared_ptr<const FleetLattice> GetOrBuild(const std::string& scene_id, const Scene& scene,
                                                 const FleetLatticeRequest& request, bool* was_cached = nullptr);
  std::size_t size() const;

 private:
  using Entry = std::pair<std::string, std::shared_ptr<const FleetLattice>>;
  std::size_t capacity_;
  mutable std::mutex mutex_;
  std::list<Entry> entries_;  ///< most recently used first
  std::unordered_map<std::string, std::list<Entry>::iterator> index_;
};

}  // namespace chasles
