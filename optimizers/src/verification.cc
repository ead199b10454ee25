#include "chasles/optimizers/verification.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <queue>
#include <string>
#include <vector>

#include "chasles/robot/dynamics.h"
#include "chasles/robot/error.h"
#include "piece_certification.h"

namespace chasles {
namespace {

using Piece = TimedTrajectory::Piece;

std::string At(double t) { return " at t = " + FormatNumber(t) + " s"; }

/// Row i of a piece as a contiguous coefficient vector.
Eigen::VectorXd Row(const Piece& piece, int i) { return piece.coefficients.row(i).transpose(); }

class Verifier {
 public:
  Verifier(const CollisionChecker& checker, const KinematicLimits& limits, const VerificationOptions& options,
           VerificationReport* report)
      : checker_(checker), robot_(checker.robot()), limits_(limits), options_(options), report_(report) {
    dynamics_.gravity = limits.gravity;
  }

  std::string JointName(int i) const {
    std::string name = "joint " + std::to_string(i);
    if (i < static_cast<int>(robot_.dof_names().size())) name += " '" + robot_.dof_names()[i] + "'";
    return name;
  }

  bool Fail(const std::string& reason) {
    report_->reason = reason;
    return false;
  }

  /// Exact limits of one piece: position range, |q̇|, |q̈| and (when limited) |q⃛| at the
  /// extrema of each joint's polynomial.
  bool CheckLimits(const Piece& piece) {
    const double slack = 1.0 + options_.limit_tolerance;
    const Eigen::VectorXd& lower = robot_.lower_limits();
    const Eigen::VectorXd& upper = robot_.upper_limits();
    struct Bound {
      int order;
      const Eigen::VectorXd* limit;
      double* ratio;
      const char* what;
      const char* unit;
    };
    const Bound bounds[3] = {
        {1, &limits_.max_velocity, &report_->max_velocity_ratio, "velocity", "rad/s"},
        {2, &limits_.max_acceleration, &report_->max_acceleration_ratio, "acceleration", "rad/s²"},
        {3, &limits_.max_jerk, &report_->max_jerk_ratio, "jerk", "rad/s³"},
    };
    for (int i = 0; i < piece.coefficients.rows(); ++i) {
      const Eigen::VectorXd c = Row(piece, i);
      const int size = static_cast<int>(c.size());
      double lo, hi;
      poly::Range(c.data(), size, piece.duration, &lo, &hi);
      const double pad_lo = 1e-12 * std::max(1.0, std::abs(lower[i]));
      const double pad_hi = 1e-12 * std::max(1.0, std::abs(upper[i]));
      if (!(lo >= lower[i] - pad_lo && hi <= upper[i] + pad_hi)) {
        const double value = lo < lower[i] - pad_lo ? lo : hi;
        return Fail(JointName(i) + " position " + FormatNumber(value) + " is outside its limits [" +
                    FormatNumber(lower[i]) + ", " + FormatNumber(upper[i]) + "] between t = " + FormatNumber(piece.t0) +
                    " and " + FormatNumber(piece.t0 + piece.duration) + " s");
      }
      for (const Bound& bound : bounds) {
        if (bound.limit->size() == 0) continue;
        double where = 0.0;
        const double value = poly::MaxAbsDerivative(c.data(), size, bound.order, piece.duration, &where);
        const double ratio = value / (*bound.limit)[i];
        *bound.ratio = std::max(*bound.ratio, ratio);
        if (!(ratio <= slack)) {
          return Fail(JointName(i) + " " + bound.what + " " +
                      FormatNumber(poly::EvalDerivative(c.data(), size, bound.order, where)) + " " + bound.unit +
                      " exceeds limit " + FormatNumber((*bound.limit)[i]) + " " + bound.unit + At(piece.t0 + where));
        }
      }
    }
    return true;
  }

  /// CheckLimits has passed: any excess over a position limit is rounding (<= 1e-12 relative).
  Eigen::VectorXd Clamped(const Eigen::VectorXd& q) const {
    return q.cwiseMax(robot_.lower_limits()).cwiseMin(robot_.upper_limits());
  }

  /// Collisions (self and scene) of one state at time t.
  bool CheckCollision(const Eigen::VectorXd& q, double t) {
    ++report_->states_checked;
    if (checker_.IsValid(q, &counters_)) return true;
    const CollisionResult contact = checker_.Check(q);
    if (!contact.in_collision) return Fail("state is invalid" + At(t) + " (rejected by the checker)");
    return Fail(ContactText(contact, t));
  }

  /// "collision at t = … between link 'a' and 'b'" / "self-collision at t = … between link 'a'
  /// and link 'b'".
  static std::string ContactText(const CollisionResult& contact, double t) {
    if (!contact.violation.empty()) return "path constraint broken" + At(t) + ": " + contact.violation;
    if (contact.self_collision) {
      return "self-collision" + At(t) + " between link '" + contact.link_a + "' and link '" + contact.other + "'";
    }
    return "collision" + At(t) + " between link '" + contact.link_a + "' and '" + contact.other + "'";
  }

  /// Collisions and, when limited, torques of one state (the discrete check).
  bool CheckState(const Piece& piece, double tau) {
    if (!CheckCollision(Clamped(piece.State(tau).q), piece.t0 + tau)) return false;
    return CheckEffort(piece, tau);
  }

