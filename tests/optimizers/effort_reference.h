#pragma once
/// \file
/// The reference for torque-limited time-optimal parameterisation (issue 23), written apart from
/// the solver it checks (optimizers/src/effort_parameterization.cc): numerical integration of
/// ṡ² along a straight segment under the maximum-velocity curve, its feasible s̈ taken from
/// InverseDynamics calls directly. Used by tests/optimizers/effort_optimal_test.cc and
/// `chasles-bench --section effort`. Header-only; depends on robot/ and the limits struct only.

#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/Core>

#include "chasles/optimizers/time_parameterization.h"
#include "chasles/optimizers/timed_trajectory.h"
#include "chasles/robot/dynamics.h"
#include "chasles/robot/robot_model.h"

namespace chasles::reference {

/// Reference: the minimum time along the straight segment a → b from path speed v0 to v1 [rad/s]
/// by numerical integration on a grid of `step` [rad]. At (s, x = ṡ²) the torque is
/// τ(u) = τ₀ + k·u with τ₀ = ID(q, d√x, 0) and k = ID(q, d√x, d) − τ₀ (friction included); the
/// feasible u is the intersection of the torque and acceleration intervals. The maximum-velocity
/// curve is found by bisection on x, then x = min(forward at the largest u, backward at the
/// smallest u), both clipped to the curve.
inline double ReferenceSegment(const RobotModel& robot, const KinematicLimits& limits, const Eigen::VectorXd& a,
                        const Eigen::VectorXd& b, double v0, double v1, double step) {
  const int n = static_cast<int>(a.size());
  const double length = (b - a).norm();
  const Eigen::VectorXd d = (b - a) / length;
  DynamicsOptions dynamics;
  dynamics.gravity = limits.gravity;
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(n);
  const auto range = [&](double s, double x, double* lo, double* hi) {
    const Eigen::VectorXd q = a + s * d;
    const Eigen::VectorXd qd = d * std::sqrt(std::max(0.0, x));
    const Eigen::VectorXd t0 = InverseDynamics(robot, q, qd, zero, dynamics);
    const Eigen::VectorXd k = InverseDynamics(robot, q, qd, d, dynamics) - t0;
    *lo = -1e300;
    *hi = 1e300;
    for (int j = 0; j < n; ++j) {
      const double T = limits.max_effort[j];
      if (k[j] != 0.0) {
        const double p = (T - t0[j]) / k[j], m = (-T - t0[j]) / k[j];
        *lo = std::max(*lo, std::min(p, m));
        *hi = std::min(*hi, std::max(p, m));
      } else if (std::abs(t0[j]) > T) {
        *lo = 1.0;
        *hi = -1.0;
      }
      if (d[j] != 0.0) {
        const double A = limits.max_acceleration[j] / std::abs(d[j]);
        *lo = std::max(*lo, -A);
        *hi = std::min(*hi, A);
      }
    }
    return *lo <= *hi;
  };
  double xv = 1e300;
  for (int j = 0; j < n; ++j) {
    if (d[j] != 0.0) xv = std::min(xv, std::pow(limits.max_velocity[j] / d[j], 2));
  }
  const int K = std::max(1, static_cast<int>(std::ceil(length / step)));
  const double h = length / K;
  std::vector<double> mvc(K + 1), fwd(K + 1), bwd(K + 1);
  double lo, hi;
  for (int k = 0; k <= K; ++k) {
    double x0 = 0.0, x1 = xv;
    if (range(k * h, xv, &lo, &hi)) {
      mvc[k] = xv;
      continue;
    }
    for (int it = 0; it < 60; ++it) {
      const double mid = 0.5 * (x0 + x1);
      (range(k * h, mid, &lo, &hi) ? x0 : x1) = mid;
    }
    mvc[k] = x0;
  }
  // Heun's method on dx/ds = 2u: the slope at both ends of the step, averaged.
  const auto extreme = [&](double s, double x, bool largest) {
    if (!range(s, x, &lo, &hi)) return largest ? -1e300 : 1e300;  // above the curve: clipped next
    return largest ? hi : lo;
  };
  fwd[0] = std::min(v0 * v0, mvc[0]);
  for (int k = 0; k < K; ++k) {
    const double u0 = extreme(k * h, fwd[k], true);
    const double guess = std::max(0.0, std::min(mvc[k + 1], fwd[k] + 2.0 * h * u0));
    const double u1 = extreme((k + 1) * h, guess, true);
    const double x = fwd[k] + h * (u0 + std::min(u1, 1e300));
    fwd[k + 1] = std::max(0.0, std::min(mvc[k + 1], std::isfinite(x) ? x : guess));
  }
  bwd[K] = std::min(v1 * v1, mvc[K]);
  for (int k = K; k > 0; --k) {
    const double u1 = extreme(k * h, bwd[k], false);
    const double guess = std::max(0.0, std::min(mvc[k - 1], bwd[k] - 2.0 * h * u1));
    const double u0 = extreme((k - 1) * h, guess, false);
    const double x = bwd[k] - h * (u1 + u0);
    bwd[k - 1] = std::max(0.0, std::min(mvc[k - 1], std::isfinite(x) ? x : guess));
  }
  double t = 0.0;
  for (int k = 0; k < K; ++k) {
    const double xa = std::min(fwd[k], bwd[k]), xb = std::min(fwd[k + 1], bwd[k + 1]);
    t += 2.0 * h / (std::sqrt(xa) + std::sqrt(xb));
  }
  return t;
}

/// Reference for a path that stops at every corner (max_deviation 0): the sum of its segments'.
inline double ReferencePath(const RobotModel& robot, const KinematicLimits& limits, const JointPath& path, double step) {
  double t = 0.0;
  for (std::size_t k = 0; k + 1 < path.size(); ++k) t += ReferenceSegment(robot, limits, path[k], path[k + 1], 0, 0, step);
  return t;
}

/// The largest |τᵢ|/τmaxᵢ, |q̇ᵢ|/vᵢ and |q̈ᵢ|/aᵢ at 1 kHz and at both ends of every piece.
struct Peaks {
  double effort = 0.0, velocity = 0.0, acceleration = 0.0;
};
inline Peaks PeaksOf(const TimedTrajectory& traj, const RobotModel& robot, const KinematicLimits& limits) {
  Peaks out;
  DynamicsOptions dynamics;
  dynamics.gravity = limits.gravity;
  const auto visit = [&](const TrajectorySample& x) {
    const Eigen::VectorXd tau = InverseDynamics(robot, x.q, x.qd, x.qdd, dynamics);
    for (int i = 0; i < tau.size(); ++i) {
      out.effort = std::max(out.effort, std::abs(tau[i]) / limits.max_effort[i]);
      out.velocity = std::max(out.velocity, std::abs(x.qd[i]) / limits.max_velocity[i]);
      out.acceleration = std::max(out.acceleration, std::abs(x.qdd[i]) / limits.max_acceleration[i]);
    }
  };
  for (double t = 0.0; t < traj.duration(); t += 1e-3) visit(traj.Evaluate(t));
  for (const TimedTrajectory::Piece& piece : traj.pieces()) {
    visit(piece.State(0.0));
    visit(piece.State(0.5 * piece.duration));
    visit(piece.State(piece.duration));
  }
  return out;
}

/// The largest static torque along the path's segments (every 0.01 rad).
inline Eigen::VectorXd StaticNeed(const RobotModel& robot, const JointPath& path) {
  Eigen::VectorXd need = Eigen::VectorXd::Zero(robot.num_dofs());
  for (std::size_t k = 0; k + 1 < path.size(); ++k) {
    const int m = static_cast<int>(std::ceil((path[k + 1] - path[k]).norm() / 0.01));
    for (int i = 0; i <= m; ++i) {
      const Eigen::VectorXd q = path[k] + (path[k + 1] - path[k]) * (double(i) / m);
      need = need.cwiseMax(GravityTorques(robot, q).cwiseAbs());
    }
  }
  return need;
}

}  // namespace chasles::reference
