#pragma once
/// \file
/// Executing a fleet's grid MAPF plan: per robot a timed trajectory in (x, y, θ) along the
/// lattice, and the action dependency graph (temporal plan graph: Hönig et al., "Multi-agent
/// path finding with kinematic constraints", ICAPS 2016; "Persistent and robust execution of
/// MAPF schedules in warehouses", RA-L 2019) that keeps the robots apart however late any of
/// them runs. SI units.
///
/// Separation. On a 4-connected lattice of spacing s, let every robot at every instant occupy
/// either a node (its position) or an edge with its two end nodes (its position lies on the
/// segment). If two robots' occupied node sets are disjoint, their positions are at least s
/// apart, even in the max-norm: in lattice units a position on a node or edge has one
/// coordinate integral (a node: both). Node w vs a node v ≠ w: some coordinate differs by an
/// integer ≥ 1. Node w vs edge {u, v} (say u = (a, b), v = (a+1, b)) with w = (c, d) ∉ {u, v}:
/// d ≠ b gives |Δy| ≥ 1, else c ∉ {a, a+1} gives |Δx| ≥ 1 over x ∈ [a, a+1]. Parallel edges on
/// different lines differ by ≥ 1 across; on one line, node-disjoint x-intervals [a, a+1],
/// [c, c+1] have |a − c| ≥ 2, so a gap ≥ 1. Perpendicular {(a,b),(a+1,b)} and {(c,d),(c,d+1)}:
/// c ∉ {a, a+1} gives |Δx| ≥ 1; else d ∉ {b−1, b} (disjoint) gives |Δy| ≥ 1. So with
/// s ≥ R_i + R_j + padding for every pair, footprint discs never come closer than the padding.
///
/// Schedule. A move of robot i at discrete step t goes from paths[i][t] to paths[i][t+1]. The
/// dependency rule: i's move into node v starts only after the robot j ≠ i that visited v last
/// before i (in discrete time; it may leave v at the very step i enters, following) has
/// completed its move out of v (arrived at its next node). Earlier visitors need no edge of their
/// own: each visit of v entered after the previous one left (transitively); nor does a wait
/// for j's move b when an earlier move of the same robot already waits for a move b' >= b of
/// j (j completes b before b'). Proof of
/// separation: robot i occupies {u, v} over [start, end) of its move u → v and {v} while it
/// stands at v. A visit of v then occupies v over [entry start, exit end) (from 0 for the robot
/// that starts there, for ever for the one that ends there). Visits of v are ordered as in the
/// discrete plan, which never has two robots in one cell at one step; each begins no earlier
/// than the previous one ends (the dependency, or a robot's own move order), and each is a
/// non-empty interval, so the half-open intervals are disjoint: no two robots occupy a node at
/// one instant, and the separation above holds at every instant, on time or late.
///
/// Moves. Waits of the plan are dropped (a robot moves as soon as its dependencies allow).
/// Consecutive moves in one direction form a run, one rest-to-rest trapezoid (or triangle)
/// profile; the robot stops at every change of direction (never cuts a corner, so it stays on
/// the lattice) and holds θ while translating. A run is split before any move but its first
/// that has a dependency: a run then only waits to start, never mid-way. Without this, a run
/// R's later move could wait for a robot that itself waits for R's earlier move (a cycle of
/// runs, or an infeasible schedule); with it, every dependency points from a move at step b
/// to a run whose first move is at step t ≥ b, with b = t only for following within one step,
/// which a valid plan (no rotation cycles) keeps acyclic. Runs are timed in topological order,
/// each at the latest of: its robot's release time, its previous run's end, and the
/// completion of the moves its first move waits for. After its last arrival a robot turns in
/// place to its goal heading (its footprint disc contains it at every heading).
///
/// Makespan. Waits cost nothing and straight runs are faster than one move per step, but a
/// follower starts only when the robot ahead has arrived, so a chain of k robots that the plan
/// moves in one step takes k moves' time here: the makespan is not bounded by the discrete
/// makespan times one move's duration in general (tests/multi/fleet_test.cc, 110 robots on a
/// 32 x 32 lattice: 119 s against 60 steps x 2.55 s = 153 s).

#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "chasles/multi/fleet_lattice.h"
#include "chasles/multi/grid_map.h"
#include "chasles/optimizers/timed_trajectory.h"

