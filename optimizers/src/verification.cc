#include "chasles/optimizers/verification.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "chasles/robot/error.h"
#include "internal.h"

namespace chasles {
namespace {

using optimizers_internal::Phase;
using optimizers_internal::PhaseAt;
using optimizers_internal::PhaseDuration;
using optimizers_internal::PhaseStart;
using optimizers_internal::SegmentStateInPhase;
using Segment = TimedTrajectory::Segment;

std::string At(double t) { return " at t = " + FormatNumber(t) + " s"; }

/// Local time at which the segment's profile reaches path parameter s ∈ [0, 1].
double TimeAtParameter(const Segment& seg, double s) {
  if (!(seg.s_acc > 0.0) || !(seg.duration() > 0.0)) return 0.0;
  const double s1 = 0.5 * seg.s_acc * seg.t_acc * seg.t_acc;  // covered while accelerating
  if (s <= s1) return std::sqrt(2.0 * s / seg.s_acc);
  if (s >= 1.0 - s1) return std::max(0.0, seg.duration() - std::sqrt(2.0 * std::max(0.0, 1.0 - s) / seg.s_acc));
  return seg.t_acc + (s - s1) / (seg.s_acc * seg.t_acc);
}

class Verifier {
 public:
  Verifier(const CollisionChecker& checker, const KinematicLimits& limits,
           const VerificationOptions& options, VerificationReport* report)
      : checker_(checker), robot_(checker.robot()), limits_(limits), options_(options), report_(report) {}

  std::string JointName(int i) const {
    std::string name = "joint " + std::to_string(i);
    if (i < static_cast<int>(robot_.dof_names().size())) name += " '" + robot_.dof_names()[i] + "'";
    return name;
  }

  /// Velocity and acceleration of one state against the limits.
  bool CheckDynamics(const TrajectorySample& x) {
    const double slack = 1.0 + options_.limit_tolerance;
    for (int i = 0; i < x.qd.size(); ++i) {
      const double ratio = std::abs(x.qd[i]) / limits_.max_velocity[i];
      report_->max_velocity_ratio = std::max(report_->max_velocity_ratio, ratio);
      if (!(ratio <= slack)) {
        return Fail(JointName(i) + " velocity " + FormatNumber(x.qd[i]) + " rad/s exceeds limit " +
                    FormatNumber(limits_.max_velocity[i]) + " rad/s" + At(x.t));
      }
    }
    for (int i = 0; i < x.qdd.size(); ++i) {
      const double ratio = std::abs(x.qdd[i]) / limits_.max_acceleration[i];
      report_->max_acceleration_ratio = std::max(report_->max_acceleration_ratio, ratio);
      if (!(ratio <= slack)) {
        return Fail(JointName(i) + " acceleration " + FormatNumber(x.qdd[i]) + " rad/s² exceeds limit " +
                    FormatNumber(limits_.max_acceleration[i]) + " rad/s²" + At(x.t));
      }
    }
    return true;
  }

  /// Position limits, then collisions (self and scene) of one state.
  bool CheckState(const TrajectorySample& x) {
    const Eigen::VectorXd& lower = robot_.lower_limits();
    const Eigen::VectorXd& upper = robot_.upper_limits();
    for (int i = 0; i < x.q.size(); ++i) {
      if (!(x.q[i] >= lower[i] && x.q[i] <= upper[i])) {
        return Fail(JointName(i) + " position " + FormatNumber(x.q[i]) + " is outside its limits [" + FormatNumber(lower[i]) +
                    ", " + FormatNumber(upper[i]) + "]" + At(x.t));
      }
    }
    ++report_->states_checked;
    if (checker_.IsValid(x.q, &counters_)) return true;
    const CollisionResult contact = checker_.Check(x.q);
    if (!contact.in_collision) return Fail("state is invalid" + At(x.t) + " (rejected by the checker)");
    if (contact.self_collision) {
      return Fail("self-collision" + At(x.t) + " between link '" + contact.link_a + "' and link '" +
                  contact.other + "'");
    }
    return Fail("collision" + At(x.t) + " between link '" + contact.link_a + "' and '" + contact.other + "'");
  }

  bool Fail(const std::string& reason) {
    report_->reason = reason;
    return false;
  }

