#pragma once
/// \file
/// The discrete map a grid MAPF solver plans on (shared with chasles/multi/grid_mapf.h; to be
/// reconciled with it).

#include <cstdint>
#include <vector>

namespace chasles {

struct GridMap { int width = 0, height = 0; std::vector<std::uint8_t> blocked; };  // row-major, index y*width+x, (0,0) lower-left
using GridCell = std::int32_t;

}  // namespace chasles
