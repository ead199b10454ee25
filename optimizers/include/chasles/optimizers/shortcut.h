#pragma once
/// \file
/// Path shortening by random shortcuts, each validated by the collision checker.

#include <cstdint>

#include "chasles/collision/collision_checker.h"
#include "chasles/optimizers/timed_trajectory.h"

namespace chasles {

struct ShortcutOptions {
  int max_attempts = 100;       ///< shortcut attempts; >= 0
  double max_step = 0.005;      ///< motion-check resolution [rad] (max-norm); > 0
  std::uint64_t seed = 1;       ///< the same seed gives the same result
};

/// Removes redundant waypoints (greedy: connect each kept waypoint to the farthest valid one),
/// then tries random shortcuts between points on two segments. Endpoints are kept exactly.
/// The result is never longer (in joint-space Euclidean length) than the input and every new
/// segment passes IsMotionValid at `max_step`. Collinear and duplicate waypoints are removed.
JointPath ShortcutPath(const JointPath& path, const CollisionChecker& checker,
                       const ShortcutOptions& options, CheckCounters* counters = nullptr);

/// Sum of Euclidean joint-space segment lengths.
double PathLength(const JointPath& path);

}  // namespace chasles
