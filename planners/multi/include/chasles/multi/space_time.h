#pragma once
/// \file
/// Planning one robot in space-time among moving obstacles: a roadmap of its configuration
/// space (static obstacles only), then A* over (roadmap vertex, time) with moves along roadmap
/// edges and waits at vertices, every move and wait checked against the moving obstacles.

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "chasles/collision/collision_checker.h"
#include "chasles/optimizers/time_parameterization.h"
#include "chasles/optimizers/timed_trajectory.h"
#include "chasles/planners/termination.h"
#include "chasles/robot/joint_path.h"

namespace chasles {

/// True when the robot at configuration q at time t [s] is clear of every moving obstacle
/// (other robots' timed trajectories). Static obstacles are the roadmap's business.
using ConflictFree = std::function<bool(const Eigen::VectorXd& q, double t)>;

/// An undirected graph in one robot's configuration space; every vertex and edge (straight
/// joint-space segment) is valid against the static obstacles.
struct Roadmap {
  std::vector<Eigen::VectorXd> vertices;
  std::vector<std::vector<int>> neighbors;  ///< adjacency, symmetric
  /// Straight lines: the stations of one original edge in order (endpoints included). A robot
  /// may move between any two stations of a line in one straight motion, without stopping at
  /// the stations between (BuildRoadmap fills this; a roadmap without lines moves edge by edge).
  std::vector<std::vector<int>> lines;
  /// Adds a vertex; returns its index.
  int AddVertex(const Eigen::VectorXd& q);
  void AddEdge(int a, int b);
};

struct RoadmapOptions {
  int prm_vertices = 200;        ///< vertices grown by OMPL's PRM besides the seed paths; 0 = none
  int neighbors = 8;             ///< PRM / seed-path connections per vertex (k nearest)
  double station_spacing = 0.25; ///< [rad] edges longer than this (largest joint difference) get equally spaced intermediate vertices (places to wait)
  std::uint64_t seed = 1;
};

/// The seed paths' waypoints joined by their segments (assumed valid: each path is a planner's
/// result), plus, when prm_vertices > 0, an OMPL PRM roadmap grown on `checker` (seeded from
/// `seed`, motions by IsMotionCertified) with every seed-path vertex connected to its nearest
/// PRM vertices by valid motions. Long edges are subdivided at station_spacing. Stops early when
/// `termination` does. Vertex 0 is the first path's start.
Roadmap BuildRoadmap(const CollisionChecker& checker, const std::vector<JointPath>& seed_paths,
                     const RoadmapOptions& options, const Termination& termination);

struct SpaceTimeOptions {
  double wait_step = 0.1;          ///< [s] waits are multiples of this
  double horizon = 120.0;          ///< [s] no arrival later than this is searched
  /// [s] the robot must stay clear at the goal from its arrival until this time (the other
  /// robots' last motion ends); also the earliest the search may declare success.
  double hold_until = 0.0;
  double time_step = 0.01;         ///< [s] largest time step between checked states in the search
  double max_joint_step = 0.02;    ///< [rad] largest joint step between checked states in the search
  double time_resolution = 0.05;   ///< [s] (vertex, time) states closer than this in time are one
  int max_expansions = 200000;
  /// Moves between waits are retimed through their corners (time-optimal, stops only where the
  /// search waits) when the faster motion stays clear; the later schedule is kept by waiting
  /// longer at the next stop.
  bool merge_moves = true;
};

struct SpaceTimeResult {
  bool found = false;
  std::string message;            ///< why not, or a summary
  TimedTrajectory trajectory;     ///< from t = 0 at the start vertex to the goal vertex, waits included
  JointPath path;                 ///< the roadmap vertices it visits, in order
  double arrival = 0.0;           ///< [s] when it reaches the goal for good
  double start_delay = 0.0;       ///< [s] waited at the start before moving
  double wait_time = 0.0;         ///< [s] waited in all
  int expansions = 0;
  std::uint64_t conflict_checks = 0;
};

/// Earliest-arrival A* over (vertex, time): from `start_vertex` at t = 0 to `goal_vertex`, where
/// the robot must then stay clear until hold_until. Moves go from a station to any other station
/// of the same line (or along an edge when the roadmap has no lines) with the exact rest-to-rest
/// profile under `limits` (ParameterizeRestToRest); waits are multiples of wait_step. Every move and wait is checked with `conflict_free` at states at most time_step and
/// max_joint_step apart. The heuristic is the exact time to the goal over these moves ignoring
/// moving obstacles (Dijkstra from the goal; admissible and consistent); states that could not
/// reach the goal by the horizon even unhindered are not searched, and moves and waits are
/// checked when they leave the queue (lazily). The goal is looked at first: when it is occupied
/// at hold_until and at every time_step sample from there to the horizon (or at a sample between
/// the horizon and a later hold_until), nothing is searched and `message` says so. Expected
/// failures (no route, expansions or termination exhausted) are results with `message` set;
/// bad input (vertex indices, limits sizes, non-positive steps) throws kInvalidArgument.
SpaceTimeResult SearchSpaceTime(const Roadmap& roadmap, int start_vertex, int goal_vertex,
                                const KinematicLimits& limits, const ConflictFree& conflict_free,
                                const SpaceTimeOptions& options, const Termination& termination);

}  // namespace chasles
