// `chasles-bench --section fleet_lattice`: how long a fleet lattice takes to build — 160 x 60 nodes,
// spacing 0.65 m (two 0.3 m robots and 5 cm of padding), footprint 0.3 m over 0–0.5 m — over
// a warehouse floor of N seeded boxes (0.1–0.5 m, any yaw, 0–1 m high) spread over the lattice's
// 104 x 39 m, and how long a straight-line fleet plan on it takes to schedule.

#include "bench_fleet_lattice.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "chasles/collision/scene.h"
#include "chasles/multi/fleet.h"
#include "chasles/multi/fleet_lattice.h"

namespace chasles {
namespace {

using Clock = std::chrono::steady_clock;

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

Scene Warehouse(int boxes, double width, double depth) {
  std::mt19937_64 rng(160);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Scene scene;
  for (int k = 0; k < boxes; ++k) {
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.linear() = Eigen::AngleAxisd(M_PI * u(rng), Eigen::Vector3d::UnitZ()).toRotationMatrix();
    pose.translation() = Eigen::Vector3d(width * u(rng), depth * u(rng), 0.5);
    scene.AddObject({"box" + std::to_string(k), Shape::Box(Eigen::Vector3d(0.1 + 0.4 * u(rng), 0.1 + 0.4 * u(rng), 1.0), pose)});
  }
  return scene;
}

}  // namespace

void BenchFleetLattice(const FleetLatticeBenchOptions& options) {
  const double s = FleetResolution({0.3, 0.3}, 0.05);
  FleetLatticeRequest request;
  request.spacing = s;
  request.lower = Eigen::Vector2d(0, 0);
  request.upper = Eigen::Vector2d(159 * s, 59 * s) + Eigen::Vector2d::Constant(1e-9);
  request.footprint = {0.3, 0.0, 0.5};
  std::printf("\n## Fleet lattice: 160 x 60 nodes, spacing %.2f m, footprint 0.3 m (%d builds)\n\n", s,
              options.repeats);
  std::printf("| boxes | free nodes | edge checks | blocked edges between free nodes | median [ms] | min | max |\n"
              "|---|---|---|---|---|---|---|\n");
  for (const int boxes : options.boxes) {
    const Scene scene = Warehouse(boxes, 159 * s, 59 * s);
    std::vector<double> ms;
    FleetLatticeStats stats;
    std::size_t free_nodes = 0, blocked_edges = 0;
    for (int r = 0; r < options.repeats; ++r) {
      const auto started = Clock::now();
      const FleetLattice lattice = BuildFleetLattice(scene, request, &stats);
      ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - started).count());
      free_nodes = std::count(lattice.map().blocked.begin(), lattice.map().blocked.end(), 0);
      blocked_edges = lattice.blocked_edges().size();
    }
    std::printf("| %d | %zu | %zu | %zu | %.1f | %.1f | %.1f |\n", boxes, free_nodes, stats.edge_checks, blocked_edges,
                Median(ms), *std::min_element(ms.begin(), ms.end()), *std::max_element(ms.begin(), ms.end()));
  }

  // Scheduling: one robot per row crosses its row east (159 moves, one run each), then turns.
  FleetScheduleRequest plan;
  plan.lattice = BuildFleetLattice(Scene(), request).geometry();
  for (int row = 0; row < 60; ++row) {
    std::vector<GridCell> path;
    for (int x = 0; x < 160; ++x) path.push_back(row * 160 + x);
    FleetRobot robot;
    robot.start << plan.lattice.Position(path.front()), 0.0;
    robot.goal << plan.lattice.Position(path.back()), 1.0;
    plan.robots.push_back(robot);
    plan.paths.push_back(path);
  }
  std::vector<double> ms;
  double makespan = 0.0;
  for (int r = 0; r < options.repeats; ++r) {
    const auto started = Clock::now();
    makespan = ScheduleFleet(plan).makespan;
    ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - started).count());
  }
  std::printf("\nScheduleFleet, 60 robots x 159 moves on it: median %.1f ms (makespan %.1f s)\n", Median(ms), makespan);
}

}  // namespace chasles
