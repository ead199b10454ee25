#pragma once
// Private to planners/multi: the FLEET method of Coordinate — a team of planar bases planned
// on the fleet lattice (fleet_lattice.h) by the grid MAPF solver (grid_mapf.h) and timed by
// the fleet schedule (fleet.h).

#include <string>
#include <vector>

#include <Eigen/Core>

#include "chasles/multi/coordinator.h"

namespace chasles::detail {

/// One robot of the team as the coordinator resolved it.
struct FleetMember {
  const PlacedRobot* placement = nullptr;
  Eigen::VectorXd start, goal;  ///< (x, y, θ)
  KinematicLimits limits;       ///< velocity and acceleration per coordinate
};

struct FleetAttempt {
  /// False: FLEET cannot plan this team (why_not says why; AUTO moves on to the other methods).
  bool applicable = false;
  std::string why_not;
  bool ok = false;
  bool out_of_time = false;
  std::string message;
  std::vector<TimedTrajectory> trajectories;
  std::vector<JointPath> paths;  ///< the lattice nodes each robot moves through, (x, y, θ)
  std::vector<double> start_delay, wait_time;
  FleetSummary summary;
  /// Limits exactly (every piece is a polynomial of degree <= 2), ends, and robot-to-robot
  /// distances at instants at most 0.01 s apart (at most 2000) between footprint discs; the
  /// separation itself is proven by the lattice and the dependencies (fleet.h).
  TeamVerificationReport verification;
};

/// Why FLEET cannot plan these robots ("" when it can): every robot a planar base (RobotKind
/// kPlanar, 3 coordinates) whose base frame is the scene frame, no committed motions.
std::string FleetInapplicable(const CoordinationQuery& query);

/// Runs FLEET. \throws Error(kInvalidArgument) for a fleet_resolution below the footprints'
/// smallest safe spacing (naming both).
FleetAttempt RunFleet(const CoordinationQuery& query, const std::vector<FleetMember>& members,
                      const Termination& termination);

}  // namespace chasles::detail