  /// Proves piece k free along its continuous motion (sphere path): conservative advancement
  /// over spans of at most kCertifiedSpanTravel, a span that does not certify bisected up to
  /// kMaxBisections levels. On failure the reason names the contact, found densely in the
  /// first part that did not certify.
  bool CertifyPiece(const Piece& piece) {
    // A piece along a line visits the configurations of one straight segment: certified as that
    // segment in one advancement (no restart per span, a speed bound no time profile loosens).
    // Should it not certify, the spans below find and name the contact.
    Eigen::VectorXd a, b;
    if (detail::LineSegmentOf(piece, &a, &b)) {
      CheckCounters counters;
      const bool ok = checker_.IsCurveCertified(detail::SegmentCurve(a, b, robot_), (b - a).cwiseAbs(), &counters);
      report_->states_checked += static_cast<int>(counters.state_checks);
      if (ok) return true;
    }
    for (const detail::PieceSpan& span : detail::SplitPiece(piece, detail::kCertifiedSpanTravel)) {
      CheckCounters counters;
      detail::PieceSpan failed;
      const bool ok = detail::CertifySpan(piece, span, checker_, kMaxBisections, &counters, &failed);
      report_->states_checked += static_cast<int>(counters.state_checks);
      if (!ok) return Fail(Uncertified(piece, failed));
    }
    return true;
  }

  /// Torques of one state when max_effort is set (no collision check).
  bool CheckEffort(const Piece& piece, double tau) {
    if (limits_.max_effort.size() == 0) return true;
    const double t = piece.t0 + tau;
    const TrajectorySample x = piece.State(tau);
    const Eigen::VectorXd q = Clamped(x.q);
    const int n = static_cast<int>(q.size());
    const Eigen::VectorXd effort = InverseDynamics(robot_, q, x.qd, x.qdd, dynamics_);
    for (int i = 0; i < n; ++i) {
      const double ratio = std::abs(effort[i]) / limits_.max_effort[i];
      report_->max_effort_ratio = std::max(report_->max_effort_ratio, ratio);
      if (!(ratio <= 1.0 + options_.limit_tolerance)) {
        return Fail(JointName(i) + " effort " + FormatNumber(effort[i]) + " exceeds limit " +
                    FormatNumber(limits_.max_effort[i]) + At(t));
      }
    }
    return true;
  }

 private:
  static constexpr int kMaxBisections = 12;
  static constexpr double kProbeMargin = 1e-5;  // [m] padding added to name a near-contact

  /// Why the part `failed` of `piece` is not certified: the first colliding state among states
  /// at most 0.0005 rad apart (at least 16 intervals), else the first pair that comes within
  /// kProbeMargin of touching at those states, else only the time span.
  std::string Uncertified(const Piece& piece, const detail::PieceSpan& failed) const {
    const double travel = detail::SpanSpeedBound(piece, failed).maxCoeff();
    const int m = std::max(16, static_cast<int>(std::min(1e5, std::ceil(travel / 0.0005))));
    const auto curve = detail::SpanCurve(piece, failed, robot_);
    const auto time = [&](int i) { return piece.t0 + failed.begin + (failed.end - failed.begin) * i / m; };
    std::vector<Eigen::VectorXd> states(m + 1);
    for (int i = 0; i <= m; ++i) {
      curve(static_cast<double>(i) / m, &states[i]);
      const CollisionResult contact = checker_.Check(states[i]);
      if (contact.in_collision) return ContactText(contact, time(i));
    }
    CollisionOptions probe_options = checker_.options();
    probe_options.padding += kProbeMargin;
    const CollisionChecker probe(checker_.robot_ptr(), std::make_shared<Scene>(checker_.scene()), probe_options);
    for (int i = 0; i <= m; ++i) {
      const CollisionResult near = probe.Check(states[i]);
      if (!near.in_collision) continue;
      return "not certified" + At(time(i)) + ": link '" + near.link_a + "' passes within rounding of " +
             (near.self_collision ? "link '" : "'") + near.other + "' (closer than " + FormatNumber(kProbeMargin) +
             " m; conservative advancement cannot prove the gap, no colliding state found)";
    }
    return "not certified between t = " + FormatNumber(piece.t0 + failed.begin) + " and " +
           FormatNumber(piece.t0 + failed.end) +
           " s: conservative advancement stalled (no colliding state and no contact within " +
           FormatNumber(kProbeMargin) + " m found)";
  }

