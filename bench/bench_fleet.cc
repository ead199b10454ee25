// `chasles-bench --section fleet`: SolveMapf on three benchmark-style maps against the number of
// robots. Per map and robot count, `runs` random scenarios (RandomScenario, seeds seed + r); each
// is solved twice with the same solver seed: once without refinement (the first plan: its time
// and cost) and once with (the final plan). Both runs find the same first plan (the solver is
// deterministic), so their first-plan times agree within timing noise. A plan that
// CheckMapfPlan rejects is counted as such, never as solved.

#include "bench_fleet.h"

#include <algorithm>
#include <chrono>
#include <ctime>
#include <cstdio>
#include <string>
#include <vector>

#include "bench_pipeline.h"  // QuantileOrNan
#include "chasles/multi/grid_mapf.h"

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
