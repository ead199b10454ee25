#pragma once
/// \file
/// `chasles-bench --section fleet`: the grid MAPF solver (planners/multi grid_mapf.h) on maps in
/// the MAPF benchmark's style — random 32 × 32 with 20 % blocked, rooms 32 × 32 (3 × 3 rooms),
/// warehouse 161 × 63 — against the number of robots: success, time to the first plan and to
/// the end of refinement, and the sum of costs over the sum of the robots' shortest distances.
/// Every plan is re-checked by CheckMapfPlan.

#include <cstdint>
#include <string>
#include <vector>

namespace chasles {

/// bench_main fills the first two (--runs, --seed) by position: keep them first.
struct FleetBenchOptions {
  int runs = 5;               ///< seeded scenarios per map and robot count
  std::uint64_t seed = 1;     ///< the maps' seed; scenario r uses seed + r
  double budget = 10.0;       ///< [s] per solve (first plan and refinement together)
  double refine_budget = 0.3; ///< [s] MapfOptions::refine_budget
  std::vector<int> robots = {2, 4, 8, 16, 32, 50, 100, 200, 300, 500};  ///< where at most half the free cells
};

/// Prints one markdown table per map to stdout.
void BenchFleet(const FleetBenchOptions& options);

/// `chasles-bench --section fleet_coordinate`: Coordinate() end to end (validation, pair checks,
/// lattice from the scene's boxes, search, schedule, verification; no gRPC) for disc bases
/// (0.4 m radius, 1 m/s, 1 m lattice) on the same maps, AUTO (which picks FLEET) beside
/// PRIORITIZED on small teams in the same run. Medians over `runs` scenarios; writes an SVG plot
/// of time against robots to `svg` when not empty.
void BenchFleetCoordinate(const FleetBenchOptions& options, const std::string& svg);

}  // namespace chasles
