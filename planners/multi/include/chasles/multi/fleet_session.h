#pragma once
/// \file
/// Lifelong fleet operation: goals keep coming, one robot at a time, and each is answered with a
/// trajectory that keeps clear of every trajectory already given out, without replanning the
/// fleet. SI units; times are on the session's clock [s].
///
/// Occupancy. Every robot's motion is a sequence of rest-to-rest straight runs along the lattice
/// (one or more edges in one direction) and stands at nodes. A robot occupies a node from the
/// start of the run that brings it there (the moment it may leave the previous node) to the end
/// of the run that takes it away (it has arrived at the next node), and every node along a run
/// for the whole run; after its last run it occupies its last node for ever (parked) until a new
/// goal moves it. Occupancy intervals are half-open, [enter, leave). When no two robots occupy a
/// node at one instant, every robot is on a node or on an edge whose two nodes it occupies, so
/// (fleet.h, "Separation") their positions are at least the spacing apart at every instant: with
/// spacing >= R_i + R_j + padding the footprint discs keep the padding. This is what Assign keeps,
/// exactly (no sampling), with a guard of kGuard seconds on every interval.
///
/// Planning a goal (Assign). Safe interval path planning (SIPP: Phillips & Likhachev, ICRA 2011)
/// over (node, safe interval) for the robot with the goal, against the occupancy of all others:
/// an action is one straight run of 1 … max_run edges, leaving as early as the start node, the
/// nodes along the run and the end node allow; the goal is reached in its last safe interval
/// (the robot may park there for ever). A* with the time of a straight rest-to-rest run over the
/// lattice distance as heuristic (admissible: run times are subadditive). The robot keeps the run
/// it is on at `now` (a new plan starts where that run ends) and, once arrived, turns in place to
/// the goal heading (the footprint disc holds it at every heading).
///
/// Idle robots in the way (the window). When no plan exists among the parked robots, the robot is
/// planned as if idle robots (parked, no motion left after `now`) were absent; each idle robot
/// parked on a node that plan uses is moved aside, to the nearest node off that plan's nodes where
/// nobody else parks, itself planned with SIPP against everyone; then the robot is planned again
/// among them (a few rounds). Only the robot with the goal and the idle robots it displaces get
/// new trajectories: the rest of the fleet keeps its own, as rolling-horizon lifelong MAPF replans
/// a window rather than the whole fleet. On failure nothing changes.

#include <cstddef>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "chasles/multi/fleet.h"
#include "chasles/multi/fleet_lattice.h"
#include "chasles/optimizers/timed_trajectory.h"
#include "chasles/planners/termination.h"

