#include "chasles/optimizers/time_parameterization.h"

#include <cmath>
#include <limits>
#include <string>

#include "chasles/robot/error.h"
#include "internal.h"

namespace chasles {
namespace {


void ValidatePositive(const Eigen::VectorXd& values, const char* field, int num_dofs) {
  if (values.size() != num_dofs) {
    ThrowInvalid(std::string(field) + " has " + std::to_string(values.size()) + " values, robot has " +
                 std::to_string(num_dofs) + " joints");
  }
  for (int i = 0; i < values.size(); ++i) {
    const double v = values[i];
    const std::string name = std::string(field) + "[" + std::to_string(i) + "] = " + FormatNumber(v);
    if (!std::isfinite(v)) ThrowInvalid(name + " must be finite");
    if (!(v > 0.0)) ThrowInvalid(name + " must be > 0");
  }
}

}  // namespace

void KinematicLimits::Validate(int num_dofs) const {
  ValidatePositive(max_velocity, "max_velocity", num_dofs);
  ValidatePositive(max_acceleration, "max_acceleration", num_dofs);
}

TimedTrajectory ParameterizeRestToRest(const JointPath& path, const KinematicLimits& limits) {
  if (path.empty()) ThrowInvalid("path has 0 waypoints, needs at least 1");
  const int n = static_cast<int>(path.front().size());
  limits.Validate(n);
  for (std::size_t k = 0; k < path.size(); ++k) {
    if (path[k].size() != n) {
      ThrowInvalid("path[" + std::to_string(k) + "] has " + std::to_string(path[k].size()) +
                   " values, path[0] has " + std::to_string(n));
    }
    for (int i = 0; i < n; ++i) {
      if (!std::isfinite(path[k][i])) {
        ThrowInvalid("path[" + std::to_string(k) + "][" + std::to_string(i) + "] = " + FormatNumber(path[k][i]) +
                     " must be finite");
      }
    }
  }

  constexpr double kMax = std::numeric_limits<double>::max();
  std::vector<TimedTrajectory::Segment> segments;
  const Eigen::VectorXd* previous = &path.front();
  double t = 0.0;
  for (std::size_t k = 1; k < path.size(); ++k) {
    const Eigen::VectorXd& next = path[k];
    if (next == *previous) continue;  // exact duplicate: zero-length segment, dropped
    const Eigen::VectorXd delta = next - *previous;
    // V = min vᵢ/|Δᵢ|, A = min aᵢ/|Δᵢ| over the joints that move (path-parameter limits).
    double v = kMax, a = kMax;
    for (int i = 0; i < n; ++i) {
      const double d = std::abs(delta[i]);
      if (d == 0.0) continue;
      v = std::min(v, limits.max_velocity[i] / d);
      a = std::min(a, limits.max_acceleration[i] / d);
    }
    // (Clamped to the largest double, so a segment of denormal length stays finite.)
    TimedTrajectory::Segment seg;
    seg.a = *previous;
    seg.b = next;
    seg.t0 = t;
    seg.s_acc = a;
    if (v * v <= a) {  // trapezoid: reaches V after V/A, cruises the rest
      seg.t_acc = v / a;
      seg.t_cruise = std::max(0.0, 1.0 / v - v / a);
    } else {           // triangle: accelerates to the middle, peak ds/dt = √A < V
      seg.t_acc = 1.0 / std::sqrt(a);
      seg.t_cruise = 0.0;
    }
    t += seg.duration();
    segments.push_back(std::move(seg));
    previous = &next;
  }
  if (segments.empty()) {
    // One waypoint (or all identical): a single zero-duration segment at rest there, so that
    // Evaluate and Sample still report the configuration.
    TimedTrajectory::Segment seg;
    seg.a = path.front();
    seg.b = path.back();
    segments.push_back(std::move(seg));
  }
  // Trailing duplicates compare equal but may differ in the sign of a zero: end on the last
  // waypoint bit for bit.
  segments.back().b = path.back();
  return TimedTrajectory(std::move(segments));
}

}  // namespace chasles
