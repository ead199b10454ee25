#pragma once
/// \file
/// `chasles-bench --section fleet_lattice`: building a fleet lattice (multi/fleet_lattice.h) — 160 x 60
/// nodes over scenes of N seeded boxes — and scheduling a fleet's grid plan on it.

#include <vector>

namespace chasles {

struct FleetLatticeBenchOptions {
  std::vector<int> boxes = {0, 1000, 3000, 10000};  ///< scene sizes
  int repeats = 5;                                   ///< builds per scene; medians
};

/// Prints a markdown table to stdout.
void BenchFleetLattice(const FleetLatticeBenchOptions& options);

}  // namespace chasles