  const CollisionChecker& checker_;
  const RobotModel& robot_;
  const KinematicLimits& limits_;
  const VerificationOptions& options_;
  VerificationReport* report_;
  CheckCounters counters_;
  DynamicsOptions dynamics_;
};

/// Structural soundness of piece k. Returns an empty string when sound.
std::string PieceDefect(const TimedTrajectory& trajectory, std::size_t k, int n, const VerificationOptions& options,
                        double velocity_tolerance, bool jerk_limited) {
  const Piece& piece = trajectory.pieces()[k];
  const std::string name = "piece " + std::to_string(k);
  if (piece.coefficients.rows() != n) {
    return name + " has " + std::to_string(piece.coefficients.rows()) + " joints, robot has " + std::to_string(n);
  }
  if (!piece.coefficients.allFinite()) return name + " has a non-finite coefficient";
  if (!std::isfinite(piece.duration) || !(piece.duration >= 0.0) || !std::isfinite(piece.t0)) {
    return name + " has an invalid timing (t0 = " + FormatNumber(piece.t0) + ", duration = " +
           FormatNumber(piece.duration) + ")";
  }
  if (k == 0) {
    if (piece.t0 != 0.0) return name + " starts at t = " + FormatNumber(piece.t0) + " s, expected 0 s";
    return {};
  }
  const Piece& previous = trajectory.pieces()[k - 1];
  const double expected_t0 = previous.t0 + previous.duration;
  if (!(std::abs(piece.t0 - expected_t0) <= 1e-9 * std::max(1.0, expected_t0))) {
    return name + " starts at t = " + FormatNumber(piece.t0) + " s, expected " + FormatNumber(expected_t0) + " s";
  }
  for (int i = 0; i < n; ++i) {
    const double jump = std::abs(piece.coefficients(i, 0) - previous.Derivative(i, 0, previous.duration));
    if (!(jump <= options.endpoint_tolerance)) {
      return name + " does not start where piece " + std::to_string(k - 1) + " ends: joint " + std::to_string(i) +
             " jumps " + FormatNumber(jump) + " rad" + At(piece.t0);
    }
    const double velocity_jump = std::abs(piece.Derivative(i, 1, 0.0) - previous.Derivative(i, 1, previous.duration));
    if (!(velocity_jump <= velocity_tolerance)) {
      return name + " velocity of joint " + std::to_string(i) + " jumps " + FormatNumber(velocity_jump) + " rad/s" +
             At(piece.t0);
    }
    if (jerk_limited) {
      const double jump2 = std::abs(piece.Derivative(i, 2, 0.0) - previous.Derivative(i, 2, previous.duration));
      if (!(jump2 <= velocity_tolerance)) {
        return name + " acceleration of joint " + std::to_string(i) + " jumps " + FormatNumber(jump2) +
               " rad/s² (an infinite jerk; max_jerk is set)" + At(piece.t0);
      }
    }
  }
  return {};
}

const char* ShapeName(ShapeType type) {
  switch (type) {
    case ShapeType::kSphere: return "sphere";
    case ShapeType::kBox: return "box";
    case ShapeType::kCylinder: return "cylinder";
    case ShapeType::kCapsule: return "capsule";
    case ShapeType::kMesh: return "mesh";
  }
  return "shape";
}

/// At most 5 items joined by ", ", then how many more.
std::string JoinSome(const std::vector<std::string>& items) {
  std::string out;
  for (std::size_t i = 0; i < items.size() && i < 5; ++i) out += (i == 0 ? "" : ", ") + items[i];
  if (items.size() > 5) out += " and " + std::to_string(items.size() - 5) + " more";
  return out;
}

}  // namespace

std::string DiscreteCheckCause(const CollisionChecker& checker) {
  std::vector<std::string> parts;
  std::vector<std::string> links;
  for (const Link& link : checker.robot().links()) {
    for (const Shape& shape : link.collision) {
      if (shape.type == ShapeType::kSphere) continue;
      links.push_back("'" + link.name + "' (" + ShapeName(shape.type) + ")");
      break;
    }
  }
  if (!links.empty()) parts.push_back("robot links with shapes other than spheres: " + JoinSome(links));
  std::vector<std::string> meshes;
  for (const SceneObject& object : checker.scene().objects()) {
    if (object.shape.type == ShapeType::kMesh) meshes.push_back("'" + object.name + "'");
  }
  if (!meshes.empty()) parts.push_back("scene meshes " + JoinSome(meshes));
  const std::size_t maps = checker.scene().occupancy_maps().size();
  if (maps > 0 && !checker.uses_fast_path()) {
    std::vector<std::string> names;
    for (const OccupancyMap& map : checker.scene().occupancy_maps()) names.push_back("'" + map.name + "'");
    parts.push_back("occupancy maps " + JoinSome(names) + " (FCL octree)");
  } else if (maps > static_cast<std::size_t>(checker.num_gridded_occupancy_maps())) {
    parts.push_back(std::to_string(maps - checker.num_gridded_occupancy_maps()) + " of " + std::to_string(maps) +
                    " occupancy maps too large to grid (their occupied voxels span more than 2^28 finest voxels)");
  }
  if (parts.empty()) {
    if (checker.certifies_motion()) return {};
    parts.push_back(checker.options().force_fcl ? "the checker was built with force_fcl (the generic FCL path)"
                                                : "the checker cannot bound its motion");
  }
  std::string out;
  for (std::size_t i = 0; i < parts.size(); ++i) out += (i == 0 ? "" : "; ") + parts[i];
  return out;
}

VerificationReport VerifyTrajectory(const TimedTrajectory& trajectory, const Eigen::VectorXd& start,
                                    const Eigen::VectorXd& goal, const CollisionChecker& checker,
                                    const KinematicLimits& limits, const VerificationOptions& options) {
  if (!std::isfinite(options.max_joint_step) || !(options.max_joint_step > 0.0)) {
    ThrowInvalid("verification max_joint_step = " + FormatNumber(options.max_joint_step) + " must be finite and > 0");
  }
  if (!std::isfinite(options.max_time_step) || options.max_time_step < 0.0) {
    ThrowInvalid("verification max_time_step = " + FormatNumber(options.max_time_step) + " must be finite and >= 0");
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
  if (limits.max_effort.size() != 0 && !HasInertia(robot)) {
    ThrowInvalid("max_effort needs a robot with inertia on every moving link");
  }
  if (start.size() != n) {
    ThrowInvalid("start has " + std::to_string(start.size()) + " values, robot has " + std::to_string(n) + " joints");
  }
  if (goal.size() != n) {
    ThrowInvalid("goal has " + std::to_string(goal.size()) + " values, robot has " + std::to_string(n) + " joints");
  }
  for (const auto* v : {&options.start_velocity, &options.end_velocity}) {
    if (v->size() != 0 && v->size() != n) {
      ThrowInvalid(std::string(v == &options.start_velocity ? "start" : "end") + " velocity has " +
                   std::to_string(v->size()) + " values, robot has " + std::to_string(n) + " joints");
    }
  }

  VerificationReport report;
  if (checker.certifies_motion()) {
    report.collision_guarantee = "certified";
  } else {
    report.collision_guarantee = "discrete";
    report.collision_guarantee_reason = "collisions checked at states at most " + FormatNumber(options.max_joint_step) +
                                        " rad apart, not proven between them: " + DiscreteCheckCause(checker);
  }
  if (trajectory.empty()) {
    report.reason = "trajectory is empty";
    return report;
  }
  const double velocity_tolerance = 1e-6 * std::max(1.0, limits.max_velocity.maxCoeff());
  const bool jerk_limited = limits.max_jerk.size() != 0;
  const auto& pieces = trajectory.pieces();
  for (std::size_t k = 0; k < pieces.size(); ++k) {
    std::string defect = PieceDefect(trajectory, k, n, options, velocity_tolerance, jerk_limited);
    if (!defect.empty()) {
      report.reason = defect;
      return report;
    }
  }
  const TrajectorySample first = trajectory.Evaluate(0.0);
  const TrajectorySample last = trajectory.Evaluate(trajectory.duration());
  const double start_error = (first.q - start).cwiseAbs().maxCoeff();
  if (!(start_error <= options.endpoint_tolerance)) {
    report.reason = "trajectory starts " + FormatNumber(start_error) + " rad from the start configuration (tolerance " +
                    FormatNumber(options.endpoint_tolerance) + " rad)";
    return report;
  }
  const double end_error = (last.q - goal).cwiseAbs().maxCoeff();
  if (!(end_error <= options.endpoint_tolerance)) {
    report.reason = "trajectory ends " + FormatNumber(end_error) + " rad from the goal configuration (tolerance " +
                    FormatNumber(options.endpoint_tolerance) + " rad)" + At(trajectory.duration());
    return report;
  }
  const Eigen::VectorXd rest = Eigen::VectorXd::Zero(n);
  const Eigen::VectorXd& v0 = options.start_velocity.size() != 0 ? options.start_velocity : rest;
  const Eigen::VectorXd& v1 = options.end_velocity.size() != 0 ? options.end_velocity : rest;
  const double v0_error = (first.qd - v0).cwiseAbs().maxCoeff();
  if (!(v0_error <= velocity_tolerance)) {
    report.reason = "trajectory starts with a velocity " + FormatNumber(v0_error) + " rad/s from the expected one";
    return report;
  }
  const double v1_error = (last.qd - v1).cwiseAbs().maxCoeff();
  if (!(v1_error <= velocity_tolerance)) {
    report.reason = "trajectory ends with a velocity " + FormatNumber(v1_error) + " rad/s from the expected one" +
                    At(trajectory.duration());
    return report;
  }
  if (jerk_limited) {
    // A jerk limit means the acceleration is continuous, also from and to rest.
    if (v0.isZero(0.0) && !(first.qdd.cwiseAbs().maxCoeff() <= velocity_tolerance)) {
      report.reason = "trajectory starts at rest with acceleration " + FormatNumber(first.qdd.cwiseAbs().maxCoeff()) +
                      " rad/s² (an infinite jerk; max_jerk is set)";
      return report;
    }
    if (v1.isZero(0.0) && !(last.qdd.cwiseAbs().maxCoeff() <= velocity_tolerance)) {
      report.reason = "trajectory ends at rest with acceleration " + FormatNumber(last.qdd.cwiseAbs().maxCoeff()) +
                      " rad/s² (an infinite jerk; max_jerk is set)" + At(trajectory.duration());
      return report;
    }
  }

  Verifier verifier(checker, limits, options, &report);
  for (const Piece& piece : pieces) {
    if (!verifier.CheckLimits(piece)) return report;
  }
  // 4. Collisions: certified over each piece's continuous motion on the sphere path, else at
  //    discrete states; torques at discrete states either way.
  const bool certified = checker.certifies_motion();
  const bool effort = limits.max_effort.size() != 0;
  constexpr double kMaxStatesPerPiece = 1e8;
  for (std::size_t k = 0; k < pieces.size(); ++k) {
    const Piece& piece = pieces[k];
    if (certified && !verifier.CertifyPiece(piece)) return report;
    if (certified && !effort) continue;
    double steps = std::ceil(piece.MaxJointTravel() / options.max_joint_step);
    if (options.max_time_step > 0.0) steps = std::max(steps, std::ceil(piece.duration / options.max_time_step));
    if (steps > kMaxStatesPerPiece) {
      report.reason = "piece " + std::to_string(k) + " would need more than 1e8 checks at max_joint_step = " +
                      FormatNumber(options.max_joint_step) + " rad, max_time_step = " +
                      FormatNumber(options.max_time_step) + " s";
      return report;
    }
    const int m = std::max(1, static_cast<int>(steps));
    for (int i = (k == 0 ? 0 : 1); i <= m; ++i) {  // piece k's first state is piece k−1's last
      const double tau = piece.duration * i / m;
      if (!(certified ? verifier.CheckEffort(piece, tau) : verifier.CheckState(piece, tau))) return report;
    }
  }
  // The exact final configuration (the trajectory's end_position, which the last sample is).
  if (!verifier.CheckCollision(verifier.Clamped(last.q), trajectory.duration())) return report;
  report.ok = true;
  return report;
}

namespace {

/// square += row² (polynomial product; square has 2·row.size() − 1 coefficients).
void AddSquare(const std::vector<double>& row, std::vector<double>* square) {
  const std::size_t size = row.size();
  for (std::size_t a = 0; a < size; ++a) {
    if (row[a] == 0.0) continue;
    for (std::size_t b = 0; b < size; ++b) (*square)[a + b] += row[a] * row[b];
  }
}

/// The least distance [rad] from w to the piece's positions over τ ∈ [0, duration]: the least of
/// Σᵢ (cᵢ(τ) − wᵢ)², a polynomial of twice the piece's degree, by poly::Range (its ends and the
/// real roots of its derivative).
double DistanceToPiece(const Eigen::VectorXd& w, const Piece& piece) {
  const int n = static_cast<int>(piece.coefficients.rows());
  const int size = static_cast<int>(piece.coefficients.cols());
  std::vector<double> square(static_cast<std::size_t>(2 * size - 1), 0.0), row(static_cast<std::size_t>(size));
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < size; ++j) row[j] = piece.coefficients(i, j);
    row[0] -= w[i];
    AddSquare(row, &square);
  }
  double lo, hi;
  poly::Range(square.data(), 2 * size - 1, piece.duration, &lo, &hi);
  return std::sqrt(std::max(0.0, lo));
}

/// Distance from x to the segment a–b.
double DistanceToSegment(Eigen::Ref<const Eigen::VectorXd> x, Eigen::Ref<const Eigen::VectorXd> a,
                         Eigen::Ref<const Eigen::VectorXd> b) {
  // Written out, without temporaries: this runs (states × waypoints) times per trajectory.
  const Eigen::Index n = x.size();
  double len2 = 0.0, along = 0.0;
  for (Eigen::Index i = 0; i < n; ++i) {
    const double ab = b[i] - a[i];
    len2 += ab * ab;
    along += (x[i] - a[i]) * ab;
  }
  const double s = len2 > 0.0 ? std::min(1.0, std::max(0.0, along / len2)) : 0.0;
  double d2 = 0.0;
  for (Eigen::Index i = 0; i < n; ++i) {
    const double e = x[i] - (a[i] + s * (b[i] - a[i]));
    d2 += e * e;
  }
  return std::sqrt(d2);
}

constexpr double kDeviationTolerance = 1e-9;  // [rad] how far max_deviation may stay below the true figure
constexpr int kMaxDeviationSplits = 2000;     // spans split in all before that figure is left as sampled

/// The piece's polynomials on [τ0, τ0 + h], re-expanded about τ0 (a Taylor shift), as a piece of
/// duration h.
Piece SubPiece(const Piece& piece, double tau0, double h) {
  Piece out;
  out.t0 = piece.t0 + tau0;
  out.duration = h;
  const int size = static_cast<int>(piece.coefficients.cols());
  out.coefficients = Eigen::MatrixXd::Zero(piece.coefficients.rows(), size);
  for (int m = 0; m < size; ++m) {
    double binomial = 1.0, power = 1.0;  // C(m, j) and τ0^(m − j), from j = m down
    for (int j = m; j >= 0; --j) {
      out.coefficients.col(j) += binomial * power * piece.coefficients.col(m);
      binomial = binomial * j / (m - j + 1);
      power *= tau0;
    }
  }
  return out;
}

/// Raises `deviation` — the largest distance from sampled trajectory states to the path's
/// polyline, a true value — to the largest over the whole continuous trajectory, within
/// kDeviationTolerance. A span whose bound (the least over segments of MaxDistanceToSegment, exact
/// polynomial ranges) is above the figure by more is split in two and its midpoint's distance
/// taken, at most kMaxDeviationSplits times in all; false when that was not enough.
bool RefineDeviation(const TimedTrajectory& trajectory, const JointPath& path, double* deviation) {
  struct Span {
    std::size_t piece;
    double tau0, h;
  };
  const std::vector<Piece>& pieces = trajectory.pieces();
  std::vector<Span> spans;
  for (std::size_t p = pieces.size(); p-- > 0;) {
    if (pieces[p].duration > 0.0) spans.push_back({p, 0.0, pieces[p].duration});
  }
  const std::size_t segments = path.size() - 1;
  int splits = 0;
  while (!spans.empty()) {
    const Span span = spans.back();
    spans.pop_back();
    const Piece sub = SubPiece(pieces[span.piece], span.tau0, span.h);
    Eigen::VectorXd middle(sub.coefficients.rows());
    for (Eigen::Index i = 0; i < middle.size(); ++i) {
      middle[i] = poly::Eval(sub.coefficients.data() + i, static_cast<int>(sub.coefficients.cols()), span.h / 2,
                             static_cast<int>(sub.coefficients.rows()));
    }
    // The segment nearest the span's middle first: usually the only one tried.
    std::size_t nearest = 0;
    double middle_distance = std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < segments; ++k) {
      const double d = DistanceToSegment(middle, path[k], path[k + 1]);
      if (d < middle_distance) {
        middle_distance = d;
        nearest = k;
      }
    }
    *deviation = std::max(*deviation, middle_distance);
    const double enough = *deviation + kDeviationTolerance;
    bool settled = false;
    for (std::size_t i = 0; i < segments && !settled; ++i) {
      const std::size_t k = (nearest + i) % segments;
      settled = MaxDistanceToSegment(sub, path[k], path[k + 1]) <= enough;
    }
    if (settled) continue;
    if (++splits > kMaxDeviationSplits) return false;
    spans.push_back({span.piece, span.tau0 + span.h / 2, span.h / 2});
    spans.push_back({span.piece, span.tau0, span.h / 2});
  }
  return true;
}

