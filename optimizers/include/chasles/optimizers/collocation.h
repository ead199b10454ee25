#pragma once
/// \file
/// Minimum-time (plus jerk) trajectories by direct collocation, solved with Ipopt.

#include <functional>
#include <string>

#include <Eigen/Core>

#include "chasles/collision/collision_checker.h"
#include "chasles/robot/joint_path.h"
#include "chasles/optimizers/optimizer_report.h"
#include "chasles/optimizers/time_parameterization.h"
#include "chasles/optimizers/timed_trajectory.h"

namespace chasles {

struct CollocationOptions {
  int knots = 100;              ///< K >= 2 knots, K − 1 intervals with their own durations
  /// w >= 0 in the objective T + w·∫‖q⃛‖² dt [s⁶/rad²]; 0 = minimum time only.
  double jerk_weight = 0.0;
  /// Required distance between every link and every obstacle at each knot and each interval
  /// midpoint [m], >= 0; used only with a checker whose scene has obstacles. Where the warm
  /// start itself passes closer, its own distance there is required instead.
  double clearance = 0.01;
  /// >= 0 [m]: a link that comes within clearance + activation_distance of an obstacle anywhere
  /// along the warm start is constrained at every knot and midpoint from the first solve; any
  /// other link found too close after a solve is added, and the problem solved again.
  double activation_distance = 0.05;
  /// With a path to follow: the trajectory stays within this distance of the path and passes
  /// within it of every interior waypoint, in order [rad, Euclidean in joint space]; in (0, 1].
  double corridor = 0.05;
  /// Ipopt max_iter per solve, >= 1: the budget that decides the result (the same on any machine).
  int max_iterations = 500;
  double tolerance = 1e-8;      ///< Ipopt tol, finite and > 0
  /// [s] > 0 for the whole call: a safety cap (Ipopt's max_cpu_time, and a wall-clock check
  /// every iteration), far above what max_iterations takes, so that results do not depend on
  /// the machine's load; a call it cuts short is not ok and says so.
  double time_budget = 60.0;
  /// Optional: polled every iteration; true stops the solve (the result is then not ok).
  std::function<bool()> stop;

