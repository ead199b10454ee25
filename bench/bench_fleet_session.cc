// `chasles-bench --section fleet_session`: a fleet in the warehouse of the fleet benchmark (160 x 60
// nodes, shelf rows of 10 with aisles of 2, spacing 1 m, robots at 1 m/s and 1 m/s²) serves a
// stream of goals: each goes to the robot that is idle first, every fourth to a random robot still
// on its way, at a node no robot is bound for (as a dispatcher assigns them). A goal a robot
// bound for a node on every way makes impossible is retried once every robot is idle. Reported:
// the time to answer one goal (FleetSession::Assign: search, robots moved aside, orders) against
// one whole-fleet replan by SolveMapf (first plan, no refinement) for the same number of robots.

#include "bench_fleet_session.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>
#include <random>
#include <vector>

#include "chasles/multi/fleet_session.h"
#include "chasles/multi/grid_mapf.h"

namespace chasles {
namespace {

using Clock = std::chrono::steady_clock;

double Quantile(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  const std::size_t k = std::min(v.size() - 1, static_cast<std::size_t>(q * static_cast<double>(v.size() - 1) + 0.5));
  return v[k];
}

/// The lattice of `map` itself: nodes free where cells are, every edge between two free nodes free.
std::shared_ptr<const FleetLattice> MapLattice(const GridMap& map) {
  LatticeGeometry g;
  g.width = map.width;
  g.height = map.height;
  g.spacing = 1.0;
  std::vector<std::uint8_t> edges(map.blocked.size(), 0x0F);
  return std::make_shared<const FleetLattice>(g, Footprint{0.3, 0.0, 0.5}, std::move(edges), map.blocked);
}

}  // namespace

void BenchFleetSession(const FleetSessionBenchOptions& options) {
  const GridMap map = WarehouseGridMap(160, 60);
  const std::shared_ptr<const FleetLattice> lattice = MapLattice(map);
  const LatticeGeometry& g = lattice->geometry();
  std::vector<GridCell> free_cells;
  for (GridCell c = 0; c < g.num_cells(); ++c) {
    if (lattice->node_free(c)) free_cells.push_back(c);
  }
  std::printf("\n## Fleet session: goals that keep coming (warehouse 160 x 60, %zu free nodes, %d goals per fleet)\n\n",
              free_cells.size(), options.goals);
  std::printf("| robots | goals answered | retried when all idle | idle robots moved aside | goal median [ms] | "
              "p95 [ms] | max [ms] | whole-fleet replan (SolveMapf, first plan) [ms] | goal median / replan | "
              "simulated time [s] | late reports | robots delayed per late report (mean) | late report median [ms] | "
              "p95 [ms] | max [ms] |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  // Each fleet size twice: goals only, then with a robot on its way reported late (where its plan
  // had it 0.5 s before) after every other goal.
  std::vector<std::pair<bool, int>> rows;
  for (const bool late : {false, true}) {
    for (const int n : options.robots) rows.emplace_back(late, n);
  }
  for (const auto& [report_late, n] : rows) {
    std::vector<GridCell> starts, goals;
    RandomScenario(map, n, options.seed, &starts, &goals);
    std::vector<FleetSessionRobot> robots(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) robots[static_cast<std::size_t>(i)].pose.head<2>() = g.Position(starts[static_cast<std::size_t>(i)]);
    FleetSession session(lattice, robots, 0.0);
    std::mt19937_64 rng(options.seed);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    std::vector<double> ms;
    std::vector<GridCell> bound(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) bound[static_cast<std::size_t>(i)] = starts[static_cast<std::size_t>(i)];
    std::vector<char> taken(static_cast<std::size_t>(g.num_cells()), 0);
    for (GridCell c : bound) taken[static_cast<std::size_t>(c)] = 1;
    int answered = 0, retried = 0, moved = 0, delayed = 0;
    std::vector<double> late_ms;  // Report calls [ms]
    double now = 0.0;
    for (int k = 0; k < options.goals; ++k) {
      int robot = 0;
      if (k % 4 == 3) {
        robot = static_cast<int>(unit(rng) * n);
      } else {
        for (int i = 1; i < n; ++i) {
          if (session.plan(i).finish_time < session.plan(robot).finish_time) robot = i;
        }
        now = std::max(now, session.plan(robot).finish_time);
      }
      now += 0.05;
      GridCell cell = free_cells[static_cast<std::size_t>(unit(rng) * free_cells.size())];
      while (taken[static_cast<std::size_t>(cell)]) cell = free_cells[static_cast<std::size_t>(unit(rng) * free_cells.size())];
      const Eigen::Vector2d xy = g.Position(cell);
      FleetGoalOutcome outcome = session.Assign(robot, Eigen::Vector3d(xy.x(), xy.y(), 0.0), now);
      ms.push_back(outcome.seconds * 1e3);
      if (outcome.code != FleetGoalCode::kSuccess) {
        ++retried;
        for (int i = 0; i < n; ++i) now = std::max(now, session.plan(i).finish_time);
        outcome = session.Assign(robot, Eigen::Vector3d(xy.x(), xy.y(), 0.0), now);
        ms.push_back(outcome.seconds * 1e3);
        if (outcome.code != FleetGoalCode::kSuccess) continue;
      }
      ++answered;
      moved += static_cast<int>(outcome.robots.size()) - 1;
      for (int r : outcome.robots) {
        taken[static_cast<std::size_t>(bound[static_cast<std::size_t>(r)])] = 0;
        bound[static_cast<std::size_t>(r)] = g.NodeAt(session.plan(r).trajectory.Evaluate(1e18).q.head<2>(), "end");
        taken[static_cast<std::size_t>(bound[static_cast<std::size_t>(r)])] = 1;
      }
      // After every other goal, a robot on its way reports being where its plan had it 0.5 s
      // before: late (its plan and those ordered after it delayed; their goals stay theirs).
      if (report_late && k % 2 == 0) {
        for (int tries = 0; tries < 20; ++tries) {
          const int r = static_cast<int>(unit(rng) * n);
          const FleetSessionPlan& plan = session.plan(r);
          if (plan.runs.empty() || now - 0.5 <= plan.runs.front().start_time || now >= plan.arrival_time) continue;
          const auto started = Clock::now();
          const FleetStateOutcome late = session.Report(r, session.PoseAt(r, now - 0.5).head<2>(), now, 1e-3);
          late_ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - started).count());
          if (late.status == FleetStateStatus::kLate) delayed += static_cast<int>(late.robots.size()) - 1;
          break;
        }
      }
    }
    // The baseline: one whole-fleet plan for as many robots (first plan, no refinement), 5 runs.
    std::vector<double> replan;
    for (int r = 0; r < 5; ++r) {
      std::vector<GridCell> s, t;
      RandomScenario(map, n, options.seed + 100 + static_cast<std::uint64_t>(r), &s, &t);
      MapfOptions mapf;
      mapf.refine = false;
      const auto started = Clock::now();
      const MapfResult result = SolveMapf(map, s, t, mapf, Termination::After(std::chrono::seconds(30)));
      if (result.solved) replan.push_back(std::chrono::duration<double, std::milli>(Clock::now() - started).count());
    }
    const double median = Quantile(ms, 0.5);
    const double replan_median = replan.empty() ? 0.0 : Quantile(replan, 0.5);
    const bool reported = !late_ms.empty();
    std::printf("| %d | %d/%d | %d | %d | %.2f | %.2f | %.2f | %.0f | %.4f | %.0f | %zu | %.2f | %.3f | %.3f | %.3f |\n", n,
                answered, options.goals, retried, moved, median, Quantile(ms, 0.95), *std::max_element(ms.begin(), ms.end()),
                replan_median, replan_median > 0.0 ? median / replan_median : 0.0, now, late_ms.size(),
                reported ? static_cast<double>(delayed) / late_ms.size() : 0.0, reported ? Quantile(late_ms, 0.5) : 0.0,
                reported ? Quantile(late_ms, 0.95) : 0.0,
                reported ? *std::max_element(late_ms.begin(), late_ms.end()) : 0.0);
  }
}

}  // namespace chasles
