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

  /// Exact state at time t (clamped to [0, duration()]).
  TrajectorySample Evaluate(double t) const;
  /// Samples at t = 0, period, 2·period, …, and always at duration() exactly.
  /// Precondition: period > 0.
  std::vector<TrajectorySample> Sample(double period) const;

 private:
  std::vector<Segment> segments_;
};

}  // namespace chasles
