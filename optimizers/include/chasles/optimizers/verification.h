#pragma once
/// \file
/// Dense verification of a timed trajectory before it leaves the server, and the quality
/// figures a response reports.

#include <string>

#include "chasles/collision/collision_checker.h"
#include "chasles/optimizers/time_parameterization.h"
#include "chasles/optimizers/timed_trajectory.h"

namespace chasles {

struct VerificationOptions {
  double max_joint_step = 0.005;   ///< resample so no joint moves more than this between checks [rad]
  /// Also resample so consecutive checked states are no more than this apart in time [s]; 0 = no
  /// time bound (a robot standing still is then checked once per piece). Multi-robot
  /// verification sets it, since other robots move while one stands.
  double max_time_step = 0.0;
  double endpoint_tolerance = 1e-6;  ///< |q(0) − start|∞, |q(T) − goal|∞ and piece-to-piece jumps [rad]
  double limit_tolerance = 1e-9;   ///< relative slack on velocity/acceleration/jerk/effort limits
  /// Expected velocity at the start / end [rad/s]; empty = at rest. Checked to
  /// 1e-6·max(1, v_max) per joint, as is velocity continuity between pieces.
  Eigen::VectorXd start_velocity, end_velocity;
};

struct VerificationReport {
  bool ok = false;
  std::string reason;              ///< empty when ok, else what failed and where (time, joint)
  /// States evaluated for collisions: the conservative advancement's states when certified, the
  /// discrete states otherwise (plus the exact final configuration).
  int states_checked = 0;
  /// Which collision guarantee step 4 gives: "certified" — no state anywhere on the continuous
  /// motion collides (conservative advancement over every polynomial piece, padding included);
  /// "discrete" — the states checked (at most max_joint_step apart) are free, the motion
  /// between them is not proven. Set also when verification fails.
  std::string collision_guarantee;
  /// Empty when certified; else why the checker cannot certify (DiscreteCheckCause) and the step.
  std::string collision_guarantee_reason;
  double max_velocity_ratio = 0.0;     ///< max over the trajectory and joints of |q̇ᵢ|/vᵢ (exact)
  double max_acceleration_ratio = 0.0; ///< max of |q̈ᵢ|/aᵢ (exact)
  double max_jerk_ratio = 0.0;         ///< max of |q⃛ᵢ|/jᵢ (exact); 0 without jerk limits
  double max_effort_ratio = 0.0;       ///< max of |τᵢ|/τmaxᵢ at the checked states; 0 without effort limits
};

/// Checks, in order, stopping at the first failure:
/// 1. structure: every piece has num_dofs rows, finite coefficients, a finite duration >= 0,
///    starts when the previous one ends (1e-9 s relative), and continues its position (within
///    endpoint_tolerance) and velocity; with max_jerk set also its acceleration, and the
///    acceleration is zero at an end at rest (a step there would be an infinite jerk);
/// 2. q(0) vs start, q(T) vs goal, q̇(0) and q̇(T) vs the expected velocities;
/// 3. piece by piece in time order, exactly at the extrema of each polynomial: position limits
///    (to 1e-12 relative), velocity, acceleration and (when limited) jerk limits;
/// 4. collisions (self + scene) and, with max_effort on a robot with inertia, torques:
///    - when checker.certifies_motion() (sphere robot; primitives and gridded occupancy maps):
///      every piece is certified along its continuous motion, piece by piece in time order. A
///      piece along a line (every coefficient column after the first a multiple of one
///      direction, to 1e-12 rad) is certified as the straight segment it sweeps, between the
///      extremes of its scalar profile, in one IsCurveCertified; should that not certify, or for
///      any other piece: cut into spans of at most 0.25 rad of joint travel, each span's curve checked by
///      CollisionChecker::IsCurveCertified with the exact speed bound (span length)·max|q̇ᵢ|
///      over the span (extrema of the polynomial); a span that does not certify is bisected, up
///      to 12 levels, so only a motion that collides or passes within rounding of a contact
///      fails. The contact is then named from states at most 0.0005 rad apart in the first part
///      that failed. Torques are checked at discrete states as below.
///    - otherwise: states spaced so no joint moves more than max_joint_step between consecutive
///      ones (m = ⌈maxᵢ max|q̇ᵢ|·duration / step⌉ per piece, or ⌈duration / max_time_step⌉ if
///      more), collisions and torques at each.
///    Then the exact final configuration (the trajectory's end position).
/// `reason` says what failed and where, e.g.
/// `collision at t = 1.234 s between link 'panda_link5' and 'shelf_top'`,
/// `self-collision at t = 0.5 s between link 'link1' and link 'link4'`,
/// `not certified at t = 0.8 s: link 'panda_hand' passes within rounding of 'shelf_top' (closer
/// than 1e-05 m; …)` (certified check only: no colliding state found, but the gap cannot be
/// proven), or `not certified between t = 0.8 and 0.81 s: …` when not even a near pair is found,
/// `joint 3 'panda_joint4' velocity 2.1 rad/s exceeds limit 2 rad/s at t = 0.5 s`,
/// `joint 0 'joint1' position 3.2 is outside its limits [-3.14159, 3.14159] at t = 1 s`,
/// `trajectory ends 0.001 rad from the goal configuration (tolerance 1e-06 rad) at t = 4.8 s`,
/// `trajectory is empty`. Joints are numbered from 0 in configuration order.
/// \throws Error(kInvalidArgument) for options that are not finite with max_joint_step > 0 and
///         tolerances >= 0, limits that fail Validate(robot().num_dofs()), start/goal or
///         expected velocity sizes, or max_effort on a robot without inertia.
/// Why `checker` checks collisions at discrete states rather than certifying motions, e.g.
/// `robot links with shapes other than spheres: 'link1' (box); scene meshes 'bunny'`; empty when
/// checker.certifies_motion().
std::string DiscreteCheckCause(const CollisionChecker& checker);

VerificationReport VerifyTrajectory(const TimedTrajectory& trajectory, const Eigen::VectorXd& start,
                                    const Eigen::VectorXd& goal, const CollisionChecker& checker,
                                    const KinematicLimits& limits,
                                    const VerificationOptions& options = {});

/// Quality figures of a trajectory (what a response reports besides the verification).
struct TrajectoryQuality {
  double duration = 0.0;                ///< [s]
  double max_velocity_ratio = 0.0;      ///< max |q̇ᵢ|/vᵢ (exact)
  double max_acceleration_ratio = 0.0;  ///< max |q̈ᵢ|/aᵢ (exact)
  double max_jerk_ratio = 0.0;          ///< max |q⃛ᵢ|/jᵢ (exact, inside pieces); 0 without jerk limits
  double max_jerk = 0.0;                ///< max |q⃛ᵢ| inside pieces [rad/s³] (steps between pieces not counted)
  double max_effort_ratio = 0.0;        ///< max |τᵢ|/τmaxᵢ at the sampled states; 0 without effort limits
  /// Largest distance [rad] (Euclidean in joint space) between the trajectory and the input
  /// path, both ways, never above the true figure: from every point of the trajectory to the
  /// path's polyline within 1e-9 rad of the truth (sampled states, then spans of each piece whose
  /// bound — MaxDistanceToSegment, the least over segments — is above the figure are split and
  /// their middles measured; after 2000 splits the figure is left where it is, possibly lower),
  /// and from each waypoint to the trajectory exactly (per polynomial piece, the least of
  /// |q(τ) − w|²).
  double max_deviation = 0.0;
  /// Smallest distance [m] between the robot — grown by the checker's padding — and the scene's
  /// obstacles (CollisionChecker::Clearance; self-distance and allowed pairs not included);
  /// +inf when the scene has none. When the checker certifies motions it is a lower bound on
  /// the minimum over the whole continuous trajectory, within max(1e-4 m, 2 % of it) of it (see
  /// MeasureTrajectory); otherwise it is the minimum at sampled states, which may be above the
  /// true minimum.
  double min_clearance = 0.0;
  double jerk_integral = 0.0;           ///< ∫‖q⃛‖² dt over the pieces (exact) [rad²/s⁵]
  /// With a checker that has path constraints: the largest PathConstraints::WorstRatio (|error| /
  /// tolerance) over the sampled states, <= 1 when each keeps them; 0 without constraints.
  /// Verification certifies them along the whole motion; this says how close the path came.
  double max_constraint_ratio = 0.0;
};

/// Measures `trajectory` against the limits and the input `path` (may be empty: deviation 0),
/// sampling states every `max_joint_step` of joint motion (at most 2000 states in all) for the
/// sampled figures. `checker` may be null (clearance +inf, effort 0).
/// min_clearance, when checker->certifies_motion(): a piece along a line is taken as the straight
/// segment it sweeps (parameter u ∈ [0, 1], |dq/du| = |b − a| exactly), any other piece by time in
/// spans of at most 0.25 rad of travel (each span's largest speed). Each clearance group g of the
/// checker (CollisionChecker::Clearance(q, &groups)) moves at most L_g = maxₖ Dₖ over its spheres
/// per unit of the parameter, Dₖ = Σᵢ Rₖᵢ·|dqᵢ| the lever bound of sphere k, so between evaluated
/// states at s0 < s1 its clearance is at least (c0 + c1 − L_g·(s1 − s0))/2, and the clearance the
/// least of these over the groups. Starting from states at most 0.2 rad
/// apart, the interval with the lowest such bound is bisected until every bound is within
/// max(1e-4 m, 2 % of it) of the smallest clearance evaluated; the figure is the smallest bound (>= 0). At most
/// 5000 states are evaluated: beyond that the figure is the smallest remaining bound (still a
/// lower bound, possibly looser). Otherwise min_clearance is the minimum at (at
/// most about 200 of) the sampled states.
TrajectoryQuality MeasureTrajectory(const TimedTrajectory& trajectory, const KinematicLimits& limits,
                                    const JointPath& path, const CollisionChecker* checker,
                                    double max_joint_step = 0.01);

/// ∫‖q⃛‖² dt over the pieces, exactly (each jerk polynomial squared and integrated term by
/// term) [rad²/s⁵]; steps of acceleration between pieces are not counted
/// (TrajectoryQuality::jerk_integral).
double JerkIntegral(const TimedTrajectory& trajectory);

/// An upper bound [rad] on the distance from every position of `piece` to the segment a–b
/// (Euclidean in joint space), from exact polynomial ranges: with e(τ) = q(τ) − a, d̂ the unit
/// direction and L the length, √(max ‖e − (d̂ᵀe)d̂‖² + E²) where E is how far d̂ᵀe leaves [0, L]
/// (0 when it stays inside, and then the bound is the exact maximum). a = b: the exact largest
/// distance to a.
double MaxDistanceToSegment(const TimedTrajectory::Piece& piece, const Eigen::VectorXd& a, const Eigen::VectorXd& b);

}  // namespace chasles
