// `chasles-bench --section fleet`: SolveMapf on three benchmark-style maps against the number of
// robots. Per map and robot count, `runs` random scenarios (RandomScenario, seeds seed + r); each
// is solved twice with the same solver seed: once without refinement (the first plan: its time
// and cost) and once with (the final plan). Both runs find the same first plan (the solver is
// deterministic), so their first-plan times agree within timing noise. A plan that
// CheckMapfPlan rejects is counted as such, never as solved.

#include "bench_fleet.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <ctime>
#include <cstdio>
#include <string>
#include <vector>

#include "bench_pipeline.h"  // QuantileOrNan
#include "chasles/multi/coordinator.h"
#include "chasles/multi/grid_mapf.h"
#include "chasles/robot/mobile.h"

namespace chasles {
namespace {

struct FleetMap {
  std::string name;
  GridMap map;
};

int FreeCells(const GridMap& map) {
  return static_cast<int>(std::count(map.blocked.begin(), map.blocked.end(), 0));
}

}  // namespace

void BenchFleet(const FleetBenchOptions& options) {
  const std::vector<FleetMap> maps = {
      {"random 32×32, 20 % blocked (like random-32-32-20)", RandomGridMap(32, 32, 0.2, options.seed)},
      {"rooms 32×32, 3×3 rooms (like room-32-32-4)", RoomsGridMap(32, 32, 3, options.seed)},
      {"warehouse 161×63 (like warehouse-10-20-10-2-1)", WarehouseGridMap(161, 63)},
  };
  std::printf("\n## Grid MAPF (LaCAM* with PIBT, no swaps, no rotation cycles)\n\n");
  std::printf("%d scenarios per row (seeds %llu..%llu), %.3g s budget per solve, refinement budget %.3g s. "
              "'first' = without refinement, 'final' = with it; times are medians (max in brackets) over the "
              "solved runs; 'first CPU' is the process CPU time of the first-plan solve, apart from the machine's load; "
              "SOC / LB = sum of costs over the sum of shortest distances (median). Invalid = plans CheckMapfPlan "
              "rejected.\n",
              options.runs, static_cast<unsigned long long>(options.seed),
              static_cast<unsigned long long>(options.seed + options.runs - 1), options.budget,
              options.refine_budget);
  for (const FleetMap& m : maps) {
    const int free = FreeCells(m.map);
    std::printf("\n### %s, %d free cells\n\n", m.name.c_str(), free);
    std::printf("| robots | solved | invalid | first [s] | first CPU [s] | final [s] | SOC / LB first | SOC / LB final | "
                "makespan final | refinement neighbourhoods |\n");
    std::printf("|---|---|---|---|---|---|---|---|---|---|\n");
    for (int robots : options.robots) {
      if (2 * robots > free) continue;
      int solved = 0, invalid = 0;
      std::vector<double> first_seconds, first_cpu, final_seconds, first_ratio, final_ratio, makespan, nodes;
      for (int r = 0; r < options.runs; ++r) {
        std::vector<GridCell> starts, goals;
        RandomScenario(m.map, robots, options.seed + static_cast<std::uint64_t>(r), &starts, &goals);
        MapfOptions first_options;
        first_options.seed = options.seed + static_cast<std::uint64_t>(r);
        first_options.refine = false;
        MapfOptions final_options = first_options;
        final_options.refine = true;
        final_options.refine_budget = options.refine_budget;
        const auto budget = std::chrono::duration<double>(options.budget);
        const std::clock_t cpu_began = std::clock();
        const MapfResult first = SolveMapf(m.map, starts, goals, first_options, Termination::After(budget));
        const double cpu = static_cast<double>(std::clock() - cpu_began) / CLOCKS_PER_SEC;
        const MapfResult last = SolveMapf(m.map, starts, goals, final_options, Termination::After(budget));
        if (!first.solved || !last.solved) continue;
        if (!CheckMapfPlan(m.map, starts, goals, first.paths).empty() ||
            !CheckMapfPlan(m.map, starts, goals, last.paths).empty()) {
          ++invalid;
          continue;
        }
        ++solved;
        const double lower = static_cast<double>(std::max<std::int64_t>(1, first.sum_of_lower_bounds));
        first_seconds.push_back(first.seconds);
        first_cpu.push_back(cpu);
        final_seconds.push_back(last.seconds);
        first_ratio.push_back(static_cast<double>(first.sum_of_costs) / lower);
        final_ratio.push_back(static_cast<double>(last.sum_of_costs) / lower);
        makespan.push_back(last.makespan);
        nodes.push_back(static_cast<double>(last.refine_iterations));
      }
      const auto max_of = [](const std::vector<double>& v) {
        return v.empty() ? QuantileOrNan(v, 1.0) : *std::max_element(v.begin(), v.end());
      };
      std::printf("| %d | %d/%d | %d | %.3f (%.3f) | %.3f (%.3f) | %.3f (%.3f) | %.3f | %.3f | %.0f | %.0f |\n", robots,
                  solved, options.runs, invalid, QuantileOrNan(first_seconds, 0.5), max_of(first_seconds),
                  QuantileOrNan(first_cpu, 0.5), max_of(first_cpu),
                  QuantileOrNan(final_seconds, 0.5), max_of(final_seconds), QuantileOrNan(first_ratio, 0.5),
                  QuantileOrNan(final_ratio, 0.5), QuantileOrNan(makespan, 0.5), QuantileOrNan(nodes, 0.5));
      std::fflush(stdout);
    }
  }
}

}  // namespace chasles

