#include "fleet_method.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>

#include "chasles/multi/fleet.h"
#include "chasles/multi/fleet_lattice.h"
#include "chasles/multi/grid_mapf.h"
#include "chasles/robot/error.h"

namespace chasles::detail {
namespace {

using Clock = std::chrono::steady_clock;

double SecondsSince(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

std::string Robot(const CoordinationQuery& query, std::size_t k) {
  return "robots[" + std::to_string(k) + "] '" + query.robots[k].placement.name + "'";
}

std::string Point(const Eigen::Vector2d& p) { return "(" + FormatNumber(p.x()) + ", " + FormatNumber(p.y()) + ")"; }

/// Limits exactly and the ends of every trajectory (pieces of degree <= 2: velocity extremes at
/// piece ends, constant acceleration); "" or what fails.
std::string CheckLimitsAndEnds(const std::vector<TimedTrajectory>& trajectories, const std::vector<FleetMember>& members,
                               double* velocity_ratio, double* acceleration_ratio) {
  *velocity_ratio = *acceleration_ratio = 0.0;
  for (std::size_t k = 0; k < trajectories.size(); ++k) {
    const TimedTrajectory& trajectory = trajectories[k];
    const FleetMember& m = members[k];
    if (trajectory.degree() > 2) return "robot " + std::to_string(k) + ": a piece of degree > 2";
    for (const TimedTrajectory::Piece& piece : trajectory.pieces()) {
      for (int j = 0; j < 3; ++j) {
        const double c1 = piece.coefficients.cols() > 1 ? piece.coefficients(j, 1) : 0.0;
        const double c2 = piece.coefficients.cols() > 2 ? piece.coefficients(j, 2) : 0.0;
        const double v = std::max(std::abs(c1), std::abs(c1 + 2.0 * c2 * piece.duration));
        *velocity_ratio = std::max(*velocity_ratio, v / m.limits.max_velocity[j]);
        *acceleration_ratio = std::max(*acceleration_ratio, std::abs(2.0 * c2) / m.limits.max_acceleration[j]);
      }
    }
    if ((trajectory.Evaluate(0.0).q - m.start).cwiseAbs().maxCoeff() > 1e-9) return "robot " + std::to_string(k) + " does not start at its start";
    if ((trajectory.Evaluate(trajectory.duration()).q - m.goal).cwiseAbs().maxCoeff() > 1e-9) {
      return "robot " + std::to_string(k) + " does not end at its goal";
    }
  }
  if (*velocity_ratio > 1.0 + 1e-9 || *acceleration_ratio > 1.0 + 1e-9) {
    return "a velocity or acceleration limit is exceeded (|q̇|/v " + FormatNumber(*velocity_ratio) + ", |q̈|/a " +
           FormatNumber(*acceleration_ratio) + ")";
  }
  return "";
}

/// The smallest distance between two robots' footprint discs at `instants` + 1 evenly spaced
/// instants over [0, makespan], capped at kMaxReportedRobotDistance; *worst names the nearest
/// pair. Robots are bucketed per instant into cells of `reach` over the lattice's extent (no
/// allocation per instant), so only pairs in neighbouring cells — nearer than `reach` — are
/// measured; the cap is below `reach`.
double MinDiscDistance(const std::vector<TimedTrajectory>& trajectories, const std::vector<double>& radii, double makespan,
                       int instants, const LatticeGeometry& lattice, double reach, std::string* worst) {
  const int n = static_cast<int>(trajectories.size());
  const int gw = static_cast<int>(std::ceil((lattice.width - 1) * lattice.spacing / reach)) + 1;
  const int gh = static_cast<int>(std::ceil((lattice.height - 1) * lattice.spacing / reach)) + 1;
  std::vector<int> head(static_cast<std::size_t>(gw) * static_cast<std::size_t>(gh)), next(static_cast<std::size_t>(n));
  std::vector<Eigen::Vector2d> at(static_cast<std::size_t>(n));
  std::vector<int> gx(static_cast<std::size_t>(n)), gy(static_cast<std::size_t>(n));
  double best = std::min(kMaxReportedRobotDistance, reach);
  for (int s = 0; s <= instants; ++s) {
    const double t = instants == 0 ? 0.0 : makespan * s / instants;
    std::fill(head.begin(), head.end(), -1);
    for (int k = 0; k < n; ++k) {
      const Eigen::Vector2d p = trajectories[static_cast<std::size_t>(k)].Evaluate(t).q.head<2>();
      at[static_cast<std::size_t>(k)] = p;
      const Eigen::Vector2d local = (p - lattice.origin) / reach;
      const int x = std::clamp(static_cast<int>(std::floor(local.x())), 0, gw - 1);
      const int y = std::clamp(static_cast<int>(std::floor(local.y())), 0, gh - 1);
      gx[static_cast<std::size_t>(k)] = x;
      gy[static_cast<std::size_t>(k)] = y;
      int& first = head[static_cast<std::size_t>(y) * static_cast<std::size_t>(gw) + static_cast<std::size_t>(x)];
      next[static_cast<std::size_t>(k)] = first;
      first = k;
    }
    for (int k = 0; k < n; ++k) {
      const Eigen::Vector2d& p = at[static_cast<std::size_t>(k)];
      for (int y = std::max(0, gy[static_cast<std::size_t>(k)] - 1); y <= std::min(gh - 1, gy[static_cast<std::size_t>(k)] + 1); ++y) {
        for (int x = std::max(0, gx[static_cast<std::size_t>(k)] - 1); x <= std::min(gw - 1, gx[static_cast<std::size_t>(k)] + 1); ++x) {
          for (int j = head[static_cast<std::size_t>(y) * static_cast<std::size_t>(gw) + static_cast<std::size_t>(x)]; j >= 0;
               j = next[static_cast<std::size_t>(j)]) {
            if (j <= k) continue;
            const double d = (at[static_cast<std::size_t>(j)] - p).norm() - radii[static_cast<std::size_t>(k)] -
                             radii[static_cast<std::size_t>(j)];
            if (d < best) {
              best = d;
              *worst = "robots " + std::to_string(k) + " and " + std::to_string(j) + " at t = " + FormatNumber(t) + " s";
            }
          }
        }
      }
    }
  }
  return best;
}

}  // namespace

std::string FleetInapplicable(const CoordinationQuery& query) {
  if (!query.committed.empty()) return "FLEET does not plan around committed workcell trajectories";
  for (std::size_t k = 0; k < query.robots.size(); ++k) {
    const TeamRobotSpec& robot = query.robots[k];
    if (robot.placement.model->kind() != RobotKind::kPlanar || robot.placement.model->num_dofs() != 3) {
      return Robot(query, k) + " is not a planar mobile base (x, y, θ); FLEET plans fleets of them";
    }
    if (!robot.placement.base_pose.matrix().isIdentity(1e-12)) {
      return Robot(query, k) + " has a base pose; FLEET plans bases whose frame is the scene frame";
    }
    if (robot.pose_goal) return Robot(query, k) + " has a pose goal; FLEET takes (x, y, θ) goals";
  }
  return "";
}

FleetAttempt RunFleet(const CoordinationQuery& query, const std::vector<FleetMember>& members,
                      const Termination& termination) {
  FleetAttempt out;
  out.why_not = FleetInapplicable(query);
  if (!out.why_not.empty()) return out;
  const std::size_t n = members.size();
  FleetSummary& summary = out.summary;

  // 1. Footprints, spacing and the lattice (cached under the scene's id).
  std::vector<std::shared_ptr<const RobotModel>> models;
  for (const FleetMember& m : members) models.push_back(m.placement->model);
  const FleetLatticeChoice choice =
      ChooseFleetLattice(models, members[0].start.head<2>(), *query.scene, query.scene_id, query.fleet_resolution,
                         query.robot_padding, query.lattice_cache);
  const std::vector<double>& radii = choice.radii;
  const std::shared_ptr<const FleetLattice>& lattice = choice.lattice;
  const double spacing = choice.spacing;
  summary.lattice_cached = choice.cached;
  summary.lattice_seconds = choice.seconds;
  const LatticeGeometry& geometry = lattice->geometry();
  summary.resolution = spacing;
  summary.width = geometry.width;
  summary.height = geometry.height;

  // 2. Starts and goals on nodes; off the lattice FLEET does not apply (AUTO moves on).
  std::vector<GridCell> starts(n), goals(n);
  try {
    for (std::size_t k = 0; k < n; ++k) {
      starts[k] = geometry.NodeAt(members[k].start.head<2>(), "robots[" + std::to_string(k) + "].start");
      goals[k] = geometry.NodeAt(members[k].goal.head<2>(), "robots[" + std::to_string(k) + "].goal");
    }
  } catch (const Error& e) {
    out.why_not = e.what();
    return out;
  }
  out.applicable = true;
  // A lattice whose free nodes are joined by a blocked edge is planned with one end of each
  // such edge blocked, so every move between free neighbours is along a free edge.
  const GridMap map = lattice->blocked_edges().empty() ? lattice->map() : lattice->NodeBlockingMap();
  summary.free_nodes = static_cast<int>(std::count(map.blocked.begin(), map.blocked.end(), 0));
  for (std::size_t k = 0; k < n; ++k) {
    for (const auto& [cell, what] : {std::pair<GridCell, const char*>{starts[k], "start"}, {goals[k], "goal"}}) {
      if (map.blocked[static_cast<std::size_t>(cell)] == 0) continue;
      out.message = Robot(query, k) + ": its " + what + " node " + Point(geometry.Position(cell)) +
                    " is not free for the fleet's footprint (a cylinder of radius " +
                    FormatNumber(choice.footprint.radius) + " m, the largest robot's) or lies at a blocked edge";
      return out;
    }
  }

  // 3. The discrete plan.
  MapfOptions options;
  options.seed = query.seed;
  options.refine_budget = std::min(0.3, 0.25 * termination.SecondsLeft());
  const MapfResult plan = SolveMapf(map, starts, goals, options, termination);
  summary.search_seconds = plan.seconds;
  if (!plan.solved) {
    out.message = plan.message;
    out.out_of_time = termination.ShouldStop();
    return out;
  }
  summary.makespan_steps = plan.makespan;
  summary.sum_of_costs = plan.sum_of_costs;
  summary.sum_of_lower_bounds = plan.sum_of_lower_bounds;

  // 4. Timing and dependencies.
  const Clock::time_point t_schedule = Clock::now();
  FleetScheduleRequest timing;
  timing.lattice = geometry;
  timing.paths = plan.paths;
  timing.free_space = lattice.get();
  for (const FleetMember& m : members) {
    FleetRobot robot;
    robot.start = m.start;
    robot.goal = m.goal;
    robot.max_velocity = m.limits.max_velocity;
    robot.max_acceleration = m.limits.max_acceleration;
    timing.robots.push_back(robot);
  }
  const FleetSchedule schedule = ScheduleFleet(timing);
  summary.schedule_seconds = SecondsSince(t_schedule);

  // 5. Per robot: trajectory, the nodes it moves through, and where each step leaves it.
  std::vector<std::vector<int>> node_before(n);  // [k][t]: index into paths[k] of the node at step t
  for (std::size_t k = 0; k < n; ++k) {
    const FleetRobotSchedule& robot = schedule.robots[k];
    const std::vector<GridCell>& cells = plan.paths[k];
    JointPath nodes{members[k].start};
    std::vector<int>& before = node_before[k];
    before.assign(cells.size(), 0);
    for (std::size_t t = 0; t + 1 < cells.size(); ++t) {
      before[t] = static_cast<int>(nodes.size()) - 1;
      if (cells[t + 1] == cells[t]) continue;
      const Eigen::Vector2d p = geometry.Position(cells[t + 1]);
      nodes.push_back(Eigen::Vector3d(p.x(), p.y(), members[k].start[2]));
    }
    before.back() = static_cast<int>(nodes.size()) - 1;
    if (nodes.size() > 1) nodes.back().head<2>() = members[k].goal.head<2>();  // the exact goal, not the node's rounding
    if (nodes.back()[2] != members[k].goal[2]) nodes.push_back(members[k].goal);  // the turn in place
    out.paths.push_back(std::move(nodes));
    out.trajectories.push_back(robot.trajectory);
    out.start_delay.push_back(robot.runs.empty() ? robot.finish_time : robot.runs.front().start_time);
    out.wait_time.push_back(robot.wait_time);
  }
  for (const FleetDependency& d : schedule.dependencies) {
    FleetWait wait;
    wait.robot = d.robot;
    wait.leave_index = node_before[static_cast<std::size_t>(d.robot)][static_cast<std::size_t>(d.step)];
    wait.waits_for = d.waits_for_robot;
    wait.arrival_index = node_before[static_cast<std::size_t>(d.waits_for_robot)][static_cast<std::size_t>(d.waits_for_step)] + 1;
    wait.x = d.x;
    wait.y = d.y;
    summary.dependencies.push_back(wait);
  }

  // 6. Verification: limits and ends exactly; the robots' discs at instants (the separation is
  //    proven by the lattice and the dependencies — this re-measures it).
  TeamVerificationReport& verification = out.verification;
  std::string failure =
      CheckLimitsAndEnds(out.trajectories, members, &verification.max_velocity_ratio, &verification.max_acceleration_ratio);
  const double makespan = schedule.makespan;
  const int instants = std::max(1, std::min(2000, static_cast<int>(std::ceil(makespan / 0.01))));
  std::string nearest;
  verification.min_robot_distance =
      n < 2 ? kMaxReportedRobotDistance
            : MinDiscDistance(out.trajectories, radii, makespan, instants, geometry, 2.0 * spacing, &nearest);
  verification.states_checked = static_cast<std::uint64_t>(instants + 1) * n;
  if (failure.empty() && n >= 2 && verification.min_robot_distance < query.robot_padding - 1e-9) {
    failure = "footprint discs " + FormatNumber(verification.min_robot_distance) + " m apart (" + nearest +
              "), less than robot_padding " + FormatNumber(query.robot_padding) + " m";
  }
  verification.ok = failure.empty();
  verification.reason = failure;
  verification.collision_guarantee = "certified";
  verification.collision_guarantee_reason = "";
  out.ok = verification.ok;
  out.message = verification.ok ? "fleet of " + std::to_string(n) + " on a " + std::to_string(geometry.width) + " x " +
                                      std::to_string(geometry.height) + " lattice (" + FormatNumber(spacing) +
                                      " m), sum of costs " + std::to_string(plan.sum_of_costs) + " steps (" +
                                      std::to_string(plan.sum_of_lower_bounds) + " alone), " + plan.message
                                : "its schedule failed verification: " + failure;
  return out;
}

}  // namespace chasles::detail