namespace chasles {

/// The smallest lattice spacing that keeps every pair of robots `padding` apart: the sum of the
/// two largest radii plus padding (one robot: twice its radius plus padding) [m].
/// \throws Error(kInvalidArgument) for an empty list, a radius that is not finite and > 0, or a
///         padding that is not finite and >= 0 (naming radii[i] / padding).
double FleetResolution(const std::vector<double>& radii, double padding);

/// The lattice a fleet of planar robots plans on (FleetLatticeRequest filled for them, built or
/// taken from a cache).
struct FleetLatticeChoice {
  std::shared_ptr<const FleetLattice> lattice;
  double spacing = 0.0;    ///< [m]
  Footprint footprint;     ///< CoverFootprints of the robots'
  std::vector<double> radii;  ///< each robot's footprint radius [m]
  bool cached = false;     ///< taken from the cache
  double seconds = 0.0;    ///< building it [s] (0 when cached)
};

/// The robots' lattice: spacing `resolution`, or FleetResolution of their footprints
/// (PlanarFootprint) and `padding` when 0; bounds FleetBounds(robots); anchored at `anchor`
/// (a robot's start); from `cache` under `scene_id` when both are given (else built).
/// \throws Error(kInvalidArgument) for a resolution below the smallest safe spacing (naming
///         `resolution_field`, both values and the padding), and what PlanarFootprint,
///         FleetBounds and BuildFleetLattice throw.
FleetLatticeChoice ChooseFleetLattice(const std::vector<std::shared_ptr<const RobotModel>>& robots,
                                      const Eigen::Vector2d& anchor, const Scene& scene, const std::string& scene_id,
                                      double resolution, double padding, FleetLatticeCache* cache,
                                      const std::string& resolution_field = "fleet_resolution",
                                      const std::string& padding_field = "robot_padding");

struct FleetRobot {
  Eigen::Vector3d start = Eigen::Vector3d::Zero();  ///< (x, y, θ) [m, m, rad]; (x, y) on a node
  Eigen::Vector3d goal = Eigen::Vector3d::Zero();   ///< (x, y, θ); (x, y) on a node
  Eigen::Vector3d max_velocity = Eigen::Vector3d::Ones();      ///< per coordinate, > 0
  Eigen::Vector3d max_acceleration = Eigen::Vector3d::Ones();  ///< per coordinate, > 0
  double release_time = 0.0;  ///< [s] >= 0: the robot starts no earlier (a late robot)
};

struct FleetScheduleRequest {
  LatticeGeometry lattice;
  std::vector<FleetRobot> robots;
  /// paths[i][t]: robot i's cell at step t; all of one length >= 1, paths[i][0] = the start's
  /// node, paths[i].back() = the goal's node, consecutive cells equal or 4-neighbours.
  std::vector<std::vector<GridCell>> paths;
  /// Optional: the lattice's free nodes and edges; then every cell must be free and every move
  /// along a free edge.
  const FleetLattice* free_space = nullptr;
};

/// An edge of the action dependency graph between two robots.
struct FleetDependency {
  int robot = 0, step = 0;                      ///< robot's move at this step (into `cell`) ...
  int waits_for_robot = 0, waits_for_step = 0;  ///< ... waits until this move (out of `cell`) is done
  GridCell cell = 0;
  double x = 0.0, y = 0.0;  ///< the node of `cell` [m]
};

/// Moves of one robot executed as one rest-to-rest straight motion.
struct FleetRun {
  int first_step = 0, last_step = 0;  ///< the discrete steps of its first and last move
  GridCell from = 0, to = 0;
  double start_time = 0.0, end_time = 0.0;  ///< [s]
};

struct FleetRobotSchedule {
  TimedTrajectory trajectory;  ///< (x, y, θ), from t = 0 (at rest at the start) to its end at the goal
  double arrival_time = 0.0;   ///< [s] the robot reaches its goal node for good (before turning)
  double finish_time = 0.0;    ///< [s] the trajectory's end, goal heading reached
  double wait_time = 0.0;      ///< [s] standing between release and arrival, waiting for others
  std::vector<FleetRun> runs;
};

struct FleetSchedule {
  std::vector<FleetRobotSchedule> robots;
  /// Every cross-robot dependency, by robot then step. An executor that starts each move only
  /// when the moves it waits for are done keeps the separation whatever the timing.
  std::vector<FleetDependency> dependencies;
  double makespan = 0.0;  ///< [s] the latest finish_time
  int discrete_makespan = 0;  ///< steps until the last robot's last move ends
};

/// Times the plan (see the file comment).
/// \throws Error(kInvalidArgument) naming the field, e.g. `robots[2].start = (1.2, 0.4) is not on
///         a lattice node: …`, `robots[0].max_velocity[2] = 0 must be > 0`, `paths[3][7] = 12 is
///         not a neighbour of paths[3][6] = 40`, `paths[1][4] = 17: robots 1 and 5 are both in
///         that cell at step 4`, `paths[2][3]: robots 2 and 6 swap cells 8 and 9 at step 3`,
///         `paths[4][2] moves along the blocked edge 30 -> 31`, or a rotation cycle of
///         following robots at one step.
FleetSchedule ScheduleFleet(const FleetScheduleRequest& request);

}  // namespace chasles
