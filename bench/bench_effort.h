#pragma once
/// \file
/// `chasles-bench --section effort` (issue 23): TOPP under torque limits on the Panda — random
/// straight segments, random multi-waypoint paths (stopping at each waypoint, and blended) and the
/// shelf path of examples/requests — against the independent reference of
/// tests/optimizers/effort_reference.h (numerical integration under the maximum-velocity curve),
/// with the velocity/acceleration-only TOPP on the same paths as the in-run baseline.

#include <cstdint>
#include <string>

namespace chasles {

struct EffortBenchOptions {
  std::string examples_dir;  ///< holds robots/panda.urdf and .srdf
  int cases = 10;            ///< random paths per group
  int repeats = 5;           ///< timed solves per path (the median is kept)
  std::uint64_t seed = 1;
};

/// Prints markdown tables to stdout.
void BenchEffort(const EffortBenchOptions& options);

}  // namespace chasles