namespace chasles {

struct FleetSessionRobot {
  std::string name;  ///< in messages ("robot 'name'"); empty = "robot <index>"
  Eigen::Vector3d pose = Eigen::Vector3d::Zero();              ///< (x, y, θ) at the session's start; (x, y) on a free node
  Eigen::Vector3d max_velocity = Eigen::Vector3d::Ones();      ///< per coordinate, > 0
  Eigen::Vector3d max_acceleration = Eigen::Vector3d::Ones();  ///< per coordinate, > 0
};

struct FleetSessionOptions {
  int max_run = 10;          ///< longest straight run of one action [edges]
  int max_evasions = 16;     ///< idle robots one goal may move aside
  int evasion_rounds = 3;    ///< plan / move aside / plan again, at most this often
  std::size_t max_expansions = 2000000;  ///< SIPP states expanded per search
};

/// One robot's committed motion.
struct FleetSessionPlan {
  double start_time = 0.0;     ///< session time of the trajectory's t = 0 [s]
  TimedTrajectory trajectory;  ///< (x, y, θ), at rest at both ends
  double arrival_time = 0.0;   ///< session time it reaches its last node [s]
  double finish_time = 0.0;    ///< session time the trajectory ends (heading turned) [s]
  std::vector<FleetRun> runs;  ///< its runs, session times (first_step/last_step: run indices)
};

/// An order at a node an executor keeps when robots run late: `after_robot` enters `cell` only
/// once `before_robot` has left it.
struct FleetSessionOrder {
  int before_robot = 0, after_robot = 0;
  GridCell cell = 0;
  double x = 0.0, y = 0.0;          ///< the node [m]
  double leaves = 0.0, enters = 0.0;  ///< planned session times [s]: before_robot leaves, after_robot enters
};

enum class FleetGoalCode { kSuccess, kNoPath, kStopped };

/// Where a reported robot stands against its plan (FleetSession::Report).
enum class FleetStateStatus {
  kOnPlan,   ///< within the tolerance of its planned (x, y) at the report's time
  kLate,     ///< on its planned path, behind: its plan and those ordered after it were delayed
  kAhead,    ///< on its planned path, ahead: nothing changes (the orders hold it back)
  kOffPlan,  ///< farther than the tolerance from every straight run of its plan: nothing changes
};

struct FleetStateOutcome {
  FleetStateStatus status = FleetStateStatus::kOnPlan;
  double deviation = 0.0;  ///< [m] from the planned (x, y) at the report's time
  /// [s] the report's time minus the plan's time at the reported point: > 0 late, < 0 ahead
  /// (kLate and kAhead only).
  double delay = 0.0;
  Eigen::Vector3d planned = Eigen::Vector3d::Zero();  ///< the planned pose at the report's time
  std::vector<int> robots;                ///< kLate: robots whose plans were delayed, the reporting robot first
  std::vector<FleetSessionOrder> orders;  ///< kLate: the orders the delayed plans take part in
  std::string message;                    ///< what was found, one sentence
};

struct FleetGoalOutcome {
  FleetGoalCode code = FleetGoalCode::kNoPath;
  std::string message;                ///< why, when not kSuccess
  std::vector<int> robots;            ///< robots given a new plan: the goal's robot first, then those moved aside
  std::vector<FleetSessionOrder> orders;  ///< the orders the new plans take part in
  std::size_t expansions = 0;         ///< SIPP states expanded, all searches
  int searches = 0;
  double seconds = 0.0;               ///< wall time
};

class FleetSession {
 public:
  /// A guard [s] added to both ends of other robots' occupancy intervals.
  static constexpr double kGuard = 1e-6;

  /// Every robot standing at its pose (parked) from `start_time`.
  /// \throws Error(kInvalidArgument) naming robots[i] (off a node, on a blocked node, two robots on
  ///         one node, a limit not finite and > 0), or a null lattice.
  FleetSession(std::shared_ptr<const FleetLattice> lattice, std::vector<FleetSessionRobot> robots,
               double start_time, FleetSessionOptions options = {});

  /// Plans `robot` to `goal` (x, y on a node; θ its final heading) from session time `now`.
  /// The session's clock never goes back: a `now` before an earlier call's is taken as that one
  /// (two dispatchers, or two replicas' clocks, a little apart).
  /// \throws Error(kInvalidArgument) for a robot index out of range, a goal off the lattice's
  ///         nodes or on a blocked node, or `now` not finite or before the session's start.
  /// Deterministic: the same calls on two sessions made alike give the same plans (unless
  /// `termination` stops a search, which then changes nothing).
  FleetGoalOutcome Assign(int robot, const Eigen::Vector3d& goal, double now, const Termination& termination = {});

  /// A robot's observed position (x, y) at session time `time` (its execution state, as a fleet
  /// manager streams it). Within `tolerance` [m] of the planned position: on plan. Otherwise the
  /// plan's straight runs are searched for the point: a robot found there behind its plan is
  /// late by δ = time − (the plan's time at that point), and its plan is delayed by δ from the
  /// start of the run it is on (it waits δ longer at the node before, so the new plan has it at
  /// the reported point at `time`); every robot ordered after it at a node it now leaves later is
  /// delayed as much as needed, and so on (the delays an action-dependency-graph executor would
  /// impose, applied to the plans, so later goals are planned around where the robots will
  /// actually be). Node occupancy stays exclusive. A robot ahead of its plan, or off it, changes
  /// nothing (the orders hold an early robot back; an off-plan robot is for its executor to
  /// stop). Deterministic like Assign; `time` moves the session's clock like Assign's `now`.
  /// \throws Error(kInvalidArgument) for a robot out of range, a position not finite, a
  ///         tolerance not finite and > 0, or `time` as Assign's `now`.
  FleetStateOutcome Report(int robot, const Eigen::Vector2d& position, double time, double tolerance);

