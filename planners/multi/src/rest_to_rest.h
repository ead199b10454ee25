#pragma once
/// \file
/// Internal to planners/multi: the rest-to-rest straight motions fleet robots make (ScheduleFleet
/// and the fleet session time their runs with it).

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <Eigen/Core>

#include "chasles/optimizers/timed_trajectory.h"

namespace chasles::fleet_internal {

/// A rest-to-rest straight motion of length L under path-speed V and path-acceleration A:
/// trapezoid (accelerate for ta, cruise, decelerate) or triangle.
struct Profile {
  double length = 0.0, accel = 0.0, peak = 0.0, ta = 0.0, da = 0.0, duration = 0.0;

  Profile(double l, double v, double a) : length(l), accel(a) {
    if (l <= 0.0) return;
    if (l * a >= v * v) {
      peak = v;
      ta = v / a;
      da = 0.5 * v * ta;
      duration = l / v + ta;
    } else {
      peak = std::sqrt(a * l);
      ta = peak / a;
      da = 0.5 * l;
      duration = 2.0 * ta;
    }
  }
  /// When the motion has covered distance d ∈ [0, length].
  double TimeAt(double d) const {
    if (d >= length) return duration;
    if (d <= da) return std::sqrt(2.0 * std::max(0.0, d) / accel);
    if (d <= length - da) return ta + (d - da) / peak;
    return duration - std::sqrt(2.0 * (length - d) / accel);
  }
  /// The pieces from t0 along origin + s·direction.
  void AppendPieces(double t0, const Eigen::VectorXd& origin, const Eigen::VectorXd& direction,
                    std::vector<TimedTrajectory::Piece>* pieces) const {
    const double cruise = duration - 2.0 * ta;
    pieces->push_back(LinePiece(t0, ta, origin, direction, 0.0, 0.0, 0.5 * accel));
    if (cruise > 0.0) pieces->push_back(LinePiece(t0 + ta, cruise, origin, direction, da, peak, 0.0));
    pieces->push_back(LinePiece(t0 + ta + std::max(0.0, cruise), ta, origin, direction, length - da, peak, -0.5 * accel));
  }
};

/// Path-speed or path-acceleration limit along a unit direction: min over moving coordinates.
inline double AlongLimit(const Eigen::Vector3d& unit, const Eigen::Vector3d& limit) {
  double best = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 3; ++i) {
    if (unit[i] != 0.0) best = std::min(best, limit[i] / std::abs(unit[i]));
  }
  return best;
}

}  // namespace chasles::fleet_internal
