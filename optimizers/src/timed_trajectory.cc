#include "chasles/optimizers/timed_trajectory.h"

#include <algorithm>
#include <cmath>

#include "chasles/robot/error.h"
#include "internal.h"

namespace chasles {
namespace optimizers_internal {

double PhaseDuration(const TimedTrajectory::Segment& seg, Phase phase) {
  return phase == Phase::kCruise ? seg.t_cruise : seg.t_acc;
}

double PhaseStart(const TimedTrajectory::Segment& seg, Phase phase) {
  switch (phase) {
    case Phase::kAccelerate: return 0.0;
    case Phase::kCruise: return seg.t_acc;
    case Phase::kDecelerate: return seg.t_acc + seg.t_cruise;
  }
  return 0.0;
}

Phase PhaseAt(const TimedTrajectory::Segment& seg, double tau) {
  if (tau < seg.t_acc) return Phase::kAccelerate;
  if (tau < seg.t_acc + seg.t_cruise) return Phase::kCruise;
  return Phase::kDecelerate;
}

TrajectorySample SegmentStateInPhase(const TimedTrajectory::Segment& seg, Phase phase, double tau) {
  TrajectorySample out;
  out.t = seg.t0 + tau;
  const Eigen::VectorXd delta = seg.b - seg.a;
  const double v_peak = seg.s_acc * seg.t_acc;  // ds/dt while cruising
  switch (phase) {
    case Phase::kAccelerate: {
      const double s = 0.5 * seg.s_acc * tau * tau;
      out.q = seg.a + s * delta;
      out.qd = (seg.s_acc * tau) * delta;
      out.qdd = seg.s_acc * delta;
      break;
    }
    case Phase::kCruise: {
      const double s = 0.5 * seg.s_acc * seg.t_acc * seg.t_acc + v_peak * (tau - seg.t_acc);
      out.q = seg.a + s * delta;
      out.qd = v_peak * delta;
      out.qdd = Eigen::VectorXd::Zero(delta.size());
      break;
    }
    case Phase::kDecelerate: {
      const double tau_left = std::max(0.0, seg.duration() - tau);  // time to the end
      const double remaining = 0.5 * seg.s_acc * tau_left * tau_left;  // 1 − s
      out.q = seg.b - remaining * delta;
      out.qd = (seg.s_acc * tau_left) * delta;
      out.qdd = -seg.s_acc * delta;
      break;
    }
  }
  // Keep every state inside the segment's bounding box (rounding could otherwise step an ulp
  // past an endpoint that sits exactly on a joint limit). Exact endpoints are unaffected.
  out.q = out.q.cwiseMax(seg.a.cwiseMin(seg.b)).cwiseMin(seg.a.cwiseMax(seg.b));
  return out;
}

}  // namespace optimizers_internal

namespace {

using optimizers_internal::PhaseAt;
using optimizers_internal::SegmentStateInPhase;

TrajectorySample RestAt(const Eigen::VectorXd& q, double t) {
  TrajectorySample out;
  out.t = t;
  out.q = q;
  out.qd = Eigen::VectorXd::Zero(q.size());
  out.qdd = Eigen::VectorXd::Zero(q.size());
  return out;
}

}  // namespace

double TimedTrajectory::duration() const {
  if (segments_.empty()) return 0.0;
  return segments_.back().t0 + segments_.back().duration();
}

JointPath TimedTrajectory::Waypoints() const {
  JointPath out;
  if (segments_.empty()) return out;
  out.reserve(segments_.size() + 1);
  out.push_back(segments_.front().a);
  for (const Segment& seg : segments_) out.push_back(seg.b);
  return out;
}

TrajectorySample TimedTrajectory::Evaluate(double t) const {
  if (segments_.empty()) {
    throw Error(ErrorCode::kFailedPrecondition, "cannot evaluate an empty trajectory");
  }
  const double end = duration();
  if (!(t > 0.0)) return RestAt(segments_.front().a, 0.0);  // also catches NaN
  if (t >= end) return RestAt(segments_.back().b, end);
  // The last segment that starts at or before t (right limit at segment boundaries).
  auto it = std::upper_bound(segments_.begin(), segments_.end(), t,
                             [](double value, const Segment& seg) { return value < seg.t0; });
  const Segment& seg = (it == segments_.begin()) ? segments_.front() : *(it - 1);
  const double tau = std::min(std::max(0.0, t - seg.t0), seg.duration());
  TrajectorySample out = SegmentStateInPhase(seg, PhaseAt(seg, tau), tau);
  out.t = t;
  return out;
}

std::vector<TrajectorySample> TimedTrajectory::Sample(double period) const {
  if (!(period > 0.0) || !std::isfinite(period)) {
    ThrowInvalid("sample period = " + FormatNumber(period) + " must be finite and > 0");
  }
  std::vector<TrajectorySample> out;
  if (segments_.empty()) return out;
  const double end = duration();
  constexpr double kMaxSamples = 1e8;
  if (end / period > kMaxSamples) {
    ThrowInvalid("sample period = " + FormatNumber(period) + " s gives more than 1e8 samples for a " +
                 FormatNumber(end) + " s trajectory");
  }
  // Times k·period strictly before the end (skipping one within 1e-9·period of it, so no
  // near-duplicate sample precedes the final one), then the end itself.
  const double guard = 1e-9 * period;
  out.push_back(RestAt(segments_.front().a, 0.0));
  for (long k = 1;; ++k) {
    const double t = static_cast<double>(k) * period;
    if (!(t < end - guard)) break;
    out.push_back(Evaluate(t));
  }
  if (end > 0.0) out.push_back(RestAt(segments_.back().b, end));
  return out;
}

}  // namespace chasles
