#pragma once
/// \file
/// The discrete map fleets plan on: the grid MAPF solver (grid_mapf.h) searches it, the fleet
/// lattice (fleet_lattice.h) builds it from a scene.

#include <cstdint>
#include <vector>

namespace chasles {

/// A grid of square cells, row-major: cell index = y * width + x, (0, 0) the lower-left cell.
struct GridMap {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> blocked;  ///< width * height entries; 1 = blocked, 0 = free
};

/// A cell index of a GridMap (y * width + x).
using GridCell = std::int32_t;

}  // namespace chasles
