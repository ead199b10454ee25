#include "chasles/optimizers/time_parameterization.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "chasles/robot/dynamics.h"
#include "chasles/robot/error.h"
#include "effort_parameterization.h"
#include "piece_certification.h"

namespace chasles {
namespace {

using Piece = TimedTrajectory::Piece;
constexpr double kInf = std::numeric_limits<double>::infinity();
/// Bisection levels of a blend span that does not certify at once (as in VerifyTrajectory).
constexpr int kBlendBisections = 12;
/// max_effort: joint motion between the torque checks of the velocity/acceleration-optimal
/// trajectory [rad], the share of a limit it may reach and still stand (the rest covers the
/// curvature between checks), and the grid of the torque-limited parameterisation [rad of path].
constexpr double kEffortCheckStep = 0.005;
constexpr double kKinematicEffortShare = 0.999;
constexpr double kEffortGridStep = 0.0025;

void ValidatePositive(const Eigen::VectorXd& values, const char* field, int num_dofs) {
  if (values.size() != num_dofs) {
    ThrowInvalid(std::string(field) + " has " + std::to_string(values.size()) + " values, robot has " +
                 std::to_string(num_dofs) + " joints");
  }
  for (int i = 0; i < values.size(); ++i) {
    const double v = values[i];
    if (std::isfinite(v) && v > 0.0) continue;  // the message is built only for a bad value
    const std::string name = std::string(field) + "[" + std::to_string(i) + "] = " + FormatNumber(v);
    ThrowInvalid(name + (std::isfinite(v) ? " must be > 0" : " must be finite"));
  }
}

/// Checks the path and returns it without exactly repeated consecutive waypoints.
JointPath ValidatedPath(const JointPath& path, const KinematicLimits& limits) {
  if (path.empty()) ThrowInvalid("path has 0 waypoints, needs at least 1");
  const int n = static_cast<int>(path.front().size());
  limits.Validate(n);
  JointPath out;
  out.reserve(path.size());
  for (std::size_t k = 0; k < path.size(); ++k) {
    if (path[k].size() != n) {
      ThrowInvalid("path[" + std::to_string(k) + "] has " + std::to_string(path[k].size()) + " values, path[0] has " +
                   std::to_string(n));
    }
    for (int i = 0; i < n; ++i) {
      if (!std::isfinite(path[k][i])) {
        ThrowInvalid("path[" + std::to_string(k) + "][" + std::to_string(i) + "] = " + FormatNumber(path[k][i]) +
                     " must be finite");
      }
    }
    if (out.empty() || path[k] != out.back()) out.push_back(path[k]);
  }
  // Trailing duplicates compare equal but may differ in the sign of a zero: end on the last
  // waypoint bit for bit.
  out.back() = path.back();
  return out;
}

/// Path-parameter limit along unit direction d: minᵢ limitᵢ/|dᵢ| over the moving joints.
double AlongLimit(const Eigen::VectorXd& d, const Eigen::VectorXd& limit) {
  double out = std::numeric_limits<double>::max();
  for (int i = 0; i < d.size(); ++i) {
    if (d[i] != 0.0) out = std::min(out, limit[i] / std::abs(d[i]));
  }
  return out;
}

Piece AtRest(const Eigen::VectorXd& q) {
  Piece piece;
  piece.coefficients = Eigen::MatrixXd::Zero(q.size(), 2);
  piece.coefficients.col(0) = q;
  return piece;
}

/// Appends the time-optimal profile along origin + s·d, s ∈ [0, length], from path speed u0
/// to u1 under |ṡ| ≤ v, |s̈| ≤ a: accelerate, cruise, decelerate (phases of zero length
/// skipped). Requires |u1² − u0²| ≤ 2·a·length and u0, u1 ≤ v. Returns the new time.
double AppendStraight(std::vector<Piece>* pieces, std::vector<int>* owners, int owner, double t,
                      const Eigen::VectorXd& origin, const Eigen::VectorXd& d, double length, double u0,
                      double u1, double v, double a) {
  if (!(length > 0.0)) return t;
  double peak = std::min(v, std::sqrt(a * length + 0.5 * (u0 * u0 + u1 * u1)));
  peak = std::max(peak, std::max(u0, u1));
  const double t1 = (peak - u0) / a, d1 = (peak * peak - u0 * u0) / (2.0 * a);
  const double t3 = (peak - u1) / a, d3 = (peak * peak - u1 * u1) / (2.0 * a);
  // Below the speed limit the profile is a triangle: no cruise (rounding would leave a sliver).
  const double d2 = peak < v ? 0.0 : std::max(0.0, length - d1 - d3);
  const double t2 = peak > 0.0 ? d2 / peak : 0.0;
  auto push = [&](Piece piece) {
    pieces->push_back(std::move(piece));
    owners->push_back(owner);
  };
  if (t1 > 0.0) push(LinePiece(t, t1, origin, d, 0.0, u0, 0.5 * a));
  if (t2 > 0.0) push(LinePiece(t + t1, t2, origin, d, d1, peak, 0.0));
  if (t3 > 0.0) push(LinePiece(t + t1 + t2, t3, origin, d, d1 + d2, peak, -0.5 * a));
  return t + t1 + t2 + t3;
}

/// Path speed along `d` of a boundary velocity, checked to point along it.
double BoundarySpeed(const Eigen::VectorXd& velocity, const Eigen::VectorXd& d, const KinematicLimits& limits,
                     const char* field, const char* which) {
  if (velocity.size() == 0) return 0.0;
  for (int i = 0; i < velocity.size(); ++i) {
    const std::string name = std::string(field) + "[" + std::to_string(i) + "] = " + FormatNumber(velocity[i]);
    if (!std::isfinite(velocity[i])) ThrowInvalid(name + " must be finite");
    if (!(std::abs(velocity[i]) <= limits.max_velocity[i] * (1.0 + 1e-12))) {
      ThrowInvalid(name + " rad/s exceeds the velocity limit " + FormatNumber(limits.max_velocity[i]) + " rad/s");
    }
  }
  if (velocity.isZero(0.0)) return 0.0;
  if (d.size() == 0) ThrowInvalid(std::string(field) + " must be zero on a path that does not move");
  const double speed = velocity.dot(d);
  const double across = (velocity - speed * d).norm();
  if (!(across <= 1e-6 * std::max(1.0, velocity.norm()))) {
    ThrowInvalid(std::string(field) + " must point along the path's " + which + " segment: its component across it is " +
                 FormatNumber(across) + " rad/s (tolerance 1e-06 relative)");
  }
  if (speed < 0.0) ThrowInvalid(std::string(field) + " points backwards along the path's " + which + " segment");
  return speed;
}

struct Layout {
  int m = 0;                            // segments
  std::vector<Eigen::VectorXd> dir;     // unit directions
  std::vector<double> length, v, a;     // per segment: length, path speed and acceleration limits
};

/// The blended parameterisation for given corner deviations.
/// Owners: a straight piece's owner is its segment k ≥ 0; a blend's is −(corner + 1).
TimedTrajectory Build(const JointPath& path, const Layout& L, const KinematicLimits& limits,
                      const std::vector<double>& deviation, double start_speed,
                      double end_speed, std::vector<int>* owners) {
  const int m = L.m;
  const int n = static_cast<int>(path.front().size());
  // Per corner j (between segment j−1 and j, j = 1..m−1): blend constant c and speed cap.
  std::vector<double> c(m + 1, 0.0), cap(m + 1, 0.0);
  const std::vector<double>& v = L.v;
  const std::vector<double>& a = L.a;
  cap[0] = start_speed;
  cap[m] = end_speed;
  for (int j = 1; j < m; ++j) {
    const Eigen::VectorXd dd = L.dir[j] - L.dir[j - 1];
    double cj = 0.0;
    for (int i = 0; i < n; ++i) cj = std::max(cj, std::abs(dd[i]) / limits.max_acceleration[i]);
    const double norm = dd.norm();
    double u = std::min(v[j - 1], v[j]);
    if (cj > 0.0) {
      u = std::min(u, std::sqrt(8.0 * deviation[j] / (norm * cj)));
      // Each blend uses at most half of each adjacent segment.
      u = std::min(u, std::sqrt(std::min(L.length[j - 1], L.length[j]) / cj));
    }
    c[j] = cj;
    cap[j] = u;
  }
  // Straight lengths left between the blends at their caps (a lower bound for any lower speed).
  std::vector<double> straight(m);
  for (int k = 0; k < m; ++k) {
    straight[k] = std::max(0.0, L.length[k] - 0.5 * cap[k] * cap[k] * c[k] - 0.5 * cap[k + 1] * cap[k + 1] * c[k + 1]);
  }
  std::vector<double> u = cap;
  for (int k = 0; k < m; ++k) u[k + 1] = std::min(u[k + 1], std::sqrt(u[k] * u[k] + 2.0 * a[k] * straight[k]));
  if (u[m] < end_speed * (1.0 - 1e-12)) {
    ThrowInvalid("end_velocity: the path speed " + FormatNumber(end_speed) +
                 " rad/s cannot be reached within the path's acceleration limits (at most " + FormatNumber(u[m]) + " rad/s)");
  }
  u[m] = end_speed;
  for (int k = m - 1; k >= 0; --k) u[k] = std::min(u[k], std::sqrt(u[k + 1] * u[k + 1] + 2.0 * a[k] * straight[k]));
  if (u[0] < start_speed * (1.0 - 1e-12)) {
    ThrowInvalid("start_velocity: the path speed " + FormatNumber(start_speed) +
                 " rad/s cannot be brought to the path's next corner or end within its acceleration limits (at most " +
                 FormatNumber(u[0]) + " rad/s)");
  }
  u[0] = start_speed;

  std::vector<Piece> pieces;
  owners->clear();
  double t = 0.0;
  for (int k = 0; k < m; ++k) {
    // Blend consumption at each end of segment k.
    const double head = k == 0 ? 0.0 : 0.5 * u[k] * u[k] * c[k];
    const double tail = k == m - 1 ? 0.0 : 0.5 * u[k + 1] * u[k + 1] * c[k + 1];
    const Eigen::VectorXd origin = head > 0.0 ? Eigen::VectorXd(path[k] + head * L.dir[k]) : path[k];
    t = AppendStraight(&pieces, owners, k, t, origin, L.dir[k], L.length[k] - head - tail, u[k], u[k + 1], v[k], a[k]);
    if (k + 1 < m && u[k + 1] > 0.0 && c[k + 1] > 0.0) {
      const int j = k + 1;
      Piece blend;
      blend.t0 = t;
      blend.duration = u[j] * c[j];
      blend.coefficients.resize(n, 3);
      blend.coefficients.col(0) = path[j] - tail * L.dir[k];
      blend.coefficients.col(1) = u[j] * L.dir[k];
      blend.coefficients.col(2) = (L.dir[j] - L.dir[k]) / (2.0 * c[j]);
      t += blend.duration;
      pieces.push_back(std::move(blend));
      owners->push_back(-(j + 1));
    }
  }
  if (pieces.empty()) {  // moves only through segments of zero-length profile (cannot happen for m > 0)
    pieces.push_back(AtRest(path.front()));
    owners->push_back(0);
  }
  return TimedTrajectory(std::move(pieces), path.back());
}

/// The blend pieces that collide, as corner indices. When the checker certifies motions, a
/// blend counts as colliding unless it is certified along its continuous motion (as
/// VerifyTrajectory checks it); otherwise its states at most `step` apart are checked.
std::vector<int> CollidingBlends(const TimedTrajectory& trajectory, const std::vector<int>& owners,
                                 const CollisionChecker& checker, double step) {
  std::vector<int> out;
  for (std::size_t p = 0; p < trajectory.pieces().size(); ++p) {
    if (owners[p] >= 0) continue;
    const Piece& piece = trajectory.pieces()[p];
    if (checker.certifies_motion()) {
      for (const detail::PieceSpan& span : detail::SplitPiece(piece, detail::kCertifiedSpanTravel)) {
        detail::PieceSpan failed;
        if (!detail::CertifySpan(piece, span, checker, kBlendBisections, nullptr, &failed)) {
          out.push_back(-owners[p] - 1);
          break;
        }
      }
      continue;
    }
    const int samples = std::max(2, static_cast<int>(std::ceil(piece.MaxJointTravel() / step)) + 1);
    for (int s = 0; s < samples; ++s) {
      const Eigen::VectorXd q = piece.State(piece.duration * s / (samples - 1)).q;
      if (!checker.IsValid(q)) {
        out.push_back(-owners[p] - 1);
        break;
      }
    }
  }
  return out;
}

/// The largest |τᵢ|/τmaxᵢ over states sampled every `step` of joint motion and at piece ends.
double WorstEffort(const TimedTrajectory& trajectory, const RobotModel& robot, const KinematicLimits& limits,
                   double step, const DynamicsOptions& dynamics) {
  double worst = 0.0;
  for (const Piece& piece : trajectory.pieces()) {
    const int samples = std::max(2, static_cast<int>(std::ceil(piece.MaxJointTravel() / step)) + 1);
    for (int s = 0; s < samples; ++s) {
      // This piece's own state, also at its end (where Evaluate would take the next piece).
      const TrajectorySample own = piece.State(piece.duration * s / (samples - 1));
      const Eigen::VectorXd tau = InverseDynamics(robot, own.q, own.qd, own.qdd, dynamics);
      for (int i = 0; i < tau.size(); ++i) worst = std::max(worst, std::abs(tau[i]) / limits.max_effort[i]);
      // Holding still must be possible at all.
      const Eigen::VectorXd hold = InverseDynamics(robot, own.q, Eigen::VectorXd::Zero(own.q.size()),
                                                   Eigen::VectorXd::Zero(own.q.size()), dynamics);
      for (int i = 0; i < hold.size(); ++i) {
        if (std::abs(hold[i]) > limits.max_effort[i]) {
          throw Error(ErrorCode::kFailedPrecondition,
                      "max_effort cannot be met: joint " + std::to_string(i) + " '" + robot.dof_names()[i] + "' needs " +
                          FormatNumber(hold[i]) + " N·m to hold the robot still at t = " + FormatNumber(own.t) +
                          " s, above its limit " + FormatNumber(limits.max_effort[i]));
        }
      }
    }
  }
  return worst;
}

/// The geometric path of a blended trajectory: per segment its straight part (one section over
/// that segment's pieces), per blend its parabola by σ = u·τ (u its speed, |c₁|).
std::vector<detail::PathSection> SectionsOf(const TimedTrajectory& trajectory, const std::vector<int>& owners,
                                            const Layout& layout) {
  std::vector<detail::PathSection> out;
  const std::vector<Piece>& pieces = trajectory.pieces();
  for (std::size_t p = 0; p < pieces.size();) {
    const Piece& piece = pieces[p];
    detail::PathSection section;
    section.p0 = piece.coefficients.col(0);
    if (owners[p] >= 0) {
      std::size_t last = p;
      while (last + 1 < pieces.size() && owners[last + 1] == owners[p]) ++last;
      const Eigen::VectorXd& d = layout.dir[owners[p]];
      const Eigen::VectorXd end = pieces[last].State(pieces[last].duration).q;
      section.p1 = d;
      section.p2 = Eigen::VectorXd::Zero(d.size());
      section.length = (end - section.p0).dot(d);
      p = last + 1;
    } else {
      const double u = piece.coefficients.col(1).norm();
      section.p1 = piece.coefficients.col(1) / u;
      section.p2 = piece.coefficients.col(2) / (u * u);
      section.length = u * piece.duration;
      ++p;
    }
    if (section.length > 0.0) out.push_back(std::move(section));
  }
  return out;
}

}  // namespace

void KinematicLimits::Validate(int num_dofs) const {
  ValidatePositive(max_velocity, "max_velocity", num_dofs);
  ValidatePositive(max_acceleration, "max_acceleration", num_dofs);
  if (max_jerk.size() != 0) ValidatePositive(max_jerk, "max_jerk", num_dofs);
  if (max_effort.size() != 0) ValidatePositive(max_effort, "max_effort", num_dofs);
  if (!gravity.allFinite()) ThrowInvalid("gravity must be finite");
}

namespace {

/// Minimum-time rest-to-rest profile of s ∈ [0, 1] under |ṡ| ≤ v, |s̈| ≤ a, |s⃛| ≤ j, as
/// pieces along origin + s·delta. Returns the end time.
double AppendJerkLimited(std::vector<Piece>* pieces, double t, const Eigen::VectorXd& origin,
                         const Eigen::VectorXd& delta, double v, double a, double j) {
  // Accelerating from rest to peak speed w: jerk ramps of tj = min(a/j, √(w/j)) and a
  // constant-acceleration phase of ta = max(0, w/a_peak − tj); distance w·(2·tj + ta)/2.
  auto ramp = [a, j](double w, double* tj, double* ta) {
    *tj = std::min(a / j, std::sqrt(w / j));
    *ta = std::max(0.0, w / (j * *tj) - *tj);
  };
  auto accel_distance = [&ramp](double w) {
    double tj, ta;
    ramp(w, &tj, &ta);
    return 0.5 * w * (2.0 * tj + ta);
  };
  double peak = v;
  if (2.0 * accel_distance(v) > 1.0) {  // the peak speed is below v: bisection on w
    double lo = 0.0, hi = v;
    for (int it = 0; it < 200 && hi - lo > 1e-16 * hi; ++it) {
      const double mid = 0.5 * (lo + hi);
      (2.0 * accel_distance(mid) > 1.0 ? hi : lo) = mid;
    }
    peak = lo;
  }
  double tj, ta;
  ramp(peak, &tj, &ta);
  const double a_peak = j * tj;
  const double cruise = std::max(0.0, (1.0 - 2.0 * accel_distance(peak)) / peak);
  // Seven phases of constant jerk.
  const double durations[7] = {tj, ta, tj, cruise, tj, ta, tj};
  const double jerks[7] = {j, 0.0, -j, 0.0, -j, 0.0, j};
  double s = 0.0, sd = 0.0, sdd = 0.0;
  for (int p = 0; p < 7; ++p) {
    const double h = durations[p];
    if (!(h > 0.0)) continue;
    pieces->push_back(LinePiece(t, h, origin, delta, s, sd, 0.5 * sdd, jerks[p] / 6.0));
    s += sd * h + 0.5 * sdd * h * h + jerks[p] * h * h * h / 6.0;
    sd += sdd * h + 0.5 * jerks[p] * h * h;
    sdd += jerks[p] * h;
    if (p == 2 || p == 6) sdd = 0.0;  // the ramps end at exactly zero acceleration
    if (p == 0) sdd = a_peak;
    t += h;
  }
  return t;
}

}  // namespace

TimedTrajectory ParameterizeRestToRest(const JointPath& path, const KinematicLimits& limits) {
  const JointPath waypoints = ValidatedPath(path, limits);
  if (waypoints.size() == 1) return TimedTrajectory({AtRest(waypoints.front())}, waypoints.front());
  if (limits.max_jerk.size() == 0) {
    TimeOptimalOptions options;
    options.max_deviation = 0.0;
    KinematicLimits kinematic = limits;
    kinematic.max_effort.resize(0);
    return ParameterizeTimeOptimal(waypoints, kinematic, options);
  }
  std::vector<Piece> pieces;
  double t = 0.0;
  for (std::size_t k = 0; k + 1 < waypoints.size(); ++k) {
    const Eigen::VectorXd delta = waypoints[k + 1] - waypoints[k];
    const Eigen::VectorXd unit = delta.cwiseAbs();
    t = AppendJerkLimited(&pieces, t, waypoints[k], delta, AlongLimit(unit, limits.max_velocity),
                          AlongLimit(unit, limits.max_acceleration), AlongLimit(unit, limits.max_jerk));
  }
  return TimedTrajectory(std::move(pieces), waypoints.back());
}

TimedTrajectory ParameterizeTimeOptimal(const JointPath& path, const KinematicLimits& limits,
                                        const TimeOptimalOptions& options, const CollisionChecker* checker,
                                        TimeOptimalReport* report) {
  const JointPath waypoints = ValidatedPath(path, limits);
  const int n = static_cast<int>(waypoints.front().size());
  if (limits.max_jerk.size() != 0) {
    ThrowInvalid("max_jerk is set, but the time-optimal parameterisation has acceleration steps (unbounded jerk); "
                 "use collocation or spline smoothing for jerk limits");
  }
  if (!std::isfinite(options.max_deviation) || !(options.max_deviation >= 0.0)) {
    ThrowInvalid("max_deviation = " + FormatNumber(options.max_deviation) + " must be finite and >= 0");
  }
  if (!std::isfinite(options.max_joint_step) || !(options.max_joint_step > 0.0)) {
    ThrowInvalid("max_joint_step = " + FormatNumber(options.max_joint_step) + " must be finite and > 0");
  }
  for (const auto* velocity : {&options.start_velocity, &options.end_velocity}) {
    if (velocity->size() != 0 && velocity->size() != n) {
      ThrowInvalid(std::string(velocity == &options.start_velocity ? "start_velocity" : "end_velocity") + " has " +
                   std::to_string(velocity->size()) + " values, path has " + std::to_string(n) + " joints");
    }
  }
  const bool effort = limits.max_effort.size() != 0;
  if (effort && (checker == nullptr || !HasInertia(checker->robot()))) {
    ThrowInvalid("max_effort needs a robot with inertia on every moving link");
  }

  Layout layout;
  layout.m = static_cast<int>(waypoints.size()) - 1;
  for (int k = 0; k < layout.m; ++k) {
    const Eigen::VectorXd delta = waypoints[k + 1] - waypoints[k];
    const double length = delta.norm();
    layout.dir.push_back(delta / length);
    layout.length.push_back(length);
    layout.v.push_back(AlongLimit(layout.dir.back(), limits.max_velocity));
    layout.a.push_back(AlongLimit(layout.dir.back(), limits.max_acceleration));
  }
  const Eigen::VectorXd none;
  const double start_speed = BoundarySpeed(options.start_velocity, layout.m > 0 ? layout.dir.front() : none, limits,
                                           "start_velocity", "first");
  const double end_speed =
      BoundarySpeed(options.end_velocity, layout.m > 0 ? layout.dir.back() : none, limits, "end_velocity", "last");
  TimeOptimalReport local;
  TimeOptimalReport& out = report != nullptr ? *report : local;
  out = TimeOptimalReport();
  if (layout.m == 0) {
    out.message = "the path does not move";
    return TimedTrajectory({AtRest(waypoints.front())}, waypoints.front());
  }

  std::vector<double> deviation(layout.m + 1, options.max_deviation);
  std::vector<int> owners;
  TimedTrajectory trajectory;
  for (;;) {
    trajectory = Build(waypoints, layout, limits, deviation, start_speed, end_speed, &owners);
    if (checker != nullptr && options.max_deviation > 0.0) {
      const std::vector<int> colliding = CollidingBlends(trajectory, owners, *checker, options.max_joint_step);
      if (!colliding.empty()) {
        for (int j : colliding) {
          deviation[j] = deviation[j] < 1e-6 ? 0.0 : 0.25 * deviation[j];
          ++out.blends_tightened;
        }
        continue;  // ends: a corner at deviation 0 has no blend
      }
    }
    break;
  }
  if (effort) {
    // The velocity- and acceleration-optimal trajectory stands when its torques stay clear of
    // the limits (checked every kEffortCheckStep of joint motion, holding still included);
    // otherwise the same path — its segments and blends — is timed again with the torque in
    // the parameterisation.
    DynamicsOptions dynamics;
    dynamics.gravity = limits.gravity;
    if (WorstEffort(trajectory, checker->robot(), limits, kEffortCheckStep, dynamics) > kKinematicEffortShare) {
      detail::EffortRetimeReport retime;
      trajectory = detail::RetimeUnderEffort(SectionsOf(trajectory, owners, layout), limits, checker->robot(), dynamics,
                                             start_speed, end_speed, kEffortGridStep, &retime);
      out.effort_passes = retime.solves;
      out.effort_grid_intervals = retime.grid_intervals;
    }
  }
  for (int owner : owners) out.blends += owner < 0 ? 1 : 0;
  out.message = std::to_string(layout.m) + " segments, " + std::to_string(out.blends) + " blended corners";
  return trajectory;
}

}  // namespace chasles