constexpr double kClearanceTolerance = 1e-4;  // [m]
constexpr double kClearanceRelativeTolerance = 0.02;  // of the clearance: 1 mm at 5 cm
constexpr int kMaxClearanceStates = 5000;

/// A lower bound on the clearance over the whole continuous trajectory (checker certifies
/// motions, so it has lever bounds). The trajectory is a sequence of curves: a piece along a
/// line is its straight segment a → b (LineSegmentOf: the same configurations), parameter
/// u ∈ [0, 1] with |dq/du| = |b − a| exactly; any other piece goes by time in spans of at
/// most kCertifiedSpanTravel, with each span's largest speed. Per clearance group g of the
/// checker (a sphere link), no sphere of g moves more than L_g per unit of the parameter, so
/// between evaluated parameters x_a < x_b, g's clearance c_g(x) >= max(c_g(x_a) − L_g(x − x_a),
/// c_g(x_b) − L_g(x_b − x)), whose minimum is (c_g(x_a) + c_g(x_b) − L_g(x_b − x_a))/2; the
/// interval's bound is the least over the groups (with the lower bounds Clearance gives per
/// group), so a group far from the scene, or slow, leaves the bound to the others. Starting
/// from states at most 0.2 rad apart, the interval with the lowest bound is bisected until
/// every bound is within max(kClearanceTolerance, kClearanceRelativeTolerance · best) of the
/// smallest clearance evaluated (or kMaxClearanceStates states were evaluated: the figure is
/// then the loosest remaining bound, still below the true minimum).
double ClearanceLowerBound(const TimedTrajectory& trajectory, const CollisionChecker& checker) {
  constexpr double kInitialTravel = 0.2;  // [rad]
  const std::size_t groups = static_cast<std::size_t>(checker.num_clearance_groups());
  const RobotModel& robot = checker.robot();
  // Per piece: its segment's SegmentCurve when it moves along a line, else its own position by
  // local time.
  std::vector<CollisionChecker::Curve> curves;
  curves.reserve(trajectory.pieces().size());
  // Per evaluated state, its groups' lower bounds; per span, its groups' L_g per unit of the
  // parameter: both `groups` values from the offsets the intervals keep.
  std::vector<double> lower, rates;
  struct Interval {
    double bound;
    std::size_t curve;
    double a, b;                   // parameters: local time, or u on a segment
    std::size_t at_a, at_b, rate;  // offsets into lower (states a, b) and rates
    bool operator>(const Interval& other) const { return bound > other.bound; }
  };
  std::priority_queue<Interval, std::vector<Interval>, std::greater<Interval>> open;
  double best = std::numeric_limits<double>::infinity();
  int evaluated = 0;
  Eigen::VectorXd q(robot.num_dofs()), group;
  const auto clearance = [&](std::size_t curve, double x) {
    curves[curve](x, &q);
    best = std::min(best, checker.Clearance(q, &group));
    ++evaluated;
    const std::size_t at = lower.size();
    lower.insert(lower.end(), group.data(), group.data() + groups);
    return at;
  };
  const auto push = [&](std::size_t curve, double a, double b, std::size_t at_a, std::size_t at_b, std::size_t rate) {
    double bound = std::numeric_limits<double>::infinity();
    const double h = b - a;
    for (std::size_t g = 0; g < groups; ++g) {
      const double ca = lower[at_a + g], cb = lower[at_b + g];
      bound = std::min(bound, std::min(std::min(ca, cb), 0.5 * (ca + cb - rates[rate + g] * h)));
    }
    open.push({bound, curve, a, b, at_a, at_b, rate});
  };
  // States at most kInitialTravel apart over [begin, end] of a curve, whose joints move at most
  // speed_i per unit of the parameter.
  const auto cover = [&](std::size_t curve, double begin, double end, const Eigen::VectorXd& speed) {
    const double length = end - begin;
    const Eigen::VectorXd sweep = checker.GroupSweepBounds(speed);
    const std::size_t rate = rates.size();
    for (std::size_t g = 0; g < groups; ++g) rates.push_back(sweep[static_cast<Eigen::Index>(g)]);
    const int m = std::max(1, static_cast<int>(std::ceil(speed.maxCoeff() * length / kInitialTravel)));
    double a = begin;
    std::size_t at_a = clearance(curve, a);
    for (int i = 1; i <= m; ++i) {
      const double b = i == m ? end : begin + length * i / m;
      const std::size_t at_b = clearance(curve, b);
      push(curve, a, b, at_a, at_b, rate);
      a = b;
      at_a = at_b;
    }
  };
  for (const Piece& piece : trajectory.pieces()) {
    const std::size_t at = curves.size();
    Eigen::VectorXd a, b;
    if (detail::LineSegmentOf(piece, &a, &b)) {
      curves.push_back(detail::SegmentCurve(a, b, robot));
      cover(at, 0.0, 1.0, (b - a).cwiseAbs());
      continue;
    }
    curves.push_back([&piece, &robot](double tau, Eigen::VectorXd* q) { detail::ClampedPosition(piece, tau, robot, q); });
    if (!(piece.duration > 0.0)) {
      clearance(at, 0.0);
    } else {
      for (const detail::PieceSpan& span : detail::SplitPiece(piece, detail::kCertifiedSpanTravel)) {
        const double length = span.end - span.begin;
        if (length > 0.0) cover(at, span.begin, span.end, detail::SpanSpeedBound(piece, span) / length);
      }
    }
  }
  // Far from obstacles a tight absolute tolerance costs many states and says little: the
  // tolerance grows with the clearance (a lower bound either way).
  const auto tolerance = [&] { return std::max(kClearanceTolerance, kClearanceRelativeTolerance * best); };
  while (!open.empty() && open.top().bound < best - tolerance() && evaluated < kMaxClearanceStates) {
    const Interval top = open.top();
    open.pop();
    const double mid = 0.5 * (top.a + top.b);
    if (!(mid > top.a && mid < top.b)) {
      best = std::min(best, top.bound);  // cannot split further: keep its bound
      continue;
    }
    const std::size_t at_mid = clearance(top.curve, mid);
    push(top.curve, top.a, mid, top.at_a, at_mid, top.rate);
    push(top.curve, mid, top.b, at_mid, top.at_b, top.rate);
  }
  double out = best;
  if (!open.empty()) out = std::min(out, open.top().bound);
  return std::max(0.0, out);
}

}  // namespace