namespace chasles {
namespace {

std::shared_ptr<const RobotModel> DiscBase(double width, double height) {
  MobileDescription mobile;
  mobile.name = "disc_base";
  mobile.kind = RobotKind::kPlanar;
  mobile.workspace_min = Eigen::Vector3d(0, 0, 0);
  mobile.workspace_max = Eigen::Vector3d(width, height, 0);
  mobile.linear_velocity = 1.0;
  mobile.angular_velocity = 1.0;
  mobile.body.collision.push_back(Shape::Sphere(0.4, Eigen::Isometry3d(Eigen::Translation3d(0, 0, 0.4))));
  return RobotFromMobile(mobile);
}

/// Blocked cell (x, y) as the box [x, x+1] × [y, y+1] × [0, 1].
std::shared_ptr<const Scene> BoxesOf(const GridMap& map) {
  auto scene = std::make_shared<Scene>();
  for (int y = 0; y < map.height; ++y) {
    for (int x = 0; x < map.width; ++x) {
      if (map.blocked[static_cast<std::size_t>(y * map.width + x)] == 0) continue;
      scene->AddObject(SceneObject{"c" + std::to_string(x) + "_" + std::to_string(y),
                                   Shape::Box(Eigen::Vector3d(1, 1, 1), Eigen::Isometry3d(Eigen::Translation3d(x + 0.5, y + 0.5, 0.5)))});
    }
  }
  return scene;
}

struct Row {
  std::string map;
  int robots = 0;
  std::string method;
  int runs = 0, solved = 0;
  double seconds = 0.0, max_seconds = 0.0, soc_ratio = 0.0, makespan = 0.0;
  double lattice = 0.0, search = 0.0, schedule = 0.0;  ///< FLEET's stages, medians [s]
};

}  // namespace

void BenchFleetCoordinate(const FleetBenchOptions& options, const std::string& svg) {
  PlannerRegistry registry;
  RegisterDefaultPlanners(&registry);
  struct Case {
    std::string name;
    GridMap map;
    std::vector<int> robots;
  };
  const std::vector<Case> cases = {
      {"random 32×32", RandomGridMap(32, 32, 0.2, options.seed), {2, 4, 8, 16, 50, 100, 200}},
      {"rooms 32×32", RoomsGridMap(32, 32, 3, options.seed), {2, 4, 8, 16, 50, 100}},
      {"warehouse 161×63", WarehouseGridMap(161, 63), {50, 200, 500}},
  };
  std::printf("\n## Coordinate with FLEET (AUTO) beside PRIORITIZED, same run\n\n");
  std::printf("Disc bases (0.4 m radius, 1 m/s, 2 m/s²) at cell centres of 1 m cells, blocked cells as boxes, "
              "fleet_resolution 1 m; %d scenarios per row; Coordinate() in process (no gRPC): validation, pair "
              "checks, lattice (built per request: no cache), search with 0.3 s refinement, schedule, "
              "verification. Time: median (max). SOC / LB: the discrete plan's sum of costs over the sum of "
              "shortest distances. PRIORITIZED: 10 s budget, teams of up to 8.\n\n",
              options.runs);
  std::printf("| map | robots | method | solved | time [s] | lattice / search / schedule [s] | SOC / LB | makespan [s] |\n"
              "|---|---|---|---|---|---|---|---|\n");
  std::vector<Row> rows;
  for (const Case& c : cases) {
    const auto model = DiscBase(c.map.width, c.map.height);
    const auto scene = BoxesOf(c.map);
    for (int robots : c.robots) {
      for (CoordinationMethod method : {CoordinationMethod::kAuto, CoordinationMethod::kPrioritized}) {
        if (method == CoordinationMethod::kPrioritized && robots > 8) continue;
        Row row;
        row.map = c.name;
        row.robots = robots;
        row.method = method == CoordinationMethod::kAuto ? "AUTO (fleet)" : "PRIORITIZED";
        std::vector<double> seconds, ratios, makespans, lattice, search, schedule;
        for (int r = 0; r < options.runs; ++r) {
          std::vector<GridCell> starts, goals;
          RandomScenario(c.map, robots, options.seed + static_cast<std::uint64_t>(r), &starts, &goals);
          CoordinationQuery query;
          query.scene = scene;
          query.method = method;
          query.fleet_resolution = 1.0;
          query.time_budget = method == CoordinationMethod::kAuto ? 30.0 : 10.0;
          query.seed = options.seed + static_cast<std::uint64_t>(r);
          query.knots_replace_samples = true;
          for (int k = 0; k < robots; ++k) {
            TeamRobotSpec spec;
            spec.placement.name = "r" + std::to_string(k);
            spec.placement.model = model;
            const GridCell s = starts[static_cast<std::size_t>(k)], g = goals[static_cast<std::size_t>(k)];
            spec.start = Eigen::Vector3d(s % c.map.width + 0.5, s / c.map.width + 0.5, 0.0);
            spec.goal = Eigen::Vector3d(g % c.map.width + 0.5, g / c.map.width + 0.5, 0.0);
            query.robots.push_back(spec);
          }
          const auto t0 = std::chrono::steady_clock::now();
          const CoordinationOutcome outcome = Coordinate(query, registry, Termination());
          const double took = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
          ++row.runs;
          if (outcome.code != CoordinationCode::kSuccess) continue;
          ++row.solved;
          seconds.push_back(took);
          makespans.push_back(outcome.makespan);
          if (outcome.fleet) {
            lattice.push_back(outcome.fleet->lattice_seconds);
            search.push_back(outcome.fleet->search_seconds);
            schedule.push_back(outcome.fleet->schedule_seconds);
          }
          if (outcome.fleet && outcome.fleet->sum_of_lower_bounds > 0) {
            ratios.push_back(static_cast<double>(outcome.fleet->sum_of_costs) / outcome.fleet->sum_of_lower_bounds);
          }
        }
        row.seconds = QuantileOrNan(seconds, 0.5);
        row.max_seconds = QuantileOrNan(seconds, 1.0);
        row.soc_ratio = QuantileOrNan(ratios, 0.5);
        row.makespan = QuantileOrNan(makespans, 0.5);
        row.lattice = QuantileOrNan(lattice, 0.5);
        row.search = QuantileOrNan(search, 0.5);
        row.schedule = QuantileOrNan(schedule, 0.5);
        std::printf("| %s | %d | %s | %d/%d | %.3f (%.3f) | %.3f / %.3f / %.4f | %.3f | %.1f |\n", row.map.c_str(), robots,
                    row.method.c_str(), row.solved, row.runs, row.seconds, row.max_seconds, row.lattice, row.search,
                    row.schedule, row.soc_ratio, row.makespan);
        std::fflush(stdout);
        rows.push_back(row);
      }
    }
  }
  if (svg.empty()) return;
  // Time against robots, log–log, one polyline per map and method.
  std::FILE* out = std::fopen(svg.c_str(), "w");
  if (out == nullptr) {
    std::printf("cannot write %s\n", svg.c_str());
    return;
  }
  const double w = 640, h = 400, left = 60, bottom = 40;
  const auto x_of = [&](double robots) { return left + (w - left - 20) * std::log10(robots / 2.0) / std::log10(250.0); };
  const auto y_of = [&](double s) { return h - bottom - (h - bottom - 20) * (std::log10(std::max(s, 1e-3)) + 3.0) / 5.0; };
  std::fprintf(out, "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%.0f\" height=\"%.0f\" font-family=\"sans-serif\" "
               "font-size=\"11\">\n<rect width=\"100%%\" height=\"100%%\" fill=\"white\"/>\n", w, h);
  for (double s : {1e-3, 1e-2, 1e-1, 1.0, 10.0, 100.0}) {
    std::fprintf(out, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#ddd\"/><text x=\"4\" y=\"%.1f\">%g s</text>\n",
                 left, y_of(s), w - 20, y_of(s), y_of(s) + 4, s);
  }
  for (int robots : {2, 4, 8, 16, 50, 100, 200, 500}) {
    std::fprintf(out, "<text x=\"%.1f\" y=\"%.1f\">%d</text>\n", x_of(robots) - 6, h - bottom + 16, robots);
  }
  std::fprintf(out, "<text x=\"%.1f\" y=\"%.1f\">robots (log)</text>\n", w / 2 - 30, h - 6);
  const char* colours[] = {"#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b"};
  int series = 0;
  for (const Case& c : cases) {
    for (const char* method : {"AUTO (fleet)", "PRIORITIZED"}) {
      std::string points;
      for (const Row& row : rows) {
        if (row.map != c.name || row.method != method || row.solved == 0) continue;
        points += std::to_string(x_of(row.robots)) + "," + std::to_string(y_of(row.seconds)) + " ";
      }
      if (points.empty()) continue;
      const char* colour = colours[series % 6];
      std::fprintf(out, "<polyline fill=\"none\" stroke=\"%s\" stroke-width=\"2\"%s points=\"%s\"/>\n", colour,
                   std::string(method) == "PRIORITIZED" ? " stroke-dasharray=\"5,3\"" : "", points.c_str());
      std::fprintf(out, "<text x=\"%.1f\" y=\"%.1f\" fill=\"%s\">%s, %s</text>\n", left + 10, 20.0 + 14 * series, colour,
                   c.name.c_str(), method);
      ++series;
    }
  }
  std::fprintf(out, "</svg>\n");
  std::fclose(out);
  std::printf("\nplot: %s\n", svg.c_str());
}

}  // namespace chasles
