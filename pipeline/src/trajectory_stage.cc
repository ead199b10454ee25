#include "chasles/pipeline/trajectory_stage.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>
#include <string>

#include "chasles/robot/dynamics.h"
#include "chasles/robot/error.h"

namespace chasles {
namespace {

using Clock = std::chrono::steady_clock;

double SecondsSince(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

void CheckVector(const Eigen::VectorXd& v, int n, const std::string& field) {
  if (v.size() == 0) return;
  if (v.size() != n) {
    ThrowInvalid("trajectory." + field + " has " + std::to_string(v.size()) + " values, the robot has " +
                 std::to_string(n) + " joints");
  }
  for (int i = 0; i < n; ++i) {
    if (!std::isfinite(v[i]) || v[i] <= 0) {
      ThrowInvalid("trajectory." + field + "[" + std::to_string(i) + "] = " + FormatNumber(v[i]) + " must be finite and > 0");
    }
  }
}

/// ∫‖q⃛‖² dt of the trajectory as an optimiser's objective sees it: JerkIntegral inside the
/// pieces, +inf when an acceleration jumps between pieces (a step has unbounded jerk), as TOPP's do.
double ObjectiveJerkIntegral(const TimedTrajectory& trajectory) {
  const std::vector<TimedTrajectory::Piece>& pieces = trajectory.pieces();
  for (std::size_t k = 0; k + 1 < pieces.size(); ++k) {
    for (int i = 0; i < trajectory.num_dofs(); ++i) {
      const double end = pieces[k].Derivative(i, 2, pieces[k].duration), next = pieces[k + 1].Derivative(i, 2, 0.0);
      if (std::abs(end - next) > 1e-9 * std::max(1.0, std::abs(next))) return std::numeric_limits<double>::infinity();
    }
  }
  return JerkIntegral(trajectory);
}

}  // namespace

std::string VerificationRepair::Describe() const {
  std::string text = failure;
  if (actions.empty()) return text;
  text += "; repairs tried: ";
  for (std::size_t k = 0; k < actions.size(); ++k) text += (k ? "; " : "") + actions[k];
  return text;
}

const char* ToString(PostProcessing method) {
  switch (method) {
    case PostProcessing::kAuto: return "auto";
    case PostProcessing::kTimeOptimal: return "topp";
    case PostProcessing::kCollocation: return "collocation";
    case PostProcessing::kSpline: return "spline";
    case PostProcessing::kNone: return "none";
  }
  return "unknown";
}

KinematicLimits ResolveLimits(const RobotModel& robot, const TrajectorySpec& spec) {
  const int n = robot.num_dofs();
  CheckVector(spec.max_velocity, n, "max_velocity");
  CheckVector(spec.max_acceleration, n, "max_acceleration");
  CheckVector(spec.max_jerk, n, "max_jerk");
  CheckVector(spec.max_effort, n, "max_effort");
  if (spec.max_effort.size() != 0 && !HasInertia(robot)) {
    ThrowInvalid("trajectory.max_effort is set, but robot '" + robot.name() +
                 "' has no inertia on every moving link, so its torques are unknown");
  }
  if (!std::isfinite(spec.max_deviation) || spec.max_deviation < 0.0 || spec.max_deviation > 1.0) {
    ThrowInvalid("trajectory.max_deviation = " + FormatNumber(spec.max_deviation) + " must be within [0, 1] rad");
  }
  KinematicLimits limits;
  limits.max_velocity = robot.velocity_limits();
  if (spec.max_velocity.size() > 0) limits.max_velocity = spec.max_velocity.cwiseMin(robot.velocity_limits());
  limits.max_acceleration =
      spec.max_acceleration.size() > 0 ? spec.max_acceleration : Eigen::VectorXd(2.0 * limits.max_velocity);
  limits.max_jerk = spec.max_jerk;
  limits.max_effort = spec.max_effort;
  limits.gravity = spec.gravity;
  return limits;
}

TrajectoryStageResult RunTrajectoryStage(const JointPath& path, const CollisionChecker& checker,
                                         const TrajectorySpec& spec, double max_joint_step,
                                         const Termination& termination) {
  const RobotModel& robot = checker.robot();
  TrajectoryStageResult out;
  out.limits = ResolveLimits(robot, spec);
  const KinematicLimits& limits = out.limits;
  const bool jerk = limits.max_jerk.size() != 0;
  PostProcessing method = spec.method;
  if (method == PostProcessing::kAuto) method = jerk ? PostProcessing::kCollocation : PostProcessing::kTimeOptimal;
  if (method == PostProcessing::kTimeOptimal && jerk) {
    ThrowInvalid("trajectory.max_jerk is set, but post_processing TOPP has acceleration steps (unbounded jerk); "
                 "use COLLOCATION, SPLINE, or NONE (jerk-limited stops at every waypoint)");
  }
  out.optimizer.requested = spec.method;

  // 1. The exact parameterisation: the answer for TOPP / NONE, the warm start otherwise.
  const auto time_optimal_options = [&](double max_deviation) {
    TimeOptimalOptions options;
    options.max_deviation = max_deviation;
    options.start_velocity = spec.start_velocity;
    options.end_velocity = spec.end_velocity;
    options.max_joint_step = max_joint_step;
    return options;
  };
  auto t = Clock::now();
  TimedTrajectory exact;
  PostProcessing exact_kind = method == PostProcessing::kNone ? PostProcessing::kNone : PostProcessing::kTimeOptimal;
  try {
    if (jerk) {
      if ((spec.start_velocity.size() != 0 && !spec.start_velocity.isZero(0.0)) ||
          (spec.end_velocity.size() != 0 && !spec.end_velocity.isZero(0.0))) {
        ThrowInvalid("start_velocity / end_velocity must be zero when trajectory.max_jerk is set");
      }
      exact = ParameterizeRestToRest(path, limits);
      exact_kind = PostProcessing::kNone;
    } else {
      exact = ParameterizeTimeOptimal(path, limits,
                                      time_optimal_options(method == PostProcessing::kNone ? 0.0 : spec.max_deviation),
                                      &checker, &out.optimizer.time_optimal);
    }
  } catch (const Error& e) {
    if (e.code() != ErrorCode::kFailedPrecondition) throw;
    out.parameterize_seconds = SecondsSince(t);
    out.code = TrajectoryStageCode::kInfeasibleLimits;
    out.message = e.what();
    return out;
  }
  out.parameterize_seconds = SecondsSince(t);

  VerificationOptions verify;
  verify.max_joint_step = max_joint_step;
  verify.start_velocity = spec.start_velocity;
  verify.end_velocity = spec.end_velocity;
  const auto stop = [&termination] {
    const StopReason reason = termination.Reason();
    return reason == StopReason::kCancelled || reason == StopReason::kDeadline;
  };

  // 2. The requested optimiser, warm-started from the exact trajectory.
  TimedTrajectory chosen = exact;
  out.optimizer.used = exact_kind;
  const bool optimise = method == PostProcessing::kCollocation || method == PostProcessing::kSpline;
  const double corridor = spec.collocation_corridor > 0.0 ? spec.collocation_corridor : spec.max_deviation;
  const bool along = method == PostProcessing::kCollocation && !spec.collocation_free;
  if (along && !(corridor > 0.0)) {
    ThrowInvalid("trajectory.max_deviation = 0 leaves COLLOCATION along the path no corridor: set "
                 "trajectory.collocation.corridor > 0, or use NONE to stop at every waypoint");
  }
  if (method == PostProcessing::kCollocation && spec.collocation_free && path.size() > 1 &&
      path.front() == path.back() && (spec.start_velocity.size() == 0 || spec.start_velocity.isZero(0.0)) &&
      (spec.end_velocity.size() == 0 || spec.end_velocity.isZero(0.0))) {
    ThrowInvalid("trajectory.collocation.path_mode = FREE keeps only the path's ends, and path[0] = path[" +
                 std::to_string(path.size() - 1) + "] with both ends at rest: the minimum-time trajectory would "
                 "not move; use ALONG_PATH to follow the path");
  }
  if (optimise) {
    // The reference for the response's duration ratio: TOPP on the same path and limits.
    if (exact_kind == PostProcessing::kTimeOptimal) {
      out.optimizer.topp_duration = exact.duration();
    } else {
      KinematicLimits unjerked = limits;
      unjerked.max_jerk.resize(0);
      try {
        out.optimizer.topp_duration =
            ParameterizeTimeOptimal(path, unjerked, time_optimal_options(spec.max_deviation), &checker).duration();
      } catch (const Error& e) {
        if (e.code() != ErrorCode::kFailedPrecondition) throw;
      }
    }
    t = Clock::now();
    const char* name = method == PostProcessing::kCollocation ? "collocation" : "spline smoothing";
    OptimizerReport report;
    TimedTrajectory candidate;
    if (method == PostProcessing::kCollocation) {
      CollocationOptions options = spec.collocation;
      options.stop = stop;
      options.corridor = along ? corridor : 0.05;
      // Along the path the warm start must be inside the corridor: TOPP's blends are redone
      // within it when max_deviation is wider.
      TimedTrajectory narrower;
      if (along && exact_kind == PostProcessing::kTimeOptimal && spec.max_deviation > corridor) {
        narrower = ParameterizeTimeOptimal(path, limits, time_optimal_options(corridor), &checker);
      }
      CollocationResult result = OptimizeByCollocation(narrower.empty() ? exact : narrower, limits, options, &checker,
                                                       along ? &path : nullptr);
      report = result.report;
      candidate = std::move(result.trajectory);
    } else {
      SplineOptions options = spec.spline;
      options.stop = stop;
      SplineResult result = SmoothWithBSpline(exact, limits, options, &checker);
      report = result.report;
      candidate = std::move(result.trajectory);
    }
    out.optimize_seconds = SecondsSince(t);
    out.optimizer.report = report;
    if (!report.ok) {
      out.optimizer.fell_back = true;
      out.optimizer.message = std::string(name) + " did not meet the limits (" + report.message +
                              "); returned the exact parameterisation instead";
    } else {
      t = Clock::now();
      const VerificationReport checked = VerifyTrajectory(candidate, path.front(), path.back(), checker, limits, verify);
      out.verify_seconds += SecondsSince(t);
      // The better under the optimiser's objective T + w·∫‖q⃛‖²: TOPP's acceleration steps have
      // unbounded jerk, so with w > 0 only a jerk-limited warm start can win.
      const double w = method == PostProcessing::kCollocation ? spec.collocation.jerk_weight : spec.spline.jerk_weight;
      const auto objective = [w](const TimedTrajectory& trajectory) {
        return trajectory.duration() + (w > 0.0 ? w * ObjectiveJerkIntegral(trajectory) : 0.0);
      };
      const double mine = objective(candidate), theirs = objective(exact);
      if (checked.ok && !(mine > theirs)) {
        chosen = std::move(candidate);
        out.optimizer.used = method;
        out.verification = checked;
        out.optimizer.message = std::string(name) + ": " + report.message;
      } else if (checked.ok) {
        out.optimizer.fell_back = true;
        out.optimizer.message = std::string(name) + " gave a worse trajectory than its warm start under its objective (" +
                                FormatNumber(mine) + " against " + FormatNumber(theirs) + "; durations " +
                                FormatNumber(candidate.duration()) + " s against " + FormatNumber(exact.duration()) +
                                " s); returned the warm start";
      } else {
        out.optimizer.fell_back = true;
        out.optimizer.message = std::string(name) + " result failed dense verification (" + checked.reason +
                                "); returned the exact parameterisation instead";
      }
    }
  }

  // 3. Verify what leaves (unless the optimiser's result was just verified).
  if (out.optimizer.used == exact_kind) {
    t = Clock::now();
    out.verification = VerifyTrajectory(chosen, path.front(), path.back(), checker, limits, verify);
    out.verify_seconds += SecondsSince(t);
    if (out.optimizer.message.empty()) out.optimizer.message = out.optimizer.time_optimal.message;
  }
  // 4. Repair: the blends are the only motion the path's checks did not cover; stop at every
  // waypoint instead.
  if (!out.verification.ok) {
    t = Clock::now();
    out.repair.failure = out.verification.reason;
    const int blends = out.optimizer.time_optimal.blends;
    if (exact_kind == PostProcessing::kTimeOptimal && blends > 0) {
      TimeOptimalReport report;
      try {
        TimedTrajectory stopped = ParameterizeTimeOptimal(path, limits, time_optimal_options(0.0), &checker, &report);
        const VerificationReport checked = VerifyTrajectory(stopped, path.front(), path.back(), checker, limits, verify);
        std::string action = "retimed without the " + std::to_string(blends) + " corner blend" +
                             (blends == 1 ? "" : "s") + " (stopping at every waypoint): ";
        if (checked.ok) {
          action += "verified, " + FormatNumber(stopped.duration()) + " s instead of " +
                    FormatNumber(chosen.duration()) + " s";
          chosen = std::move(stopped);
          out.verification = checked;
          out.optimizer.time_optimal = report;
          out.repair.repaired = true;
        } else {
          action += "failed too (" + checked.reason + ")";
        }
        out.repair.actions.push_back(std::move(action));
      } catch (const Error& e) {
        if (e.code() != ErrorCode::kFailedPrecondition) throw;
        out.repair.actions.push_back(std::string("retiming without corner blends failed: ") + e.what());
      }
    }
    out.repair.seconds = SecondsSince(t);
  }
  if (!out.verification.ok) {
    out.code = TrajectoryStageCode::kVerificationFailed;
    out.message = "the trajectory failed dense verification: " + out.repair.Describe();
    return out;
  }
  t = Clock::now();
  out.quality = MeasureTrajectory(chosen, limits, path, &checker, std::max(max_joint_step, 0.01));
  if (out.optimizer.topp_duration > 0.0) out.optimizer.duration_ratio_to_topp = chosen.duration() / out.optimizer.topp_duration;
  out.quality_seconds = SecondsSince(t);
  out.trajectory = std::move(chosen);
  out.code = TrajectoryStageCode::kSuccess;
  return out;
}

std::uint64_t SampleCap::EstimateBytes(std::uint64_t samples, int dofs) {
  // Per sample: the submessage's tag and length (≤ 4), t (9), four packed double fields
  // (tag, length ≤ 2, 8 bytes a joint).
  const std::uint64_t per_sample = 4 + 9 + 4 * (3 + 8 * static_cast<std::uint64_t>(std::max(dofs, 0)));
  return samples * per_sample;
}

void SampleCap::Check(double duration, double period, int dofs) const {
  if (!(duration >= 0.0) || !(period > 0.0)) return;  // Sample() names these
  const double estimate = std::floor(duration / period) + 2.0;
  const double per_sample = static_cast<double>(EstimateBytes(1, dofs));
  const double bytes = estimate * per_sample;
  const double fit_samples =
      std::min(static_cast<double>(max_samples), std::floor(static_cast<double>(max_reply_bytes) / per_sample));
  if (estimate <= static_cast<double>(max_samples) && bytes <= static_cast<double>(max_reply_bytes)) return;
  // Rounded up to 3 significant digits, so the period suggested does fit.
  const double exact_period = duration / std::max(1.0, fit_samples - 2.0);
  const double scale = std::pow(10.0, std::floor(std::log10(exact_period)) - 2.0);
  const double smallest_period = std::ceil(exact_period / scale) * scale;
  char duration_text[32];
  std::snprintf(duration_text, sizeof(duration_text), "%.4g", duration);
  std::ostringstream message;
  message << field << " = " << FormatNumber(period) << " s over the " << duration_text
          << " s trajectory gives about " << static_cast<std::uint64_t>(estimate) << " samples (~"
          << static_cast<std::uint64_t>(std::ceil(bytes / 1048576.0)) << " MiB for " << dofs << " joints), more than ";
  if (estimate > static_cast<double>(max_samples)) {
    message << "the server's cap of " << max_samples << " samples (--max-samples)";
  } else {
    message << "the server's reply cap of " << (max_reply_bytes >> 20) << " MiB (" << reply_cap_source << ")";
  }
  char period_text[32];
  std::snprintf(period_text, sizeof(period_text), "%.3g", smallest_period);
  message << "; use a " << field << " of at least " << period_text
          << " s, or sample the trajectory on the client";
  ThrowResourceExhausted(message.str());
}

std::vector<TrajectorySample> SampleTrajectory(const TimedTrajectory& trajectory, const RobotModel& robot,
                                               double period, const Eigen::Vector3d& gravity, const SampleCap& cap) {
  cap.Check(trajectory.duration(), period, robot.num_dofs());
  std::vector<TrajectorySample> samples = trajectory.Sample(period);
  const bool effort = HasInertia(robot);
  DynamicsOptions dynamics;
  dynamics.gravity = gravity;
  for (TrajectorySample& sample : samples) {
    sample.q = sample.q.cwiseMax(robot.lower_limits()).cwiseMin(robot.upper_limits());
    if (effort) sample.effort = InverseDynamics(robot, sample.q, sample.qd, sample.qdd, dynamics);
  }
  return samples;
}

OptimizeOutcome OptimizePath(const OptimizeQuery& query, const Termination& termination) {
  const auto t_start = Clock::now();
  if (!query.checker) ThrowInvalid("robot/scene: no collision checker was built for the query");
  const CollisionChecker& checker = *query.checker;
  const RobotModel& robot = checker.robot();
  if (query.path.empty()) ThrowInvalid("path has no waypoints: give at least one (or a trajectory with points)");
  for (std::size_t k = 0; k < query.path.size(); ++k) {
    robot.ValidateConfiguration(query.path[k], "path[" + std::to_string(k) + "].positions");
  }
  if (!std::isfinite(query.sample_period) || query.sample_period < 1e-4 || query.sample_period > 1.0) {
    ThrowInvalid("options.sample_period = " + FormatNumber(query.sample_period) + " must be within [0.0001, 1]");
  }
  if (!std::isfinite(query.collision_resolution) || query.collision_resolution < 1e-4 ||
      query.collision_resolution > 0.1) {
    ThrowInvalid("collision_resolution = " + FormatNumber(query.collision_resolution) + " must be within [0.0001, 0.1]");
  }
  OptimizeOutcome out;
  const auto finish = [&](TrajectoryStageCode code, std::string message) {
    out.code = code;
    out.message = std::move(message);
    out.total_seconds = SecondsSince(t_start);
    return out;
  };
  ResolveLimits(robot, query.trajectory);  // named errors before any work
  // The user's path must be collision-free: say which segment is not, and why.
  const auto describe = [](const CollisionResult& contact) {
    if (!contact.violation.empty()) return "it breaks " + contact.violation;
    return "link '" + contact.link_a + "' touches " + (contact.self_collision ? "link '" : "'") + contact.other + "'";
  };
  if (query.path.size() == 1 && !checker.IsValid(query.path.front())) {
    return finish(TrajectoryStageCode::kVerificationFailed,
                  "the input path is not collision-free: path[0]: " + describe(checker.Check(query.path.front())));
  }
  for (std::size_t k = 0; k + 1 < query.path.size(); ++k) {
    const Eigen::VectorXd& a = query.path[k];
    const Eigen::VectorXd& b = query.path[k + 1];
    if (checker.IsMotionValid(a, b, query.collision_resolution)) continue;
    std::string where = "segment path[" + std::to_string(k) + "] → path[" + std::to_string(k + 1) + "]";
    std::string what = "it collides between its checked states, or leaves its path constraints";
    std::string broken = "is not collision-free";
    const int steps = std::max(1, static_cast<int>(std::ceil((b - a).cwiseAbs().maxCoeff() / query.collision_resolution)));
    for (int s = 0; s <= steps; ++s) {
      const double fraction = static_cast<double>(s) / steps;
      const CollisionResult contact = checker.Check(a + (b - a) * fraction);
      if (!contact.in_collision) continue;
      what = "at s = " + FormatNumber(fraction) + " " + describe(contact);
      if (!contact.violation.empty()) broken = "leaves its path constraints";
      break;
    }
    return finish(TrajectoryStageCode::kVerificationFailed, "the input path " + broken + ": " + where + " " + what);
  }
  out.stage = RunTrajectoryStage(query.path, checker, query.trajectory, std::min(0.005, query.collision_resolution),
                                 termination);
  if (out.stage.code != TrajectoryStageCode::kSuccess) return finish(out.stage.code, out.stage.message);
  const auto t_sample = Clock::now();
  if (!query.knots_replace_samples || out.stage.trajectory.degree() > 2) {
    out.samples =
        SampleTrajectory(out.stage.trajectory, robot, query.sample_period, query.trajectory.gravity, query.sample_cap);
  }
  out.sample_seconds = SecondsSince(t_sample);
  std::string message = std::string(ToString(out.stage.optimizer.used)) + " trajectory of " +
                        FormatNumber(out.stage.trajectory.duration()) + " s, verified at " +
                        std::to_string(out.stage.verification.states_checked) + " states";
  if (out.stage.optimizer.fell_back) message += "; " + out.stage.optimizer.message;
  return finish(TrajectoryStageCode::kSuccess, message);
}

}  // namespace chasles