TrajectoryQuality MeasureTrajectory(const TimedTrajectory& trajectory, const KinematicLimits& limits,
                                    const JointPath& path, const CollisionChecker* checker, double max_joint_step) {
  TrajectoryQuality out;
  out.duration = trajectory.duration();
  out.min_clearance = std::numeric_limits<double>::infinity();
  if (trajectory.empty()) return out;
  const int n = trajectory.num_dofs();
  // Exact figures, piece by piece.
  for (const Piece& piece : trajectory.pieces()) {
    for (int i = 0; i < n; ++i) {
      const Eigen::VectorXd c = Row(piece, i);
      const int size = static_cast<int>(c.size());
      if (limits.max_velocity.size() == n) {
        out.max_velocity_ratio = std::max(
            out.max_velocity_ratio, poly::MaxAbsDerivative(c.data(), size, 1, piece.duration) / limits.max_velocity[i]);
      }
      if (limits.max_acceleration.size() == n) {
        out.max_acceleration_ratio =
            std::max(out.max_acceleration_ratio,
                     poly::MaxAbsDerivative(c.data(), size, 2, piece.duration) / limits.max_acceleration[i]);
      }
      const double jerk = poly::MaxAbsDerivative(c.data(), size, 3, piece.duration);
      out.max_jerk = std::max(out.max_jerk, jerk);
      if (limits.max_jerk.size() == n) out.max_jerk_ratio = std::max(out.max_jerk_ratio, jerk / limits.max_jerk[i]);
    }
  }
  out.jerk_integral = JerkIntegral(trajectory);
  // Sampled figures: states spaced by at most `step` of joint motion within each piece, and
  // every piece boundary (where a waypoint is passed exactly when the robot stops there).
  std::vector<double> travel;  // per piece
  double total_travel = 0.0;
  for (const Piece& piece : trajectory.pieces()) {
    travel.push_back(piece.MaxJointTravel());
    total_travel += travel.back();
  }
  const double step = std::max(max_joint_step, total_travel / 2000.0);
  const bool effort = checker != nullptr && limits.max_effort.size() == n && HasInertia(checker->robot());
  DynamicsOptions dynamics;
  dynamics.gravity = limits.gravity;
  // The sampled states' positions, one column each (the velocities and accelerations only when
  // torques are measured), evaluated piece by piece: no sample allocates.
  std::size_t count = 1;  // the first piece's start, then each piece's states after its start
  std::vector<int> per_piece;
  for (const double t : travel) {
    per_piece.push_back(std::max(1, static_cast<int>(std::ceil(t / step))));
    count += static_cast<std::size_t>(per_piece.back());
  }
  Eigen::MatrixXd states(n, static_cast<Eigen::Index>(count));
  Eigen::Index filled = 0;
  const bool bound_clearance = checker != nullptr && checker->certifies_motion();
  const PathConstraints* constraints = checker != nullptr ? checker->path_constraints() : nullptr;
  const int clearance_every = std::max<int>(1, static_cast<int>(count) / 200);
  Eigen::VectorXd q(n);
  for (std::size_t p = 0; p < trajectory.pieces().size(); ++p) {
    const Piece& piece = trajectory.pieces()[p];
    const int m = per_piece[p];
    const double* const c = piece.coefficients.data();
    const int size = static_cast<int>(piece.coefficients.cols());
    for (int i = filled == 0 ? 0 : 1; i <= m; ++i) {
      const double tau = piece.duration * i / m;
      const bool last = p + 1 == trajectory.pieces().size() && i == m;
      if (last) {
        q = trajectory.Evaluate(trajectory.duration()).q;  // the exact end
      } else {
        for (int j = 0; j < n; ++j) q[j] = tau == 0.0 ? c[j] : poly::Eval(c + j, size, tau, n);
      }
      states.col(filled) = q;
      if (constraints != nullptr) out.max_constraint_ratio = std::max(out.max_constraint_ratio, constraints->WorstRatio(q));
      // Off the sphere path: the clearance at (at most about 200 of) the sampled states.
      if (checker != nullptr && !bound_clearance && (filled % clearance_every == 0 || last)) {
        out.min_clearance = std::min(out.min_clearance, checker->Clearance(q));
      }
      if (effort) {
        // Both sides of a piece boundary, where the acceleration may jump.
        const auto torque = [&](const TrajectorySample& x) {
          const Eigen::VectorXd joint = InverseDynamics(checker->robot(), q, x.qd, x.qdd, dynamics);
          for (int k = 0; k < n; ++k) {
            out.max_effort_ratio = std::max(out.max_effort_ratio, std::abs(joint[k]) / limits.max_effort[k]);
          }
        };
        torque(piece.State(tau));
        if (i == m && !last) torque(trajectory.pieces()[p + 1].State(0.0));
      }
      ++filled;
    }
  }
  if (bound_clearance) out.min_clearance = ClearanceLowerBound(trajectory, *checker);
  if (path.size() >= 2) {
    // max over points of the distance to the nearest part of the other side (a path segment, or
    // a trajectory piece). A point whose distance to some part is at most the deviation so far
    // cannot raise it, so its search stops there; it starts at the part nearest the previous
    // point (consecutive points are near the same part), which usually ends it at once. Exact
    // either way.
    const auto deviation = [&](std::size_t points, const auto& point, std::size_t segments, const auto& segment) {
      std::size_t start = 0;
      for (std::size_t p = 0; p < points; ++p) {
        double nearest = std::numeric_limits<double>::infinity();
        std::size_t at = start;
        for (std::size_t i = 0; i < segments && nearest > out.max_deviation; ++i) {
          const std::size_t k = (start + i) % segments;
          const double d = segment(point(p), k);
          if (d < nearest) {
            nearest = d;
            at = k;
          }
        }
        start = at;
        out.max_deviation = std::max(out.max_deviation, nearest);
      }
    };
    deviation(
        static_cast<std::size_t>(states.cols()), [&](std::size_t p) { return states.col(static_cast<Eigen::Index>(p)); },
        path.size() - 1, [&](const auto& x, std::size_t k) { return DistanceToSegment(x, path[k], path[k + 1]); });
    // Between the sampled states, exactly (to 1e-9 rad) by bounds on spans of the pieces.
    RefineDeviation(trajectory, path, &out.max_deviation);
    // Each waypoint to the trajectory itself, exactly: per piece the least of |q(τ) − w|² (a
    // polynomial, poly::Range), not chords between sampled states (which lie outside a blend's
    // curve and overstated the distance to the corner it cuts).
    deviation(
        path.size(), [&](std::size_t p) -> const Eigen::VectorXd& { return path[p]; }, trajectory.pieces().size(),
        [&](const Eigen::VectorXd& w, std::size_t k) { return DistanceToPiece(w, trajectory.pieces()[k]); });
  }
  return out;
}