  /// The one owner of these rules (OptimizeByCollocation checks them; the server calls it after
  /// mapping its defaults): knots in [2, kMaxKnots], weights and distances finite and >= 0,
  /// corridor in (0, 1], max_iterations >= 1, tolerance finite and > 0, time_budget > 0.
  /// \throws Error(kInvalidArgument) naming the field as `field_prefix` + its name, e.g.
  ///   `collocation knots = 1 must be >= 2`, `options.collocation.corridor = 0 must be in (0, 1] rad`.
  void Validate(const std::string& field_prefix = "collocation ") const;
  static constexpr int kMaxKnots = 2000;
};

struct CollocationResult {
  TimedTrajectory trajectory;   ///< cubic pieces (constant jerk per interval); empty unless report.ok
  OptimizerReport report;
};

/// Direct collocation on the triple integrator q⃛ = u with states (q, q̇, q̈) at K knots,
/// piecewise-constant jerk u and a free duration hₖ per interval, so each interval is an
/// exact cubic (Hermite–Simpson collocation is exact for it). The start and end states
/// (position, velocity) are those of `warm_start`, which also initialises every variable (its
/// states at the knot times). The result has one cubic piece per interval.
///
/// Along a path (`path` given with two or more distinct waypoints; its ends must be the warm
/// start's): the warm start must follow it (TOPP's blends within `corridor`, or stops). A knot
/// is put where the warm start passes closest to each interior waypoint, the others spread
/// evenly in time between them (at least two intervals per segment; K is raised to 2W − 1 for
/// W waypoints when smaller). Constraints: that knot within `corridor` of its waypoint, and
/// every other interior knot between waypoints j and j+1 within `corridor` of segment j
/// (distance to its line, and the projection within the segment), with exact curvature. After a
/// solve the whole trajectory is bounded exactly (MaxDistanceToSegment per piece); an interval
/// that bulges beyond `corridor` between its knots tightens its two knots' rows by twice the
/// excess, and the problem is solved again (within the same 8 solves as
/// the clearance and the position limits). The result is ok only within the corridor everywhere
/// (report.path_deviation). Without a path (free): only the ends are kept, and a warm start that
/// returns to its start at rest is not ok (its minimum-time trajectory would not move).
///
/// The pieces returned are exact: the knot accelerations are corrected by a least-norm Δ (at
/// most 1e-4 of the limits, else not ok; every limit is then checked on the result exactly) so
/// that the cubic chain integrated from the start with the solved durations ends exactly at the
/// end state; positions, velocities and accelerations are then continuous to rounding at every
/// knot.
///
/// Objective: T + w·∫‖q⃛‖² dt, plus a tie-breaking term of at most 1e-3·T₀-relative size that
/// keeps the knots evenly spread along a cruise and the joints that do not limit the time
/// smooth (minimum time alone has a flat optimum Ipopt drifts on). hₖ >= a tenth of an even
/// split of the duration's lower bound maxᵢ |Δqᵢ|/vᵢ.
///
/// Constraints: position limits (with a checker) and velocity and acceleration limits at the
/// knots; the velocity over each interval through its middle Bernstein coefficient (the
/// velocity is quadratic in an interval, and free durations would otherwise let it overshoot
/// between knots); jerk limits on u; with max_jerk, q̈ = 0 at an end at rest. With max_effort
/// (robot with inertia): |τ| <= max_effort − Coulomb friction at the knots, τ = RNEA + viscous
/// damping, its Jacobian by central differences of RNEA (∂τ/∂q̈ = M(q) exactly); a warm start
/// at rest at both ends is first slowed down until its torques fit.
/// With a checker whose scene has obstacles: the clearance at the knots and midpoints, from
/// ObstacleProximity's distances and nearest points (gradient n̂ᵀ·J_v at the nearest link point;
/// in contact, where there is no direction, the last outside value is continued linearly), and
/// the joint-space motion over each half interval at most max(0.05 rad, twice the warm start's
/// average), so that a link cannot cross an obstacle between two checked instants. After each
/// solve the checked instants are verified and the motion searched for contact every 0.005 rad;
/// a violating link is then constrained everywhere and the problem solved again (at most 8
/// solves; from the warm start again when a link touched). With a checker, a cubic that leaves
/// a position limit between knots pulls that joint's bounds at both knots in by twice the
/// excess for the next solve. A re-solve with the same rows (only bounds tightened) starts from
/// the last primal and dual solution (Ipopt's warm start, mu_init 1e-4).
///
/// Afterwards the exact maxima of velocity, acceleration and jerk over each cubic give
/// r = max(velocity ratio, √acceleration ratio, ∛jerk ratio); r > 1 (rounding, bound
/// relaxation) slows the trajectory by r (OptimizerReport::time_scale). With max_effort the
/// torques are rechecked at the states VerifyTrajectory uses (every 0.005 rad) and the
/// smallest further slow-down that meets them is applied, when one exists.
///
/// With a checker, a result is ok only if it passes VerifyTrajectory (default options, the
/// warm start's end velocities) with the same limits; self-collision is not constrained, only
/// verified.
///
/// Not ok (report.message says why; the caller falls back to an exact parameterisation):
/// Ipopt did not converge (Infeasible_Problem_Detected, iteration or time limit, stop()),
/// defects left open by more than 1e-7, position limits left between knots, a clearance still
/// violated after 8 solves, torques no slow-down meets, a slow-down that would change a
/// non-zero end velocity, or a failed verification.
/// Deterministic for the same input (unless the time budget cuts a solve short).
///
/// Thread-safe, but the Ipopt solves of all threads run one at a time (Debian's sequential
/// MUMPS aborts when two run at once); waiting counts towards time_budget and polls stop().
/// Cost is dominated by MUMPS factorising the KKT system (about 7·n·K rows).
///
/// \throws Error(kInvalidArgument) naming the option for knots < 2, negative or non-finite
///   weight/clearance/activation_distance, corridor not in (0, 1], max_iterations < 1, tolerance not finite and > 0,
///   time_budget not > 0, an empty warm start or one with a non-finite end state, a path whose
///   ends are not the warm start's (or of another number of joints), a checker
///   whose robot has another number of joints, limits that fail Validate, or max_effort
///   without a checker whose robot has inertia.
CollocationResult OptimizeByCollocation(const TimedTrajectory& warm_start, const KinematicLimits& limits,
                                        const CollocationOptions& options,
                                        const CollisionChecker* checker = nullptr,
                                        const JointPath* path = nullptr);

}  // namespace chasles
