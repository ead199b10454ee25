#pragma once
/// \file
/// `chasles-bench --section moving` (issue 18, moving obstacles): a planar base crossing the yard
/// of examples/requests/base_crossing_people.json while 2–4 people walk across it on random
/// straight lines, timed so that the base's plan without them meets at least one. Per problem,
/// one Plan RPC to an in-process server per method: SPACE_TIME, VELOCITY_OBSTACLES, and the
/// walkers left out (the in-run baseline). Every trajectory is re-checked here at 1 ms samples
/// against the walkers placed by linear interpolation (the base's two body spheres against each
/// walker's upright cylinder: horizontal distances).

#include <cstdint>
#include <string>

namespace chasles {

struct MovingBenchOptions {
  std::string examples_dir;  ///< holds requests/base_crossing_people.json
  int cases = 50;
  std::uint64_t seed = 1;
};

/// Prints a markdown table to stdout.
void BenchMoving(const MovingBenchOptions& options);

}  // namespace chasles