double JerkIntegral(const TimedTrajectory& trajectory) {
  double total = 0.0;
  for (const Piece& piece : trajectory.pieces()) {
    const int size = static_cast<int>(piece.coefficients.cols());
    if (size < 4) continue;
    for (Eigen::Index i = 0; i < piece.coefficients.rows(); ++i) {
      // ∫ (q⃛ᵢ)² dτ of the jerk polynomial, exactly: square it, integrate term by term.
      std::vector<double> j;
      for (int p = 3; p < size; ++p) j.push_back(piece.coefficients(i, p) * p * (p - 1) * (p - 2));
      double integral = 0.0;
      for (std::size_t a = 0; a < j.size(); ++a) {
        for (std::size_t b = 0; b < j.size(); ++b) {
          const int power = static_cast<int>(a + b) + 1;
          integral += j[a] * j[b] * std::pow(piece.duration, power) / power;
        }
      }
      total += integral;
    }
  }
  return total;
}

double MaxDistanceToSegment(const Piece& piece, const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  const int n = static_cast<int>(piece.coefficients.rows());
  const int size = static_cast<int>(piece.coefficients.cols());
  const Eigen::VectorXd ab = b - a;
  const double length = ab.norm();
  const Eigen::VectorXd d = length > 0.0 ? Eigen::VectorXd(ab / length) : Eigen::VectorXd::Zero(n);
  // e(τ) = q(τ) − a per joint, and along(τ) = d̂ᵀe(τ).
  Eigen::MatrixXd e = piece.coefficients;
  e.col(0) -= a;
  const Eigen::RowVectorXd along = d.transpose() * e;
  std::vector<double> square(static_cast<std::size_t>(2 * size - 1), 0.0), row(static_cast<std::size_t>(size));
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < size; ++j) row[j] = e(i, j) - along[j] * d[i];
    AddSquare(row, &square);
  }
  double lo, hi;
  poly::Range(square.data(), 2 * size - 1, piece.duration, &lo, &hi);
  double excess = 0.0;
  if (length > 0.0) {
    const std::vector<double> s(along.data(), along.data() + size);
    double s_lo, s_hi;
    poly::Range(s.data(), size, piece.duration, &s_lo, &s_hi);
    excess = std::max({0.0, -s_lo, s_hi - length});
  }
  return std::sqrt(std::max(0.0, hi) + excess * excess);
}

}  // namespace chasles
