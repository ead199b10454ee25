#pragma once
/// \file
/// The trajectory stage of the pipeline: a collision-free path → the trajectory the user asked
/// for (time-optimal parameterisation, collocation, B-spline smoothing, or stops at every
/// waypoint), verified, with its quality figures. Plan runs it after shortcutting; the Optimize
/// RPC runs it on a user's own path.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "chasles/collision/collision_checker.h"
#include "chasles/optimizers/collocation.h"
#include "chasles/optimizers/optimizer_report.h"
#include "chasles/optimizers/spline_smoothing.h"
#include "chasles/optimizers/time_parameterization.h"
#include "chasles/optimizers/timed_trajectory.h"
#include "chasles/optimizers/verification.h"
#include "chasles/planners/termination.h"

namespace chasles {

/// How the path becomes a trajectory.
enum class PostProcessing {
  kAuto,         ///< kTimeOptimal, or kCollocation when max_jerk is set
  kTimeOptimal,  ///< exact time-optimal parameterisation with bounded-deviation blends
  kCollocation,  ///< direct collocation in Ipopt, warm-started from the exact parameterisation
  kSpline,       ///< B-spline smoothing in NLopt, started from the exact parameterisation
  kNone,         ///< no optimisation: the exact rest-to-rest profile, stopping at every waypoint
};
const char* ToString(PostProcessing method);  ///< "auto", "topp", "collocation", "spline", "none"

/// What the user asks of the trajectory (proto TrajectoryOptions, resolved defaults).
struct TrajectorySpec {
  PostProcessing method = PostProcessing::kAuto;
  Eigen::VectorXd max_velocity;      ///< empty = model limits; else > 0, capped at the model's
  Eigen::VectorXd max_acceleration;  ///< empty = 2 × the velocity limits
  Eigen::VectorXd max_jerk;          ///< empty = unlimited; else > 0 [rad/s³]
  Eigen::VectorXd max_effort;        ///< empty = unlimited; else > 0 [N·m]/[N] (robot with inertia)
  Eigen::Vector3d gravity = Eigen::Vector3d(0.0, 0.0, -9.81);  ///< for efforts [m/s²]
  double max_deviation = 0.05;       ///< time-optimal blends [rad], >= 0
  Eigen::VectorXd start_velocity, end_velocity;  ///< empty = at rest (Optimize only)
  CollocationOptions collocation;
  /// Collocation free of the path (only its ends kept); false = along the path within
  /// collocation_corridor.
  bool collocation_free = false;
  double collocation_corridor = 0.0;  ///< [rad] > 0; 0 = max_deviation
  SplineOptions spline;
};

/// The limits the trajectory must respect: overrides capped at the model's velocity limits,
/// acceleration defaulting to 2 × the velocity limit per second.
/// \throws Error(kInvalidArgument) naming `trajectory.<field>[i]` for sizes, non-finite or
///         non-positive values, and max_effort on a robot without inertia.
KinematicLimits ResolveLimits(const RobotModel& robot, const TrajectorySpec& spec);

/// Expected outcomes of the stage.
enum class TrajectoryStageCode {
  kSuccess,
  kInfeasibleLimits,    ///< max_effort cannot be met (e.g. gravity alone exceeds it)
  kVerificationFailed,  ///< even the exact parameterisation failed dense verification (a path in collision)
};

/// What the optimiser did, for the response.
struct OptimizerSummary {
  PostProcessing requested = PostProcessing::kAuto;
  PostProcessing used = PostProcessing::kTimeOptimal;  ///< what the returned trajectory is
  bool fell_back = false;   ///< the requested optimiser's result was not used (reason in `message`)
  std::string message;
  OptimizerReport report;   ///< of the collocation / spline solve (zeros otherwise)
  double topp_duration = 0.0;           ///< [s] TOPP on the same path (COLLOCATION / SPLINE); 0 = unknown
  double duration_ratio_to_topp = 0.0;  ///< returned duration / topp_duration; 0 = unknown
  TimeOptimalReport time_optimal;  ///< of the exact parameterisation
};

/// What was done when the first trajectory failed dense verification (a contact the planner's
/// or the blends' checks stepped over, a limit missed by rounding): the failure, then each repair
/// tried with its result. Empty when the first trajectory passed.
struct VerificationRepair {
  std::string failure;               ///< what the first verification found (VerificationReport::reason)
  std::vector<std::string> actions;  ///< repairs tried, in order, each with its result
  bool repaired = false;             ///< the returned trajectory is a repair's, verified
  double seconds = 0.0;              ///< wall time of the repairs [s]
  bool attempted() const { return !failure.empty(); }
  /// "<failure>; repairs tried: <action>; <action>" for a message.
  std::string Describe() const;
};

struct TrajectoryStageResult {
  TrajectoryStageCode code = TrajectoryStageCode::kVerificationFailed;
  std::string message;
  KinematicLimits limits;
  TimedTrajectory trajectory;        ///< empty unless kSuccess
  VerificationReport verification;
  TrajectoryQuality quality;
  OptimizerSummary optimizer;
  double parameterize_seconds = 0.0;  ///< the exact parameterisation
  double optimize_seconds = 0.0;      ///< collocation / spline
  double verify_seconds = 0.0;
  double quality_seconds = 0.0;       ///< MeasureTrajectory: the quality figures (min_clearance bound)
  /// When the exact parameterisation failed verification with blended corners: the path retimed
  /// stopping at every waypoint (its straight segments are what the planner and the shortcuts
  /// checked), verified in turn.
  VerificationRepair repair;
};

/// Runs the stage on `path` (start … goal, collision-free segments expected): the exact
/// parameterisation (with max_jerk: jerk-limited stops at every waypoint), then the requested
/// optimiser warm-started from it, then dense verification (collisions at max_joint_step,
/// limits exactly). An optimiser that fails, or whose result fails verification, is replaced by
/// the exact parameterisation (fell_back, with the reason); the exact one is verified too, so
/// nothing that violates a limit or collides is ever returned. When it fails with blended
/// corners, the path is retimed without blends (stopping at each waypoint) and verified again
/// (`repair` says so); kVerificationFailed only when that fails too. Optimisers stop when
/// `termination` does (deadline, cancellation) and fall back.
/// \throws Error(kInvalidArgument) for invalid limits/options (named), and kTimeOptimal with
///         max_jerk set.
TrajectoryStageResult RunTrajectoryStage(const JointPath& path, const CollisionChecker& checker,
                                         const TrajectorySpec& spec, double max_joint_step,
                                         const Termination& termination);

/// How much a reply may carry, checked from the trajectory's duration before any sample is made.
struct SampleCap {
  std::uint64_t max_samples = 1000000;          ///< samples of one trajectory
  std::uint64_t max_reply_bytes = 64ull << 20;  ///< estimated encoded bytes of those samples
  std::string field = "trajectory.sample_period";  ///< the period's field, named in the error
  std::string reply_cap_source = "the reply cap";   ///< where max_reply_bytes comes from, for the error
  /// Encoded bytes of `samples` samples of a `dofs`-joint robot (t, q, q̇, q̈ and τ as packed
  /// doubles), an upper estimate.
  static std::uint64_t EstimateBytes(std::uint64_t samples, int dofs);
  /// \throws Error(kResourceExhausted) naming `field`, the estimate, the cap and the period that
  ///         would fit, when sampling `duration` seconds at `period` would exceed a cap.
  void Check(double duration, double period, int dofs) const;
};

/// Samples at `period` (TimedTrajectory::Sample) with positions clamped to the joint limits
/// (verification bounded any excess by 1e-12: rounding) and, when the robot has inertia on every
/// moving link, the inverse-dynamics efforts under `gravity`.
/// \throws Error(kResourceExhausted) before sampling when `cap` would be exceeded.
std::vector<TrajectorySample> SampleTrajectory(const TimedTrajectory& trajectory, const RobotModel& robot,
                                               double period, const Eigen::Vector3d& gravity,
                                               const SampleCap& cap = {});

/// The Optimize RPC in domain types: a user's own path → a verified trajectory.
struct OptimizeQuery {
  std::shared_ptr<const CollisionChecker> checker;
  JointPath path;                 ///< >= 1 waypoint
  TrajectorySpec trajectory;      ///< gravity included
  double sample_period = 0.01;    ///< [s], in [1e-4, 1]
  /// true: no samples when the trajectory has a knots form (degree <= 2; the caller returns
  /// knots instead); a trajectory of higher degree is still sampled.
  bool knots_replace_samples = false;
  double collision_resolution = 0.005;  ///< [rad], in [1e-4, 0.1]
  SampleCap sample_cap{1000000, 64ull << 20, "options.sample_period"};
};

struct OptimizeOutcome {
  /// kSuccess, kVerificationFailed (the input path leaves the joint limits or collides: message
  /// says where) or kInfeasibleLimits.
  TrajectoryStageCode code = TrajectoryStageCode::kVerificationFailed;
  std::string message;
  TrajectoryStageResult stage;
  std::vector<TrajectorySample> samples;  ///< at sample_period (efforts when computed)
  double sample_seconds = 0.0;            ///< SampleTrajectory (with torques)
  double total_seconds = 0.0;
};

/// Checks the path (sizes, finite, within joint limits: INVALID_ARGUMENT naming
/// `path[k].positions[i]`; every segment collision-free at collision_resolution, else the
/// kVerificationFailed outcome naming the segment and the contact), then RunTrajectoryStage.
OptimizeOutcome OptimizePath(const OptimizeQuery& query, const Termination& termination);

}  // namespace chasles
