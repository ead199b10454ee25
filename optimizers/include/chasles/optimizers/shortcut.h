#pragma once
/// \file
/// Path shortening by random shortcuts, each validated by the collision checker.

#include <cstdint>
#include <functional>

#include "chasles/collision/collision_checker.h"
#include "chasles/optimizers/timed_trajectory.h"

namespace chasles {

struct ShortcutOptions {
  int max_attempts = 100;       ///< shortcut attempts; >= 0
  double max_step = 0.005;      ///< motion-check resolution [rad] (max-norm); > 0
  std::uint64_t seed = 1;       ///< the same seed gives the same result
  /// Stop early after this many consecutive attempts none of which shortened the path by at
  /// least `stall_improvement` of its length (rejected attempts count); 0 = run all attempts.
  int stall_attempts = 0;
  double stall_improvement = 1e-3;  ///< relative; in [0, 1)
  /// A random shortcut that would shorten the path by less than this fraction of its current
  /// length is not checked (a rejected attempt). Checking is what costs: a shortcut grazing an
  /// obstacle takes hundreds of certified states, and tiny gains add little. In [0, 1); 0 =
  /// check every shorter candidate.
  double min_gain = 0.0;
  /// Optional: polled before each attempt; true ends shortcutting with the (valid) path so far
  /// (a deadline or cancellation). Unset: all attempts run.
  std::function<bool()> stop;
};

/// Removes redundant waypoints (greedy: connect each kept waypoint to the farthest valid one),
/// then tries up to `max_attempts` random shortcuts (fewer when `stall_attempts` stops them)
/// between random points on two different segments
/// (accepted when every new segment passes IsMotionValid at `max_step` and the path gets
/// shorter), then, if any was accepted, drops each waypoint whose neighbours are joined by a
/// valid segment (a skip of one waypoint; longer jumps are what the shortcuts tried). Endpoints are kept
/// bit-exactly. The result is never longer (in joint-space Euclidean length) than the input
/// and every new segment passes IsMotionValid at `max_step`; input segments that are kept are
/// not re-checked. Duplicate waypoints are removed, and collinear ones whenever the joining
/// segment is valid. Randomness: std::mt19937_64(seed) with uniform doubles from its top 53
/// bits, so the output is identical on every platform for the same input and seed.
/// When checker.certifies_motion(), every new segment is checked with IsMotionCertified
/// instead (no state on it collides; it then passes IsMotionValid at any step), and the head
/// and tail pieces of a shortcut that lie on a segment certified in this call are not checked
/// again (their states are a subset of that segment's, up to rounding).
/// Paths of fewer than 3 waypoints are returned unchanged.
/// \throws Error(kInvalidArgument) for max_attempts < 0, stall_attempts < 0, stall_improvement
///         or min_gain outside [0, 1), max_step not finite and > 0, or a
///         waypoint whose size is not robot().num_dofs() or that holds a non-finite value.
JointPath ShortcutPath(const JointPath& path, const CollisionChecker& checker,
                       const ShortcutOptions& options, CheckCounters* counters = nullptr);

/// Sum of Euclidean joint-space segment lengths.
double PathLength(const JointPath& path);

}  // namespace chasles