  /// The free lattice node of `goal` (x, y) — what Assign checks its goal with.
  /// \throws Error(kInvalidArgument) naming `field`: a heading that is not finite, (x, y) off the
  ///         lattice's nodes (NodeAt's message) or on a blocked node.
  GridCell GoalCell(const Eigen::Vector3d& goal, const std::string& field) const;

  /// What an Assign that changed nothing leaves behind (its clock and bookkeeping), for a
  /// session replaying another's calls: every call that failed there is a Skip here.
  /// \throws what Assign throws for `now`.
  void Skip(double now);

  int num_robots() const { return static_cast<int>(robots_.size()); }
  const FleetLattice& lattice() const { return *lattice_; }
  /// The robot's current plan (standing at its start pose until its first goal).
  const FleetSessionPlan& plan(int robot) const;
  /// The robot's planned pose at session time t (its plan's start pose before it starts).
  Eigen::Vector3d PoseAt(int robot, double t) const;
  /// The orders robot's plan takes part in at the nodes it occupies after `from`: who leaves
  /// each node before it enters, and who enters after it leaves.
  std::vector<FleetSessionOrder> Orders(int robot, double from) const { return OrdersOf(robot, from); }
  /// Occupancy intervals held (all robots), for memory accounting.
  std::size_t occupancy_size() const;

 private:
  struct Occupancy {
    double enter = 0.0, leave = 0.0;  ///< [enter, leave); leave = +inf when parked
    int robot = 0;
  };
  struct Visit {
    GridCell cell = 0;
    double enter = 0.0, leave = 0.0;
  };
  struct RobotState {
    FleetSessionRobot limits;
    FleetSessionPlan plan;
    std::vector<Visit> visits;  ///< time order
    double heading = 0.0;       ///< θ at the end of the plan
  };
  struct SearchResult;
  class Search;

  void CheckNow(double now) const;
  void Advance(double now);
  void Index(int robot);
  void Unindex(int robot);
  void Forget(double before);
  /// The node robot stands at (or its current run ends at) and when, from `now` on.
  Visit Anchor(int robot, double now) const;
  bool Idle(int robot, double now) const;
  /// New state for `robot`: its visits before anchor, then `path` (cells and run times).
  RobotState Replanned(int robot, const Visit& anchor, const SearchResult& result, double goal_heading) const;
  std::vector<FleetSessionOrder> OrdersOf(int robot, double from) const;
  /// The orders of each of `robots` in turn.
  std::vector<FleetSessionOrder> OrdersOf(const std::vector<int>& robots, double from) const;
  std::string Name(int robot) const;
  /// Delays robot's plan by `delta` > 0 from session time `from` (a run's start: it waits there).
  void Shift(int robot, double from, double delta);
  /// Shift(robot, from, delta), then every robot ordered after a delayed one at a node, as much as
  /// it must; the robots delayed, `robot` first.
  std::vector<int> Delay(int robot, double from, double delta);
  /// The nearest node (along free edges) from where idle `robot` stands that is not marked in
  /// `avoid`, is not `goal` and that no other robot occupies after `now`; -1 when none.
  GridCell Refuge(int robot, const std::vector<char>& avoid, GridCell goal, double now) const;

  std::shared_ptr<const FleetLattice> lattice_;
  FleetSessionOptions options_;
  double start_time_ = 0.0;
  double forgotten_ = 0.0;
  double latest_now_ = 0.0;  ///< the latest `now` of a call
  int assigns_ = 0;
  std::vector<RobotState> robots_;
  std::vector<std::vector<Occupancy>> occupancy_;  ///< per cell, any order
};

}  // namespace chasles