 private:
  const CollisionChecker& checker_;
  const RobotModel& robot_;
  const KinematicLimits& limits_;
  const VerificationOptions& options_;
  VerificationReport* report_;
  CheckCounters counters_;
};

/// Structural soundness of segment k: sizes, finite numbers, a profile that covers s ∈ [0, 1]
/// and continuity with the previous segment. Returns an empty string when sound.
std::string SegmentDefect(const TimedTrajectory& trajectory, std::size_t k, int n, double position_tolerance) {
  const Segment& seg = trajectory.segments()[k];
  const std::string name = "segment " + std::to_string(k);
  if (seg.a.size() != n || seg.b.size() != n) {
    return name + " has " + std::to_string(seg.a.size()) + "/" + std::to_string(seg.b.size()) +
           " values, robot has " + std::to_string(n) + " joints";
  }
  if (!seg.a.allFinite() || !seg.b.allFinite()) return name + " has a non-finite waypoint";
  for (double x : {seg.t0, seg.t_acc, seg.t_cruise, seg.s_acc}) {
    if (!std::isfinite(x) || x < 0.0) {
      return name + " has an invalid profile (t0 = " + FormatNumber(seg.t0) + ", t_acc = " + FormatNumber(seg.t_acc) +
             ", t_cruise = " + FormatNumber(seg.t_cruise) + ", s_acc = " + FormatNumber(seg.s_acc) + ")";
    }
  }
  const double s_end = seg.s_acc * seg.t_acc * (seg.t_acc + seg.t_cruise);
  if (seg.a != seg.b && !(std::abs(s_end - 1.0) <= 1e-9)) {
    return name + " profile covers s = " + FormatNumber(s_end) + " instead of 1" + At(seg.t0);
  }
  const double expected_t0 = k == 0 ? 0.0 : trajectory.segments()[k - 1].t0 + trajectory.segments()[k - 1].duration();
  if (!(std::abs(seg.t0 - expected_t0) <= 1e-9 * std::max(1.0, expected_t0))) {
    return name + " starts at t = " + FormatNumber(seg.t0) + " s, expected " + FormatNumber(expected_t0) + " s";
  }
  if (k > 0) {
    const double jump = (seg.a - trajectory.segments()[k - 1].b).cwiseAbs().maxCoeff();
    if (!(jump <= position_tolerance)) {
      return name + " does not start where segment " + std::to_string(k - 1) + " ends (jump " + FormatNumber(jump) +
             " rad)" + At(seg.t0);
    }
  }
  return {};
}

}  // namespace

VerificationReport VerifyTrajectory(const TimedTrajectory& trajectory, const Eigen::VectorXd& start,
                                    const Eigen::VectorXd& goal, const CollisionChecker& checker,
                                    const KinematicLimits& limits, const VerificationOptions& options) {
  if (!std::isfinite(options.max_joint_step) || !(options.max_joint_step > 0.0)) {
    ThrowInvalid("verification max_joint_step = " + FormatNumber(options.max_joint_step) + " must be finite and > 0");
  }
  if (!std::isfinite(options.endpoint_tolerance) || !(options.endpoint_tolerance >= 0.0)) {
    ThrowInvalid("verification endpoint_tolerance = " + FormatNumber(options.endpoint_tolerance) +
                 " must be finite and >= 0");
  }
  if (!std::isfinite(options.limit_tolerance) || !(options.limit_tolerance >= 0.0)) {
    ThrowInvalid("verification limit_tolerance = " + FormatNumber(options.limit_tolerance) + " must be finite and >= 0");
  }
  const RobotModel& robot = checker.robot();
  const int n = robot.num_dofs();
  limits.Validate(n);
  if (start.size() != n) {
    ThrowInvalid("start has " + std::to_string(start.size()) + " values, robot has " + std::to_string(n) + " joints");
  }
  if (goal.size() != n) {
    ThrowInvalid("goal has " + std::to_string(goal.size()) + " values, robot has " + std::to_string(n) + " joints");
  }

  VerificationReport report;
  if (trajectory.empty()) {
    report.reason = "trajectory is empty";
    return report;
  }
  const auto& segments = trajectory.segments();
  for (std::size_t k = 0; k < segments.size(); ++k) {
    std::string defect = SegmentDefect(trajectory, k, n, options.endpoint_tolerance);
    if (!defect.empty()) {
      report.reason = defect;
      return report;
    }
  }
  const double start_error = (trajectory.Evaluate(0.0).q - start).cwiseAbs().maxCoeff();
  if (!(start_error <= options.endpoint_tolerance)) {
    report.reason = "trajectory starts " + FormatNumber(start_error) + " rad from the start configuration (tolerance " +
                    FormatNumber(options.endpoint_tolerance) + " rad)";
    return report;
  }
  const double end_error = (trajectory.Evaluate(trajectory.duration()).q - goal).cwiseAbs().maxCoeff();
  if (!(end_error <= options.endpoint_tolerance)) {
    report.reason = "trajectory ends " + FormatNumber(end_error) + " rad from the goal configuration (tolerance " +
                    FormatNumber(options.endpoint_tolerance) + " rad)" + At(trajectory.duration());
    return report;
  }

  Verifier verifier(checker, limits, options, &report);
  constexpr double kMaxStatesPerSegment = 1e8;
  for (std::size_t k = 0; k < segments.size(); ++k) {
    const Segment& seg = segments[k];
    // Both one-sided values at every phase boundary: each phase at its start and its end.
    for (Phase phase : {Phase::kAccelerate, Phase::kCruise, Phase::kDecelerate}) {
      const double length = PhaseDuration(seg, phase);
      if (!(length > 0.0)) continue;
      const double begin = PhaseStart(seg, phase);
      if (!verifier.CheckDynamics(SegmentStateInPhase(seg, phase, begin))) return report;
      if (!verifier.CheckDynamics(SegmentStateInPhase(seg, phase, begin + length))) return report;
    }
    // States uniformly spaced in s, so consecutive ones differ by ≤ max_joint_step per joint.
    const double widest = (seg.b - seg.a).cwiseAbs().maxCoeff();
    const double steps = std::ceil(widest / options.max_joint_step);
    if (steps > kMaxStatesPerSegment) {
      report.reason = "segment " + std::to_string(k) + " would need more than 1e8 checks at max_joint_step = " +
                      FormatNumber(options.max_joint_step);
      return report;
    }
    const int m = std::max(1, static_cast<int>(steps));
    for (int i = (k == 0 ? 0 : 1); i <= m; ++i) {  // segment k's first state is segment k−1's last
      const double s = static_cast<double>(i) / m;
      const double tau = i == m ? seg.duration() : TimeAtParameter(seg, s);
      const Phase phase = i == m ? Phase::kDecelerate : PhaseAt(seg, tau);
      const TrajectorySample x = SegmentStateInPhase(seg, phase, tau);
      if (!verifier.CheckState(x) || !verifier.CheckDynamics(x)) return report;
    }
  }
  report.ok = true;
  return report;
}

}  // namespace chasles
