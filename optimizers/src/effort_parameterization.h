#pragma once
/// \file
/// Internal to optimizers/: the time-optimal parameterisation of a fixed geometric path under
/// velocity, acceleration and torque limits, by reachability analysis over a grid of the path
/// (Pham & Pham, "A new approach to time-optimal path parameterization based on reachability
/// analysis", IEEE T-RO 2018). ParameterizeTimeOptimal uses it when max_effort binds.

#include <vector>

#include <Eigen/Core>

#include "chasles/optimizers/time_parameterization.h"
#include "chasles/robot/dynamics.h"
#include "chasles/robot/robot_model.h"

namespace chasles::detail {

/// q(σ) = p0 + p1·σ + p2·σ² for σ ∈ [0, length] [rad of path]. A straight part has p2 = 0 and
/// |p1| = 1; a parabolic blend is its constant-acceleration piece by σ = u·τ.
struct PathSection {
  Eigen::VectorXd p0, p1, p2;
  double length = 0.0;
};

struct EffortRetimeReport {
  int grid_intervals = 0;   ///< intervals of the path grid
  int solves = 0;           ///< backward/forward passes (damping tangents, margins)
  double worst_effort = 0;  ///< max |τᵢ|/τmaxᵢ at interval ends and midpoints (friction included)
};

/// Minimum-time motion along the sections (joined end to end; where the tangent jumps between
/// two sections the motion stops there) from path speed start_speed to end_speed [rad/s].
///
/// Along the path q(s): q̇ = q′ṡ, q̈ = q′s̈ + q″ṡ², and with x = ṡ², u = s̈ the rigid-body torque
/// τ = M q′ u + (M q″ + C(q, q′) q′) x + g(q) is linear in (u, x) (three Newton–Euler passes per
/// grid point give its coefficients). Each grid interval has one u, so x is linear in s along
/// it; velocity, acceleration and torque limits are imposed at both ends of every interval
/// (TOPP-RA's "interpolation" discretisation). Friction (DofFriction, with
/// dynamics.include_friction): Coulomb f·sign(q̇ᵢ) exactly where q′ᵢ keeps its sign over an
/// interval, else ±f on both bounds; viscous damping D·q′ᵢ·√x by a linear upper bound — the
/// tangent of √x at the previous solve's x where it adds torque, the chord of √x over
/// [0, velocity limit] where it takes it away — so it is never understated.
///
/// Between grid points the torque is not linear in s: every interval's limits carry a margin,
/// twice the gap between the exact torque at its midpoint (InverseDynamics of the returned
/// state) and the mean of its ends' (the curvature of a smooth function over the interval, by
/// its midpoint), and the passes are repeated until the returned trajectory meets every limit
/// at every interval's ends and midpoint. The interval is at most `grid_step` of path.
///
/// Controllable sets backwards from the end speed (a 2-D linear programme per interval, solved
/// exactly on its pieces), then the greedy forward pass: the largest u that stays controllable.
/// The result has one polynomial piece per interval (degree 2 on straight sections, 4 on
/// blends).
/// \throws Error(kFailedPrecondition) when the limits cannot be met: the robot cannot hold a
///   configuration of the path against gravity, or no speed profile joins the boundary speeds.
TimedTrajectory RetimeUnderEffort(const std::vector<PathSection>& sections, const KinematicLimits& limits,
                                  const RobotModel& robot, const DynamicsOptions& dynamics, double start_speed,
                                  double end_speed, double grid_step, EffortRetimeReport* report = nullptr);

}  // namespace chasles::detail
