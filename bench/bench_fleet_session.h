#pragma once
/// \file
/// `chasles-bench --section fleet_session`: lifelong operation (multi/fleet_session.h) — goals
/// keep coming to a fleet in a warehouse; how long each new goal takes to answer, beside a
/// whole-fleet replan (SolveMapf) of the same robot count on the same map in the same run.

#include <cstdint>
#include <vector>

namespace chasles {

struct FleetSessionBenchOptions {
  std::vector<int> robots = {50, 200, 500};  ///< fleet sizes
  int goals = 2000;                          ///< goals per fleet
  std::uint64_t seed = 1;
};

/// Prints a markdown table to stdout.
void BenchFleetSession(const FleetSessionBenchOptions& options);

}  // namespace chasles
