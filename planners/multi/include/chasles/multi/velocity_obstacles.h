#pragma once
/// \file
/// Velocity obstacles (Fiorini & Shiller 1998): a planar base crossing discs that move along
/// known paths. At every control step the base picks, among the velocities it can reach within
/// one step (its acceleration limits), the one closest to where it wants to go (along a guide
/// path through the static scene) that no disc's velocity obstacle holds within the look-ahead
/// horizon, and whose step is free of the static scene. Each disc's velocity obstacle follows
/// its known path over the horizon (piece by piece at the path's constant velocities, in closed
/// form; the non-linear velocity obstacle of Shiller, Large & Sekhavat 2001), so a disc that
/// starts, turns or stops within the horizon is foreseen. Reactive and incomplete: it can be
/// boxed in or run out of simulated time, and says so. The returned trajectory is exact
/// (constant acceleration per step) and is meant to be verified against the obstacles' true
/// motions by the caller (the discs here only steer).
///
/// Thread-safe for concurrent calls (no shared state; the checker is const).

#include <string>
#include <vector>

#include <Eigen/Core>

#include "chasles/collision/collision_checker.h"
#include "chasles/optimizers/time_parameterization.h"
#include "chasles/optimizers/timed_trajectory.h"
#include "chasles/planners/termination.h"
#include "chasles/robot/joint_path.h"

namespace chasles {

/// A disc moving in the plane along a known path: its centre is at centres[k] at times[k],
/// moves linearly in between, stands at centres.front() before times.front() and at
/// centres.back() after times.back().
struct MovingDisc {
  std::string name;                     ///< for messages
  double radius = 0.0;                  ///< [m] > 0
  std::vector<double> times;            ///< [s] at least one, finite, strictly increasing
  std::vector<Eigen::Vector2d> centres; ///< [m] one per time
  /// [m] the centre at time t [s] (NaN counts as before the path).
  /// \throws Error(kInvalidArgument) when times is empty or centres has another size.
  Eigen::Vector2d CentreAt(double t) const;
  /// [m/s] The velocity of the piece that holds t (right limit at a waypoint; zero outside the
  /// path). \throws as CentreAt.
  Eigen::Vector2d VelocityAt(double t) const;
};

struct VelocityObstacleOptions {
  double time_step = 0.1;        ///< [s] control period, > 0
  double horizon = 3.0;          ///< [s] look-ahead of each velocity obstacle, > 0
  int heading_samples = 48;      ///< candidate directions per speed, >= 4
  int speed_samples = 6;         ///< candidate speeds in (0, max], >= 1 (standing still is always a candidate)
  double margin = 0.05;          ///< [m] added to every disc's radius while steering, >= 0
  /// [m] >= 0: the final approach (brake, then the exact straight rest-to-rest motion onto the
  /// goal in (x, y, θ)) is tried once the point where the base would come to rest is within
  /// max(goal_tolerance, 0.1 m) of the goal in the plane; the trajectory always ends exactly on it.
  double goal_tolerance = 1e-3;
  double max_duration = 120.0;   ///< [s] of simulated time before giving up, > 0
};

struct VelocityObstacleResult {
  bool reached = false;
  /// Why it did not reach the goal (boxed in, out of simulated time, stopped), with where and when.
  std::string message;
  /// (x, y, θ) from t = 0, constant acceleration per step, starting and ending at rest; when not
  /// reached, the motion up to where it stopped.
  TimedTrajectory trajectory;
  JointPath path;                ///< the state at every step boundary
  int steps = 0;
  /// [m] smallest distance between the base's bounding disc and a moving disc (radii
  /// subtracted, margin not) over the step boundaries and the final approach's states (every
  /// 10 ms); +inf without discs. The caller's own check between them is the one to trust.
  double min_disc_distance = 0.0;
  double seconds = 0.0;          ///< wall-clock time spent
};

/// Plans a planar base (`checker`'s robot must have kind kPlanar: (x, y, θ)) from start to goal
/// among `discs`. The base is its bounding disc in the plane (centred on (x, y), the farthest
/// extent of its collision shapes about the body z axis: exact for spheres and upright cylinders
/// and capsules, their bounding ball otherwise) against the discs, inflated by `margin`.
///
/// Each step of `time_step` has constant acceleration per coordinate. Candidate end velocities:
/// standing still, the preferred velocity, the current one and a polar grid (speed_samples ×
/// heading_samples up to min(max_velocity[0], max_velocity[1]), aligned with the preferred
/// direction), each moved into the box reachable in one step (|Δv_i| ≤ max_acceleration_i·dt,
/// |v_i| ≤ max_velocity_i). The preferred velocity points at the target at that planar speed,
/// slowed to √(2·a·d) with d the path left and a = min(max_acceleration[0], [1]). Candidates
/// outside every velocity obstacle are ranked by |v − v_pref| + 0.1·|v − v_now|; when there are
/// none, by the largest time to collision. The best ranked whose step stays within the joint
/// limits, is free of the scene along its curve (IsCurveCertified; certified when the checker
/// certifies, else states 0.005 apart) and can then stop free of the scene is taken (at most 12
/// are checked; each is tried with the planned turn, then with the turn braked); else the base
/// brakes along the stop checked at the previous step, which is always free.
///
/// `guide`: a collision-free path through the static scene (e.g. the pipeline's plan without the
/// discs), (x, y, θ) per vertex. The target is the next guide vertex, advanced while the one
/// after it is in sight (the straight (x, y, θ) motion from the current state to it free per
/// IsMotionFree) or the current one is within 5 cm, so it is the farthest vertex of the run in
/// sight beyond the last one passed; after a step the scene blocked, an out-of-sight target
/// falls back to the latest earlier vertex in sight. The goal is the target after the last
/// vertex; empty = straight at the goal (static obstacles between can then trap the base: boxed
/// in). The heading follows the straight segment to the target: from the heading where the target
/// was taken up to the target's θ in proportion to the planar distance covered (without a guide:
/// from the start's to the goal's), within the angular velocity and acceleration limits (index 2).
///
/// Ends with the final approach (see goal_tolerance) when it is free of the scene and keeps
/// `margin` from every disc along their true paths (checked every 10 ms): `trajectory` then
/// starts and ends at rest, its end position is exactly `goal`, and every piece keeps the
/// velocity and acceleration limits exactly (max_jerk and max_effort are not considered:
/// constant acceleration per step). Otherwise it brakes to rest and returns reached = false with
/// what stopped it and where: simulated time beyond max_duration, `termination`, or boxed in (no
/// progress of 1 cm along the path or 0.01 rad of heading for 10 s of simulated time); also
/// when start or goal is in collision.
/// \throws Error(kInvalidArgument) naming the field for a robot that is not planar, sizes,
/// non-finite values or start/goal outside the joint limits, a disc with no times, times not
/// increasing or mismatched centres, a radius not > 0, guide vertices that are not (x, y, θ),
/// limits that fail Validate(3), options out of range (heading_samples in [4, 720],
/// speed_samples in [1, 100], at most 1e7 steps).
VelocityObstacleResult PlanWithVelocityObstacles(const CollisionChecker& checker, const Eigen::VectorXd& start,
                                                 const Eigen::VectorXd& goal, const std::vector<MovingDisc>& discs,
                                                 const KinematicLimits& limits, const JointPath& guide,
                                                 const VelocityObstacleOptions& options,
                                                 const Termination& termination);

}  // namespace chasles
