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
  int solves = 0;           ///< backward/forward passes (damping tangents, grown margins)
  double worst_effort = 0;  ///< max |τᵢ|/τmaxᵢ at interval ends and midpoints (friction included)
};

/// Minimum-time motion along the sections (joined end to end; where the tangent jumps between
/// two sections the motion stops there) from path speed start_speed to end_speed [rad/s].
///
/// Along the path q(s): q̇ = q′ṡ, q̈ = q′s̈ + q″ṡ², and with x = ṡ², u = s̈ the rigid-body torque
/// τ = M q′ u + (M q″ + C(q, q′) q′) x + g(q) is linear in (u, x) (PathTorqueCoefficients at
/// every grid node). Each grid interval (at most `grid_step` of path) has one u, so x is linear
/// in s along it; velocity, acceleration and torque limits are imposed at both ends of every
/// interval (TOPP-RA's "interpolation" discretisation; on a blend q̈ is linear in s, so its ends
/// bound it). Friction (DofFriction, with dynamics.include_friction): Coulomb f·sign(q′ᵢ) exactly
/// where q′ᵢ keeps its sign over an interval that does not touch a rest point (there: between
/// 0 and that), else ±f; viscous damping D·q′ᵢ·√x by linear bounds that never understate it —
/// where it adds torque the tangent of √x at the interval's mean x of the previous pass, where it
/// takes torque away the interpolant of √x through knots at ½, 0.9, 1 and 1.1 of that speed and
/// the velocity limit. One re-solve moves the tangents to the first profile's speeds.
///
/// Between grid points the torque is not linear in s: every interval's limits carry a margin of
/// twice the largest gap between the rigid torque at its midpoint and its ends' mean that any
/// (u, x) within the acceleration and velocity limits could give. The returned profile's exact
/// torque (friction included) is checked at every interval's ends and midpoint; where it is over
/// a limit, or the gap outgrows the margin, the margin grows and the passes run again.
///
/// Controllable sets backwards from the end speed (a 2-D linear programme per interval, solved
/// exactly on its pieces), then the greedy forward pass: the largest u that stays controllable.
/// The result has one polynomial piece per interval (degree 2 on straight sections, 4 on
/// blends); a piece that comes to rest ends 1e-12 of its duration early, so its last velocity
/// points along the motion.
/// \throws Error(kFailedPrecondition) when the limits cannot be met: the robot cannot hold a
///   configuration of the path against gravity, or no speed profile joins the boundary speeds.
TimedTrajectory RetimeUnderEffort(const std::vector<PathSection>& sections, const KinematicLimits& limits,
                                  const RobotModel& robot, const DynamicsOptions& dynamics, double start_speed,
                                  double end_speed, double grid_step, EffortRetimeReport* report = nullptr);

}  // namespace chasles::detail
