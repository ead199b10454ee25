#include "chasles/multi/fleet.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <queue>
#include <string>
#include <tuple>
#include <utility>

#include "chasles/robot/error.h"
#include "rest_to_rest.h"

namespace chasles {
namespace {

using fleet_internal::AlongLimit;
using fleet_internal::Profile;

std::string Cell(const std::string& field, GridCell cell) { return field + " = " + std::to_string(cell); }

std::string PathField(int robot, int step) {
  return "paths[" + std::to_string(robot) + "][" + std::to_string(step) + "]";
}

int Direction(const LatticeGeometry& lattice, GridCell from, GridCell to) {
  for (int d = 0; d < 4; ++d) {
    if (lattice.Neighbour(from, static_cast<LatticeDirection>(d)) == to) return d;
  }
  return -1;
}

struct Move {
  int step = 0;
  GridCell from = 0, to = 0;
  int direction = 0;
  int run = -1;          ///< global run index
  int index_in_run = 0;  ///< 1 for the run's first move
  std::vector<std::pair<int, int>> waits_for;  ///< (robot, step) of moves out of `to`
};

struct Run {
  int robot = 0;
  int first = 0, last = 0;  ///< move indices of the robot, inclusive
  Eigen::Vector2d from = Eigen::Vector2d::Zero(), to = Eigen::Vector2d::Zero();
  double start = 0.0;
  Profile profile{0.0, 1.0, 1.0};
  std::vector<double> reach;  ///< per move of the run: distance along it at its arrival
};

void ValidateRobot(const FleetRobot& robot, int i) {
  const std::string field = "robots[" + std::to_string(i) + "]";
  for (int k = 0; k < 3; ++k) {
    const std::string index = "[" + std::to_string(k) + "] = ";
    if (!(robot.max_velocity[k] > 0.0) || !std::isfinite(robot.max_velocity[k])) {
      ThrowInvalid(field + ".max_velocity" + index + FormatNumber(robot.max_velocity[k]) + " must be > 0 and finite");
    }
    if (!(robot.max_acceleration[k] > 0.0) || !std::isfinite(robot.max_acceleration[k])) {
      ThrowInvalid(field + ".max_acceleration" + index + FormatNumber(robot.max_acceleration[k]) +
                   " must be > 0 and finite");
    }
  }
  if (!std::isfinite(robot.start.z())) ThrowInvalid(field + ".start theta = " + FormatNumber(robot.start.z()) + " must be finite");
  if (!std::isfinite(robot.goal.z())) ThrowInvalid(field + ".goal theta = " + FormatNumber(robot.goal.z()) + " must be finite");
  if (!(robot.release_time >= 0.0) || !std::isfinite(robot.release_time)) {
    ThrowInvalid(field + ".release_time = " + FormatNumber(robot.release_time) + " must be >= 0 and finite");
  }
}

/// Checks the discrete plan's rules: cells on the lattice (free, when the free space is given),
/// moves to neighbours (along free edges), ends at the robots' nodes, one robot per cell and
/// step, no swaps. Rotation cycles are found when the runs are ordered.
void ValidatePlan(const FleetScheduleRequest& request, const std::vector<GridCell>& starts,
                  const std::vector<GridCell>& goals) {
  const LatticeGeometry& lattice = request.lattice;
  const int n = static_cast<int>(request.robots.size());
  if (static_cast<int>(request.paths.size()) != n) {
    ThrowInvalid("paths has " + std::to_string(request.paths.size()) + " paths for " + std::to_string(n) + " robots");
  }
  const std::size_t horizon = request.paths[0].size();
  for (int i = 0; i < n; ++i) {
    const auto& path = request.paths[i];
    if (path.empty() || path.size() != horizon) {
      ThrowInvalid("paths[" + std::to_string(i) + "] has " + std::to_string(path.size()) +
                   " steps; every path needs the same number >= 1 (paths[0] has " + std::to_string(horizon) + ")");
    }
    for (std::size_t t = 0; t < horizon; ++t) {
      const GridCell c = path[t];
      const std::string field = PathField(i, static_cast<int>(t));
      if (c < 0 || c >= lattice.num_cells()) {
        ThrowInvalid(Cell(field, c) + " is not a cell of the " + std::to_string(lattice.width) + " x " +
                     std::to_string(lattice.height) + " lattice");
      }
      if (request.free_space != nullptr && !request.free_space->node_free(c)) {
        ThrowInvalid(Cell(field, c) + " is a blocked node of the lattice");
      }
      if (t == 0) continue;
      const GridCell prev = path[t - 1];
      if (c == prev) continue;
      const int d = Direction(lattice, prev, c);
      if (d < 0) {
        ThrowInvalid(Cell(field, c) + " is not a neighbour of " + Cell(PathField(i, static_cast<int>(t - 1)), prev));
      }
      if (request.free_space != nullptr && !request.free_space->edge_free(prev, static_cast<LatticeDirection>(d))) {
        ThrowInvalid(field + " moves along the blocked edge " + std::to_string(prev) + " -> " + std::to_string(c) +
                     " (the footprint swept along it hits the scene)");
      }
    }
    if (path.front() != starts[i]) {
      ThrowInvalid(Cell(PathField(i, 0), path.front()) + " is not robots[" + std::to_string(i) + "].start's cell " +
                   std::to_string(starts[i]));
    }
    if (path.back() != goals[i]) {
      ThrowInvalid(Cell(PathField(i, static_cast<int>(horizon - 1)), path.back()) + " is not robots[" +
                   std::to_string(i) + "].goal's cell " + std::to_string(goals[i]));
    }
  }
  std::vector<int> at(lattice.num_cells(), -1), stamp(lattice.num_cells(), -1);
  for (std::size_t t = 0; t < horizon; ++t) {
    for (int i = 0; i < n; ++i) {
      const GridCell c = request.paths[i][t];
      if (stamp[c] == static_cast<int>(t)) {
        ThrowInvalid(Cell(PathField(i, static_cast<int>(t)), c) + ": robots " + std::to_string(at[c]) + " and " +
                     std::to_string(i) + " are both in that cell at step " + std::to_string(t));
      }
      stamp[c] = static_cast<int>(t);
      at[c] = i;
    }
    if (t + 1 == horizon) break;
    for (int i = 0; i < n; ++i) {
      const GridCell a = request.paths[i][t], b = request.paths[i][t + 1];
      if (a == b || stamp[b] != static_cast<int>(t)) continue;
      const int j = at[b];
      if (j != i && request.paths[j][t + 1] == a) {
        ThrowInvalid(PathField(i, static_cast<int>(t)) + ": robots " + std::to_string(i) + " and " + std::to_string(j) +
                     " swap cells " + std::to_string(a) + " and " + std::to_string(b) + " between steps " +
                     std::to_string(t) + " and " + std::to_string(t + 1));
      }
    }
  }
}

}  // namespace

double FleetResolution(const std::vector<double>& radii, double padding) {
  if (radii.empty()) ThrowInvalid("radii is empty: a fleet needs at least one robot");
  if (!(padding >= 0.0) || !std::isfinite(padding)) {
    ThrowInvalid("padding = " + FormatNumber(padding) + " must be >= 0 and finite");
  }
  double first = 0.0, second = 0.0;
  for (std::size_t i = 0; i < radii.size(); ++i) {
    const double r = radii[i];
    if (!(r > 0.0) || !std::isfinite(r)) {
      ThrowInvalid("radii[" + std::to_string(i) + "] = " + FormatNumber(r) + " must be > 0 and finite");
    }
    if (r > first) {
      second = first;
      first = r;
    } else if (r > second) {
      second = r;
    }
  }
  return first + (radii.size() == 1 ? first : second) + padding;
}

FleetLatticeChoice ChooseFleetLattice(const std::vector<std::shared_ptr<const RobotModel>>& robots,
                                      const Eigen::Vector2d& anchor, const Scene& scene, const std::string& scene_id,
                                      double resolution, double padding, FleetLatticeCache* cache,
                                      const std::string& resolution_field, const std::string& padding_field) {
  std::vector<Footprint> feet;
  std::vector<double> radii;
  for (const auto& robot : robots) {
    feet.push_back(PlanarFootprint(*robot));
    radii.push_back(feet.back().radius);
  }
  const double safe = FleetResolution(radii, padding);
  FleetLatticeChoice out;
  out.radii = radii;
  out.spacing = resolution > 0.0 ? resolution : safe;
  if (out.spacing < safe) {
    ThrowInvalid(resolution_field + " = " + FormatNumber(resolution) +
                 " m is below the smallest spacing that keeps these robots apart, " + FormatNumber(safe) +
                 " m (the two largest footprint radii plus " + padding_field + " " + FormatNumber(padding) + " m)");
  }
  FleetLatticeRequest request;
  request.anchor = anchor;
  request.spacing = out.spacing;
  std::tie(request.lower, request.upper) = FleetBounds(robots);
  request.footprint = CoverFootprints(feet);
  out.footprint = request.footprint;
  const auto started = std::chrono::steady_clock::now();
  if (cache != nullptr && !scene_id.empty()) {
    out.lattice = cache->GetOrBuild(scene_id, scene, request, &out.cached);
  } else {
    out.lattice = std::make_shared<const FleetLattice>(BuildFleetLattice(scene, request));
  }
  out.seconds = out.cached ? 0.0 : std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  return out;
}

FleetSchedule ScheduleFleet(const FleetScheduleRequest& request) {
  const LatticeGeometry& lattice = request.lattice;
  if (lattice.width <= 0 || lattice.height <= 0 || !(lattice.spacing > 0.0) || !std::isfinite(lattice.spacing) ||
      !lattice.origin.allFinite()) {
    ThrowInvalid("lattice: " + std::to_string(lattice.width) + " x " + std::to_string(lattice.height) +
                 " nodes with spacing " + FormatNumber(lattice.spacing) +
                 " m must have width, height and spacing > 0 and a finite origin");
  }
  if (request.free_space != nullptr) {
    const LatticeGeometry& own = request.free_space->geometry();
    if (own.width != lattice.width || own.height != lattice.height || own.spacing != lattice.spacing ||
        own.origin != lattice.origin) {
      ThrowInvalid("free_space is a lattice of other nodes than lattice (its geometry() must be the same)");
    }
  }
  const int n = static_cast<int>(request.robots.size());
  if (n == 0) ThrowInvalid("robots is empty");
  std::vector<GridCell> starts(n), goals(n);
  for (int i = 0; i < n; ++i) {
    const FleetRobot& robot = request.robots[i];
    ValidateRobot(robot, i);
    const std::string field = "robots[" + std::to_string(i) + "]";
    starts[i] = lattice.NodeAt(robot.start.head<2>(), field + ".start");
    goals[i] = lattice.NodeAt(robot.goal.head<2>(), field + ".goal");
  }
  ValidatePlan(request, starts, goals);
  const auto& paths = request.paths;
  const int horizon = static_cast<int>(paths[0].size());

  // Moves, and which move each (robot, step) is.
  std::vector<std::vector<Move>> moves(n);
  std::vector<std::vector<int>> move_at(n, std::vector<int>(horizon, -1));
  FleetSchedule schedule;
  for (int i = 0; i < n; ++i) {
    for (int t = 0; t + 1 < horizon; ++t) {
      if (paths[i][t] == paths[i][t + 1]) continue;
      Move move;
      move.step = t;
      move.from = paths[i][t];
      move.to = paths[i][t + 1];
      move.direction = Direction(lattice, move.from, move.to);
      move_at[i][t] = static_cast<int>(moves[i].size());
      moves[i].push_back(std::move(move));
      schedule.discrete_makespan = std::max(schedule.discrete_makespan, t + 1);
    }
  }

  // Visits (robot, first step, last step) of every cell in step order; the entry of each visit
  // waits for the exit of the previous visit by another robot.
  struct Visit {
    GridCell cell;
    int first, last, robot;
  };
  std::vector<Visit> visits;
  for (int i = 0; i < n; ++i) {
    for (int t = 0; t < horizon;) {
      int last = t;
      while (last + 1 < horizon && paths[i][last + 1] == paths[i][t]) ++last;
      visits.push_back({paths[i][t], t, last, i});
      t = last + 1;
    }
  }
  std::sort(visits.begin(), visits.end(),
            [](const Visit& a, const Visit& b) { return std::tie(a.cell, a.first) < std::tie(b.cell, b.first); });
  for (std::size_t k = 1; k < visits.size(); ++k) {
    const Visit& before = visits[k - 1];
    const Visit& after = visits[k];
    if (before.cell != after.cell || before.robot == after.robot) continue;
    moves[after.robot][move_at[after.robot][after.first - 1]].waits_for.emplace_back(before.robot, before.last);
  }
  // A dependency on robot j's move b is implied when an earlier move of the same robot already
  // waits for a move b' >= b of j (j completes b before b', the robot starts this move after
  // that one): drop it, so the list is shorter and runs are split less.
  std::vector<int> waited(n, -1);
  for (int i = 0; i < n; ++i) {
    std::fill(waited.begin(), waited.end(), -1);
    for (Move& move : moves[i]) {
      std::vector<std::pair<int, int>> kept;
      for (const auto& [j, b] : move.waits_for) {
        if (b > waited[j]) kept.emplace_back(j, b);
      }
      for (const auto& [j, b] : kept) {
        waited[j] = std::max(waited[j], b);
        const Eigen::Vector2d node = lattice.Position(move.to);
        schedule.dependencies.push_back({i, move.step, j, b, move.to, node.x(), node.y()});
      }
      move.waits_for = std::move(kept);
    }
  }
  std::sort(schedule.dependencies.begin(), schedule.dependencies.end(),
            [](const FleetDependency& a, const FleetDependency& b) {
              return std::tie(a.robot, a.step, a.waits_for_robot) < std::tie(b.robot, b.step, b.waits_for_robot);
            });

  // Runs: consecutive moves in one direction, split before a move that waits for another robot.
  std::vector<Run> runs;
  std::vector<std::vector<int>> robot_runs(n);
  for (int i = 0; i < n; ++i) {
    for (int m = 0; m < static_cast<int>(moves[i].size()); ++m) {
      Move& move = moves[i][m];
      const bool extends = m > 0 && moves[i][m - 1].direction == move.direction && move.waits_for.empty();
      if (!extends) {
        Run run;
        run.robot = i;
        run.first = m;
        robot_runs[i].push_back(static_cast<int>(runs.size()));
        runs.push_back(std::move(run));
      }
      Run& run = runs.back();
      run.last = m;
      move.run = static_cast<int>(runs.size()) - 1;
      move.index_in_run = m - run.first + 1;
    }
  }

  // Geometry and profile of every run: from the exact start (first run) or a node, to the
  // exact goal (last run) or a node.
  for (int i = 0; i < n; ++i) {
    const FleetRobot& robot = request.robots[i];
    for (std::size_t k = 0; k < robot_runs[i].size(); ++k) {
      Run& run = runs[robot_runs[i][k]];
      run.from = k == 0 ? Eigen::Vector2d(robot.start.head<2>()) : lattice.Position(moves[i][run.first].from);
      run.to = k + 1 == robot_runs[i].size() ? Eigen::Vector2d(robot.goal.head<2>()) : lattice.Position(moves[i][run.last].to);
      const Eigen::Vector2d delta = run.to - run.from;
      const double length = delta.norm();
      const Eigen::Vector3d unit(delta.x() / length, delta.y() / length, 0.0);
      run.profile = Profile(length, AlongLimit(unit, robot.max_velocity), AlongLimit(unit, robot.max_acceleration));
      for (int m = run.first; m <= run.last; ++m) {
        const double along = m == run.last ? length : (lattice.Position(moves[i][m].to) - run.from).dot(unit.head<2>());
        run.reach.push_back(std::clamp(along, 0.0, length));
      }
    }
  }

  // Order the runs (Kahn) and time each as soon as its predecessors allow.
  const int num_runs = static_cast<int>(runs.size());
  std::vector<std::vector<int>> successors(num_runs);
  std::vector<std::vector<int>> predecessors(num_runs);
  std::vector<int> pending(num_runs, 0);
  const auto link = [&](int from, int to) {
    successors[from].push_back(to);
    predecessors[to].push_back(from);
    ++pending[to];
  };
  for (int r = 0; r < num_runs; ++r) {
    const Run& run = runs[r];
    if (run.first > 0) link(moves[run.robot][run.first - 1].run, r);
    for (const auto& [j, step] : moves[run.robot][run.first].waits_for) link(moves[j][move_at[j][step]].run, r);
  }
  const auto completion = [&](int robot, int step) {
    const Move& move = moves[robot][move_at[robot][step]];
    const Run& run = runs[move.run];
    return run.start + run.profile.TimeAt(run.reach[move.index_in_run - 1]);
  };
  std::queue<int> ready;
  for (int r = 0; r < num_runs; ++r) {
    if (pending[r] == 0) ready.push(r);
  }
  int timed = 0;
  std::vector<char> done(num_runs, 0);
  while (!ready.empty()) {
    const int r = ready.front();
    ready.pop();
    Run& run = runs[r];
    double start = request.robots[run.robot].release_time;
    if (run.first > 0) {
      const Run& previous = runs[moves[run.robot][run.first - 1].run];
      start = std::max(start, previous.start + previous.profile.duration);
    }
    for (const auto& [j, step] : moves[run.robot][run.first].waits_for) start = std::max(start, completion(j, step));
    run.start = start;
    done[r] = 1;
    ++timed;
    for (const int next : successors[r]) {
      if (--pending[next] == 0) ready.push(next);
    }
  }
  if (timed < num_runs) {
    // The runs left wait on each other round a cycle: walk predecessors until one repeats.
    int r = 0;
    while (done[r] != 0) ++r;
    std::vector<int> seen(num_runs, -1);
    std::vector<int> walk;
    while (seen[r] < 0) {
      seen[r] = static_cast<int>(walk.size());
      walk.push_back(r);
      for (const int p : predecessors[r]) {
        if (done[p] == 0) {
          r = p;
          break;
        }
      }
    }
    std::string robots;
    for (std::size_t k = seen[r]; k < walk.size(); ++k) {
      const Run& run = runs[walk[k]];
      robots += (robots.empty() ? "" : ", ") + std::to_string(run.robot) + " (step " +
                std::to_string(moves[run.robot][run.first].step) + ")";
    }
    ThrowInvalid("paths: robots " + robots +
                 " each enter the cell the next one leaves at the same step, round a cycle (a rotation "
                 "cycle); following is allowed only along acyclic chains");
  }

  // Trajectories.
  schedule.robots.resize(n);
  for (int i = 0; i < n; ++i) {
    const FleetRobot& robot = request.robots[i];
    FleetRobotSchedule& out = schedule.robots[i];
    std::vector<TimedTrajectory::Piece> pieces;
    double t = 0.0;
    Eigen::VectorXd at(3);
    at << robot.start.x(), robot.start.y(), robot.start.z();
    const auto hold_until = [&](double until) {
      if (until > t) {
        pieces.push_back(LinePiece(t, until - t, at, Eigen::VectorXd::Zero(3), 0.0, 0.0, 0.0));
        t = until;
      }
    };
    double moving = 0.0;
    for (const int r : robot_runs[i]) {
      const Run& run = runs[r];
      hold_until(run.start);
      Eigen::VectorXd origin(3), unit(3);
      origin << run.from.x(), run.from.y(), robot.start.z();
      const Eigen::Vector2d delta = (run.to - run.from) / run.profile.length;
      unit << delta.x(), delta.y(), 0.0;
      run.profile.AppendPieces(run.start, origin, unit, &pieces);
      t = run.start + run.profile.duration;
      moving += run.profile.duration;
      at << run.to.x(), run.to.y(), robot.start.z();
      out.runs.push_back({moves[i][run.first].step, moves[i][run.last].step, moves[i][run.first].from,
                          moves[i][run.last].to, run.start, t});
    }
    const double turn = robot.goal.z() - robot.start.z();
    const Eigen::Vector2d settle = robot.goal.head<2>() - robot.start.head<2>();
    if (robot_runs[i].empty() && (settle.norm() > 0.0 || turn != 0.0)) hold_until(robot.release_time);
    if (robot_runs[i].empty() && settle.norm() > 0.0) {
      // Start and goal on one node but not at one point (within the node tolerance): close the gap.
      const Eigen::Vector3d unit(settle.x() / settle.norm(), settle.y() / settle.norm(), 0.0);
      const Profile profile(settle.norm(), AlongLimit(unit, robot.max_velocity), AlongLimit(unit, robot.max_acceleration));
      profile.AppendPieces(t, at, Eigen::VectorXd(unit), &pieces);
      t += profile.duration;
      moving += profile.duration;
    }
    out.arrival_time = robot_runs[i].empty() && settle.norm() == 0.0 ? 0.0 : t;
    out.wait_time = out.arrival_time == 0.0 ? 0.0 : out.arrival_time - robot.release_time - moving;
    at.head<2>() = robot.goal.head<2>();
    if (turn != 0.0) {
      const Profile profile(std::abs(turn), robot.max_velocity.z(), robot.max_acceleration.z());
      Eigen::VectorXd axis = Eigen::VectorXd::Zero(3);
      axis[2] = turn > 0.0 ? 1.0 : -1.0;
      profile.AppendPieces(t, at, axis, &pieces);
      t += profile.duration;
    }
    if (pieces.empty()) pieces.push_back(LinePiece(0.0, 0.0, at, Eigen::VectorXd::Zero(3), 0.0, 0.0, 0.0));
    out.finish_time = t;
    Eigen::VectorXd end(3);
    end << robot.goal.x(), robot.goal.y(), robot.goal.z();
    out.trajectory = TimedTrajectory(std::move(pieces), end);
    schedule.makespan = std::max(schedule.makespan, t);
  }
  return schedule;
}

}  // namespace chasles
