#pragma once
// Random limits and paths for the time-parameterisation tests, and the reference minimum time of
// a straight rest-to-rest segment computed independently of the code under test.

#include <cmath>
#include <limits>

#include <Eigen/Core>

#include "chasles/optimizers/time_parameterization.h"
#include "test_util.h"

namespace chasles::test {

inline KinematicLimits RandomLimits(Random& rng, int n) {
  KinematicLimits limits;
  limits.max_velocity = rng.Vector(n, 0.3, 3.0);
  limits.max_acceleration = rng.Vector(n, 0.5, 12.0);
  return limits;
}

/// Reference minimum time of a straight rest-to-rest segment, computed here independently.
inline double ReferenceDuration(const Eigen::VectorXd& a, const Eigen::VectorXd& b, const KinematicLimits& limits,
                         bool* triangle) {
  double v = std::numeric_limits<double>::infinity(), acc = v;
  for (int i = 0; i < a.size(); ++i) {
    const double d = std::fabs(b[i] - a[i]);
    if (d == 0) continue;
    v = std::fmin(v, limits.max_velocity[i] / d);
    acc = std::fmin(acc, limits.max_acceleration[i] / d);
  }
  *triangle = v * v > acc;
  return *triangle ? 2.0 / std::sqrt(acc) : 1.0 / v + v / acc;
}

/// |x| <= limit·(1 + rel) for every joint; returns the first offending joint or -1.
inline int FirstExceeding(const Eigen::VectorXd& x, const Eigen::VectorXd& limit, double rel) {
  for (int i = 0; i < x.size(); ++i) {
    if (!(std::fabs(x[i]) <= limit[i] * (1.0 + rel))) return i;
  }
  return -1;
}

/// A random path with reversals (returning to an earlier waypoint), exact duplicates and
/// joints that do not move on some segments.
inline JointPath RandomPath(Random& rng, int n) {
  JointPath path{rng.Vector(n, -2.0, 2.0)};
  const int waypoints = 2 + rng.Index(8);
  for (int k = 1; k < waypoints; ++k) {
    const double r = rng.Uniform();
    if (r < 0.15) {
      path.push_back(path.back());  // exact duplicate
    } else if (r < 0.3 && path.size() >= 2) {
      path.push_back(path[path.size() - 2]);  // reversal
    } else {
      Eigen::VectorXd q = path.back() + std::pow(10.0, rng.Uniform(-2.0, 0.0)) * rng.Vector(n, -2.0, 2.0);
      for (int i = 0; i < n; ++i) {
        if (rng.Uniform() < 0.2) q[i] = path.back()[i];
      }
      path.push_back(q);
    }
  }
  return path;
}

}  // namespace chasles::test
