#pragma once
/// \file
/// Paths and timed trajectories in joint space. SI units and radians.

#include <string>
#include <vector>

#include <Eigen/Core>

#include "chasles/robot/joint_path.h"

namespace chasles {

/// One sample of a timed trajectory.
struct TrajectorySample {
  double t = 0.0;          ///< [s] from the start
  Eigen::VectorXd q;       ///< positions [rad] / [m]
  Eigen::VectorXd qd;      ///< velocities [rad/s] / [m/s]
  Eigen::VectorXd qdd;     ///< accelerations [rad/s²] / [m/s²]
  Eigen::VectorXd effort;  ///< joint torques [N·m] / forces [N]; empty unless computed (pipeline)
};

/// A trajectory that is exact between samples: a sequence of segments, each a straight
/// joint-space line a→b traversed by a scalar profile s(t) ∈ [0, 1] that is piecewise
/// quadratic (trapezoidal or triangular velocity, rest to rest).
class TimedTrajectory {
 public:
  struct Segment {
    Eigen::VectorXd a, b;      ///< endpoints
    double t0 = 0.0;           ///< start time [s]
    double t_acc = 0.0;        ///< acceleration phase duration [s] (= deceleration)
    double t_cruise = 0.0;     ///< constant-velocity phase duration [s]
    double s_acc = 0.0;        ///< path acceleration ds/dt² [1/s²]
    double duration() const { return 2.0 * t_acc + t_cruise; }
  };

  TimedTrajectory() = default;
  explicit TimedTrajectory(std::vector<Segment> segments) : segments_(std::move(segments)) {}

  const std::vector<Segment>& segments() const { return segments_; }
  double duration() const;
  bool empty() const { return segments_.empty(); }
  int num_dofs() const { return segments_.empty() ? 0 : static_cast<int>(segments_.front().a.size()); }

  /// Exact state at time t [s], clamped to [0, duration()] (NaN counts as 0).
  /// The robot is at rest outside (0, duration()): t <= 0 gives the first waypoint and
  /// t >= duration() the last one, bit-exactly, with q̇ = q̈ = 0. At a phase or segment
  /// boundary strictly inside, q̈ (which jumps there) is the value of the phase that STARTS at
  /// t (the right limit); q and q̇ are continuous. Positions are a + s·(b − a) while
  /// accelerating or cruising and b − (1 − s)·(b − a) while decelerating, so every segment
  /// starts at its `a` and ends at its `b` exactly.
  /// \throws Error(kFailedPrecondition) on an empty trajectory.
  TrajectorySample Evaluate(double t) const;
  /// Samples at t = 0, period, 2·period, … strictly before duration() (a multiple of the
  /// period within 1e-9·period of the end is skipped), then at duration() exactly. The first
  /// and last samples are the first and last waypoints bit-exactly with q̇ = q̈ = 0. A
  /// zero-duration trajectory gives one sample; an empty one gives none.
  /// \throws Error(kInvalidArgument) when period is not finite and > 0 or would give more
  ///         than 1e8 samples.
  std::vector<TrajectorySample> Sample(double period) const;
  /// The segment endpoints in order: segments().front().a, then every segment's b.
  JointPath Waypoints() const;

 private:
  std::vector<Segment> segments_;
};

}  // namespace chasles
