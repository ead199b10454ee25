#include "chasles/multi/velocity_obstacles.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "chasles/robot/error.h"
#include "chasles/robot/geometry.h"

namespace chasles {

// ---------------------------------------------------------------------------------------------
// MovingDisc.

namespace {

void CheckDiscShape(const MovingDisc& disc) {
  if (disc.times.empty() || disc.centres.size() != disc.times.size()) {
    ThrowInvalid("disc '" + disc.name + "' has " + std::to_string(disc.times.size()) + " times and " +
                 std::to_string(disc.centres.size()) + " centres; it needs at least one time and one centre per time");
  }
}

/// Index k of the path piece [times[k], times[k + 1]) that holds t; precondition
/// times.front() <= t < times.back().
std::size_t PieceIndex(const std::vector<double>& times, double t) {
  const auto after = std::upper_bound(times.begin(), times.end(), t);
  return static_cast<std::size_t>(after - times.begin()) - 1;
}

}  // namespace

Eigen::Vector2d MovingDisc::CentreAt(double t) const {
  CheckDiscShape(*this);
  if (!(t > times.front())) return centres.front();  // NaN counts as before the path
  if (t >= times.back()) return centres.back();
  const std::size_t k = PieceIndex(times, t);
  const double fraction = (t - times[k]) / (times[k + 1] - times[k]);
  return centres[k] + fraction * (centres[k + 1] - centres[k]);
}

Eigen::Vector2d MovingDisc::VelocityAt(double t) const {
  CheckDiscShape(*this);
  if (!(t >= times.front()) || t >= times.back()) return Eigen::Vector2d::Zero();
  const std::size_t k = PieceIndex(times, t);
  return (centres[k + 1] - centres[k]) / (times[k + 1] - times[k]);
}

// ---------------------------------------------------------------------------------------------
// The planner.

namespace {

using Piece = TimedTrajectory::Piece;

constexpr double kInfinity = std::numeric_limits<double>::infinity();
constexpr double kPi = 3.14159265358979323846;
/// States along a motion checked at most this far apart when the checker does not certify [m, rad].
constexpr double kMotionStep = 0.005;
/// The final approach (brake, then a straight rest-to-rest motion onto the goal) is tried once the
/// point where the base would come to rest is within this (or goal_tolerance, if larger) of the
/// goal in the plane [m].
constexpr double kFinalApproachRadius = 0.1;
/// The final approach is checked against the discs' true paths at states this far apart in time [s].
constexpr double kApproachSampling = 0.01;
/// Without progress (kProgressDistance along the path, or kProgressAngle of heading) for this long
/// in simulated time [s], the base counts as boxed in.
constexpr double kStallSeconds = 10.0;
constexpr double kProgressDistance = 0.01;  ///< [m]
constexpr double kProgressAngle = 0.01;     ///< [rad]
/// A guide vertex this close is passed even when the next one is not in sight [m].
constexpr double kGuideReachedDistance = 0.05;
/// Candidates whose step is checked against the static scene per control step; after them the
/// base brakes.
constexpr int kMaxSceneChecks = 12;
/// Weight of |v_new − v_old| in a candidate's cost |v_new − v_pref| + weight·|v_new − v_old|.
constexpr double kChangePenalty = 0.1;

/// A number for messages, to the millimetre / milliradian / millisecond (never "-0").
std::string Rounded(double value) { return FormatNumber(std::round(value * 1000.0) / 1000.0 + 0.0); }
std::string PointText(const Eigen::Vector2d& point) {
  return "(" + Rounded(point.x()) + ", " + Rounded(point.y()) + ")";
}

// --- validation -------------------------------------------------------------------------------

void ValidatePlanarConfiguration(const Eigen::VectorXd& q, const std::string& field) {
  if (q.size() != 3) {
    ThrowInvalid(field + " has " + std::to_string(q.size()) +
                 " values; a planar robot has 3 coordinates (x, y, theta)");
  }
  for (int i = 0; i < 3; ++i) {
    if (!std::isfinite(q[i])) {
      ThrowInvalid(field + "[" + std::to_string(i) + "] = " + FormatNumber(q[i]) + " must be finite");
    }
  }
}

void RequirePositive(double value, const std::string& field) {
  if (!(std::isfinite(value) && value > 0.0)) {
    ThrowInvalid(field + " = " + FormatNumber(value) + " must be finite and > 0");
  }
}

void RequireNonNegative(double value, const std::string& field) {
  if (!(std::isfinite(value) && value >= 0.0)) {
    ThrowInvalid(field + " = " + FormatNumber(value) + " must be finite and >= 0");
  }
}

void RequireWithin(int value, int lower, int upper, const std::string& field) {
  if (value < lower || value > upper) {
    ThrowInvalid(field + " = " + std::to_string(value) + " must be within [" + std::to_string(lower) + ", " +
                 std::to_string(upper) + "]");
  }
}

void ValidateOptions(const VelocityObstacleOptions& options) {
  RequirePositive(options.time_step, "options.time_step");
  RequirePositive(options.horizon, "options.horizon");
  RequireWithin(options.heading_samples, 4, 720, "options.heading_samples");
  RequireWithin(options.speed_samples, 1, 100, "options.speed_samples");
  RequireNonNegative(options.margin, "options.margin");
  RequireNonNegative(options.goal_tolerance, "options.goal_tolerance");
  RequirePositive(options.max_duration, "options.max_duration");
  constexpr double kMaxSteps = 1e7;
  if (options.max_duration / options.time_step > kMaxSteps) {
    ThrowInvalid("options.max_duration = " + FormatNumber(options.max_duration) +
                 " s is more than 1e7 steps of options.time_step = " + FormatNumber(options.time_step) +
                 " s; shorten it or take longer steps");
  }
}

void ValidateDiscs(const std::vector<MovingDisc>& discs) {
  for (std::size_t i = 0; i < discs.size(); ++i) {
    const MovingDisc& disc = discs[i];
    const std::string field = "discs[" + std::to_string(i) + "]";
    RequirePositive(disc.radius, field + ".radius");
    if (disc.times.empty()) ThrowInvalid(field + ".times is empty; a disc needs at least one time");
    for (std::size_t k = 0; k < disc.times.size(); ++k) {
      const std::string entry = field + ".times[" + std::to_string(k) + "] = " + FormatNumber(disc.times[k]);
      if (!std::isfinite(disc.times[k])) ThrowInvalid(entry + " must be finite");
      if (k > 0 && !(disc.times[k] > disc.times[k - 1])) {
        ThrowInvalid(entry + " must be greater than the previous " + FormatNumber(disc.times[k - 1]));
      }
    }
    if (disc.centres.size() != disc.times.size()) {
      ThrowInvalid(field + ".centres has " + std::to_string(disc.centres.size()) + " values but " + field + ".times has " +
                   std::to_string(disc.times.size()) + "; one centre per time");
    }
    for (std::size_t k = 0; k < disc.centres.size(); ++k) {
      if (!disc.centres[k].allFinite()) {
        ThrowInvalid(field + ".centres[" + std::to_string(k) + "] = (" + FormatNumber(disc.centres[k].x()) + ", " +
                     FormatNumber(disc.centres[k].y()) + ") must be finite");
      }
    }
  }
}

// --- the base's bounding disc -----------------------------------------------------------------

/// How far a shape reaches in the plane from the vertical line through its origin, with
/// `rotation` its orientation in the world: exact for a sphere and for an upright cylinder or
/// capsule, else the radius of the ball about its origin that holds it (conservative).
double PlanarExtent(const Shape& shape, const Eigen::Matrix3d& rotation) {
  switch (shape.type) {
    case ShapeType::kSphere:
      return shape.radius;
    case ShapeType::kCylinder:
    case ShapeType::kCapsule:
      if (std::abs(rotation(2, 2)) >= 1.0 - 1e-12) return shape.radius;  // axis along world z
      return BoundingRadius(shape);
    default:
      return BoundingRadius(shape);
  }
}

/// The radius [m] about (x, y) of a disc that holds the footprint of every collision shape
/// carried by the planar coordinates, at every heading. At q = 0 a shape's origin is at c (plane)
/// and the heading turns about the vertical axis through a (plane; the origin for
/// RobotFromMobile); at (x, y, θ) the origin is at (x, y) + a + R(θ)(c − a), whose distance from
/// (x, y) is at most |a| + |c − a|.
double BaseRadius(const RobotModel& robot) {
  std::vector<Eigen::Isometry3d> poses;
  robot.ForwardKinematics(Eigen::VectorXd::Zero(robot.num_dofs()), &poses);
  Eigen::Vector2d axis_point = Eigen::Vector2d::Zero();
  const int heading = robot.moving_index(robot.dof_joint(2));
  if (heading >= 0) {
    // A revolute screw (ω, v), |ω| = 1, has v = −ω × a for a point a on its axis, so the foot
    // of the perpendicular from the origin is ω × v.
    const Eigen::Matrix<double, 6, 1>& screw = robot.space_screw_axis(heading);
    axis_point = screw.head<3>().cross(screw.tail<3>()).head<2>();
  }
  double radius = 0.0;
  for (int link = 0; link < robot.num_links(); ++link) {
    if (robot.link_chain(link).empty()) continue;  // fixed to the world: not part of the base
    for (const Shape& shape : robot.links()[link].collision) {
      const Eigen::Isometry3d placed = poses[link] * shape.pose;
      const Eigen::Vector2d centre = placed.translation().head<2>();
      radius = std::max(radius, axis_point.norm() + (centre - axis_point).norm() + PlanarExtent(shape, placed.linear()));
    }
  }
  return radius;
}

// --- kinematics -------------------------------------------------------------------------------

Eigen::VectorXd Configuration(const Eigen::Vector3d& q) { return Eigen::VectorXd(q); }

/// One constant-acceleration piece: q(τ) = q0 + v0 τ + ½ a τ².
Piece ConstantAccelerationPiece(double t0, double duration, const Eigen::Vector3d& position,
                                const Eigen::Vector3d& velocity, const Eigen::Vector3d& acceleration) {
  Piece piece;
  piece.t0 = t0;
  piece.duration = duration;
  piece.coefficients.resize(3, 3);
  piece.coefficients.col(0) = position;
  piece.coefficients.col(1) = velocity;
  piece.coefficients.col(2) = 0.5 * acceleration;
  return piece;
}

/// The piece's position at local time tau, by Horner's rule as TimedTrajectory evaluates it.
Eigen::Vector3d PositionAt(const Piece& piece, double tau) {
  return piece.coefficients.col(0) + tau * (piece.coefficients.col(1) + tau * piece.coefficients.col(2));
}

/// [s] first time s >= 0 at which two points moving at constant velocities come within
/// `radius` of each other: relative position r and velocity w (of one with respect to the
/// other), |r + s w| = radius, i.e. |w|² s² + 2 (r·w) s + |r|² − radius² = 0. +inf when they
/// never do. Already within `radius`: 0 unless they are separating (r·w > 0), then +inf — a
/// motion that leaves the inflated disc is allowed.
double TimeToCollision(const Eigen::Vector2d& relative_position, const Eigen::Vector2d& relative_velocity, double radius) {
  const double gap = relative_position.squaredNorm() - radius * radius;  // constant term
  const double half_slope = relative_position.dot(relative_velocity);    // ½ the linear term
  if (gap <= 0.0) return half_slope > 0.0 ? kInfinity : 0.0;
  if (half_slope >= 0.0) return kInfinity;  // the distance only grows
  const double rate = relative_velocity.squaredNorm();
  const double discriminant = half_slope * half_slope - rate * gap;
  if (discriminant < 0.0) return kInfinity;  // passes by
  // Smaller root (−b − √D)/a written as c/(−b + √D), which does not cancel.
  return gap / (-half_slope + std::sqrt(discriminant));
}

/// A stretch of a disc's known path over the look-ahead, in time from the current step's start:
/// over [begin, end] [s] its centre moves from `centre` [m] at `velocity` [m/s].
struct DiscStretch {
  double begin = 0.0, end = 0.0;
  Eigen::Vector2d centre, velocity;
  double radius = 0.0;  ///< [m] base + disc + margin
};

/// The stretches of `disc`'s path from time `now` over `horizon` [s]: one per path piece it
/// crosses (a single one, at constant velocity, before its first time or after its last).
void AppendStretches(const MovingDisc& disc, double now, double horizon, double radius,
                     std::vector<DiscStretch>* stretches) {
  double begin = 0.0;
  while (begin < horizon) {
    const double t = now + begin;
    // The piece holding t ends at the next path time after t (none after the last).
    const auto next = std::upper_bound(disc.times.begin(), disc.times.end(), t);
    const double end = next == disc.times.end() ? horizon : std::min(horizon, *next - now);
    stretches->push_back(DiscStretch{begin, end, disc.CentreAt(t), disc.VelocityAt(t), radius});
    if (!(end > begin)) break;  // rounding at a path time: never loop in place
    begin = end;
  }
}

/// [s] when the base, leaving `base` [m] at constant `velocity` [m/s] now, first comes within
/// reach of a disc along its stretches (TimeToCollision on each, where both move at constant
/// velocity); +inf when it does not within them.
double TimeToCollisionAlong(const std::vector<DiscStretch>& stretches, const Eigen::Vector2d& base,
                            const Eigen::Vector2d& velocity) {
  for (const DiscStretch& stretch : stretches) {
    const Eigen::Vector2d relative = base + stretch.begin * velocity - stretch.centre;
    const double within = TimeToCollision(relative, velocity - stretch.velocity, stretch.radius);
    if (within <= stretch.end - stretch.begin) return stretch.begin + within;
  }
  return kInfinity;
}

/// One control step the base may take: planar velocity at the end of the step [m/s] and its
/// cost; `brake` marks the step along the stop certified at the previous step.
struct Candidate {
  Eigen::Vector2d velocity;
  double cost = 0.0;
  double time_to_collision = kInfinity;  ///< [s] against the discs' velocity obstacles
  bool brake = false;
};

class VelocityObstaclePlanner {
 public:
  VelocityObstaclePlanner(const CollisionChecker& checker, const Eigen::VectorXd& start, const Eigen::VectorXd& goal,
                          const std::vector<MovingDisc>& discs, const KinematicLimits& limits, const JointPath& guide,
                          const VelocityObstacleOptions& options, const Termination& termination)
      : checker_(checker), discs_(discs), options_(options), termination_(termination), start_(start), goal_(goal) {
    // Constant acceleration per step: jerk and effort limits are not part of this motion model.
    limits_.max_velocity = limits.max_velocity;
    limits_.max_acceleration = limits.max_acceleration;
    max_velocity_ = limits.max_velocity.head<3>();
    max_acceleration_ = limits.max_acceleration.head<3>();
    planar_speed_ = std::min(max_velocity_.x(), max_velocity_.y());
    planar_acceleration_ = std::min(max_acceleration_.x(), max_acceleration_.y());
    lower_ = checker.robot().lower_limits().head<3>();
    upper_ = checker.robot().upper_limits().head<3>();
    base_radius_ = BaseRadius(checker.robot());
    for (const Eigen::VectorXd& vertex : guide) {
      waypoints_.push_back(vertex.head<2>());
      waypoint_headings_.push_back(vertex[2]);
    }
    waypoints_.push_back(goal_.head<2>());
    waypoint_headings_.push_back(goal_.z());
    length_after_.assign(waypoints_.size(), 0.0);
    for (std::size_t k = waypoints_.size() - 1; k-- > 0;) {
      length_after_[k] = length_after_[k + 1] + (waypoints_[k + 1] - waypoints_[k]).norm();
    }
    disc_stretches_.resize(discs_.size());
  }

  VelocityObstacleResult Plan() {
    position_ = start_;
    velocity_.setZero();
    leg_origin_ = start_;
    result_.path.push_back(Configuration(position_));
    result_.min_disc_distance = kInfinity;
    RecordDiscDistance(0.0, position_.head<2>());
    if (!checker_.IsValid(Configuration(start_))) return Unreached(InvalidStateText("start", start_));
    if (!checker_.IsValid(Configuration(goal_))) return Unreached(InvalidStateText("goal", goal_));
    best_remaining_ = RemainingPath();
    best_heading_error_ = std::abs(goal_.z() - position_.z());
    while (true) {
      if (termination_.ShouldStop()) {
        return StopHere("stopped by the termination condition (" + ReasonText(termination_.Reason()) + ") at t = " +
                        Rounded(time_) + " s of simulated time");
      }
      if (time_ >= options_.max_duration) {
        return StopHere("did not reach the goal within max_duration = " + FormatNumber(options_.max_duration) +
                        " s of simulated time");
      }
      if (time_ - last_progress_time_ >= kStallSeconds) {
        return StopHere("boxed in: no progress toward the goal for " + FormatNumber(kStallSeconds) +
                        " s of simulated time (t = " + Rounded(time_) + " s)");
      }
      if (TryFinalApproach()) return Finish();
      UpdateTarget();
      TakeStep();
    }
  }

 private:
  static std::string ReasonText(StopReason reason) {
    switch (reason) {
      case StopReason::kBudget: return "time budget spent";
      case StopReason::kDeadline: return "deadline";
      case StopReason::kCancelled: return "cancelled";
      default: return "none";
    }
  }

  std::string InvalidStateText(const std::string& field, const Eigen::Vector3d& q) const {
    const CollisionResult contact = checker_.Check(Configuration(q));
    std::string text = field + " (x, y, theta) = (" + Rounded(q.x()) + ", " + Rounded(q.y()) + ", " + Rounded(q.z()) +
                       ") is not valid";
    if (contact.in_collision) {
      text += contact.violation.empty() ? ": link '" + contact.link_a + "' touches '" + contact.other + "'" + VoxelText(contact)
                                        : ": " + contact.violation;
    } else {
      text += ": outside the joint limits";
    }
    return text;
  }

  // --- bookkeeping ---------------------------------------------------------------------------

  void RecordDiscDistance(double t, const Eigen::Vector2d& base) {
    for (const MovingDisc& disc : discs_) {
      const double distance = (base - disc.CentreAt(t)).norm() - base_radius_ - disc.radius;
      result_.min_disc_distance = std::min(result_.min_disc_distance, distance);
    }
  }

  void Append(const Piece& piece) {
    pieces_.push_back(piece);
    pieces_.back().t0 = time_;
    time_ += piece.duration;
  }

  /// Path length left [m]: to the current target, then along the rest of the guide to the goal.
  double RemainingPath() const {
    return (waypoints_[target_] - position_.head<2>()).norm() + length_after_[target_];
  }

  /// [s] the shortest stop of all three coordinates together (each decelerating in proportion),
  /// rounded up to a whole number of control steps. Stopping along that common time keeps the
  /// motion on one straight (x, y, θ) segment, and braking one step along it leaves a stop that
  /// lies on the same segment (its time is at most one step shorter), so the stop certified at
  /// one step stays available at the next.
  double BrakeTime(const Eigen::Vector3d& velocity) const {
    const double shortest = velocity.cwiseAbs().cwiseQuotient(max_acceleration_).maxCoeff();
    if (shortest == 0.0) return 0.0;
    const double steps = std::max(1.0, std::ceil(shortest / options_.time_step - 1e-12));
    return steps * options_.time_step;
  }

  VelocityObstacleResult Unreached(const std::string& message) {
    result_.reached = false;
    result_.message = message;
    return Finish();
  }

  /// Brakes to rest along the stop certified at the last step, then reports `reason`.
  VelocityObstacleResult StopHere(const std::string& reason) {
    const double brake_time = BrakeTime(velocity_);
    if (brake_time > 0.0) {
      const Piece brake = ConstantAccelerationPiece(0.0, brake_time, position_, velocity_, -velocity_ / brake_time);
      Append(brake);
      position_ = PositionAt(brake, brake_time);
      velocity_.setZero();
      result_.path.push_back(Configuration(position_));
      RecordDiscDistance(time_, position_.head<2>());
    }
    const double from_goal = (goal_.head<2>() - position_.head<2>()).norm();
    return Unreached(reason + "; stopped at (x, y) = " + PointText(position_.head<2>()) + " m, " + Rounded(from_goal) +
                     " m from the goal");
  }

  VelocityObstacleResult Finish() {
    if (pieces_.empty()) {
      result_.trajectory = HoldTrajectory(Configuration(position_), 0.0);
    } else if (result_.reached) {
      result_.trajectory = TimedTrajectory(pieces_, Configuration(goal_));
    } else {
      result_.trajectory = TimedTrajectory(pieces_);
    }
    result_.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start_).count();
    return std::move(result_);
  }

  // --- final approach ------------------------------------------------------------------------

  /// Once the point where the base would come to rest is near the goal: brake to it (the stop
  /// certified at the last step), then the exact straight rest-to-rest motion to the goal in
  /// (x, y, θ), if that is free of the scene and keeps `margin` from every disc along the discs'
  /// true paths. Appends it and returns true, else changes nothing.
  bool TryFinalApproach() {
    const double brake_time = BrakeTime(velocity_);
    const Eigen::Vector3d rest = position_ + 0.5 * brake_time * velocity_;
    if ((goal_.head<2>() - rest.head<2>()).norm() > std::max(kFinalApproachRadius, options_.goal_tolerance)) return false;
    if (!checker_.IsMotionFree(Configuration(rest), Configuration(goal_), kMotionStep)) return false;

    std::vector<Piece> approach;
    if (brake_time > 0.0) {
      approach.push_back(ConstantAccelerationPiece(0.0, brake_time, position_, velocity_, -velocity_ / brake_time));
    }
    const TimedTrajectory landing = ParameterizeRestToRest({Configuration(rest), Configuration(goal_)}, limits_);
    for (Piece piece : landing.pieces()) {
      if (piece.duration <= 0.0) continue;  // zero-length landing (already on the goal)
      piece.t0 += brake_time;
      approach.push_back(std::move(piece));
    }

    // The discs' true motions along the approach, every kApproachSampling.
    double closest = kInfinity;
    if (!approach.empty() && !discs_.empty()) {
      const TimedTrajectory motion(approach, Configuration(goal_));
      const double duration = motion.duration();
      const int samples = static_cast<int>(std::ceil(duration / kApproachSampling));
      for (int i = 0; i <= samples; ++i) {
        const double tau = std::min(duration, i * kApproachSampling);
        const Eigen::Vector2d base = motion.Evaluate(tau).q.head<2>();
        for (const MovingDisc& disc : discs_) {
          const double distance = (base - disc.CentreAt(time_ + tau)).norm() - base_radius_ - disc.radius;
          if (distance <= options_.margin) return false;
          closest = std::min(closest, distance);
        }
      }
    }

    result_.min_disc_distance = std::min(result_.min_disc_distance, closest);
    const double approach_start = time_;
    for (const Piece& piece : approach) {
      pieces_.push_back(piece);
      pieces_.back().t0 += approach_start;
      time_ = pieces_.back().t0 + piece.duration;
    }
    if (brake_time > 0.0) result_.path.push_back(Configuration(rest));
    if (result_.path.back() != Configuration(goal_)) result_.path.push_back(Configuration(goal_));
    position_ = goal_;
    velocity_.setZero();
    result_.reached = true;
    return true;
  }

  // --- steering ------------------------------------------------------------------------------

  /// Waypoint k is in sight when the straight (x, y, θ) motion from the current state to it
  /// (its heading) is free of the scene: the motion the base makes toward it.
  bool Visible(std::size_t k) const {
    const Eigen::Vector3d there(waypoints_[k].x(), waypoints_[k].y(), waypoint_headings_[k]);
    return checker_.IsMotionFree(Configuration(position_), Configuration(there), kMotionStep);
  }

  void SetTarget(std::size_t k) {
    target_ = k;
    leg_origin_ = position_;
  }

  /// Guide target rule: the target only moves forward, to the next vertex while that one is in
  /// sight or the current one is within kGuideReachedDistance — so the target is the farthest
  /// vertex of the run in sight beyond the last one passed. After a step the scene blocked, the
  /// current target is checked again and, when it is out of sight, the target falls back to the
  /// latest earlier vertex in sight.
  void UpdateTarget() {
    if (waypoints_.size() == 1) return;
    if (scene_blocked_ && !Visible(target_)) {
      for (std::size_t k = target_; k-- > 0;) {
        if (Visible(k)) {
          SetTarget(k);
          break;
        }
      }
    }
    scene_blocked_ = false;
    while (target_ + 1 < waypoints_.size()) {
      const bool reached = (waypoints_[target_] - position_.head<2>()).norm() < kGuideReachedDistance;
      if (!reached && !Visible(target_ + 1)) break;
      SetTarget(target_ + 1);
    }
  }

  /// [rad] the heading to hold now: from the heading where the base took up its target to the
  /// target's, in proportion to the planar distance covered (as on the straight (x, y, θ)
  /// segment between them), so a long body turns as the guide does rather than ahead of it.
  double HeadingReference() const {
    const double leg = (waypoints_[target_] - leg_origin_.head<2>()).norm();
    const double left = (waypoints_[target_] - position_.head<2>()).norm();
    const double fraction = leg > 1e-9 ? std::clamp(1.0 - left / leg, 0.0, 1.0) : 1.0;
    return leg_origin_.z() + fraction * (waypoint_headings_[target_] - leg_origin_.z());
  }

  /// [m/s] toward the target at the planar speed limit, slowed so the base can still stop at the
  /// goal: v ≤ √(2·a·d) (d the path left, a the planar acceleration limit) and v ≤ d/dt.
  Eigen::Vector2d PreferredVelocity() const {
    const Eigen::Vector2d to_target = waypoints_[target_] - position_.head<2>();
    const double distance = to_target.norm();
    if (distance < 1e-9) return Eigen::Vector2d::Zero();
    const double remaining = RemainingPath();
    const double speed = std::min({planar_speed_, std::sqrt(2.0 * planar_acceleration_ * remaining),
                                   remaining / options_.time_step});
    return to_target * (speed / distance);
  }

  /// [rad/s] the heading rate at the end of the step, turning toward HeadingReference() as fast
  /// as the angular limits allow while still able to stop on it (ω ≤ √(2·α·|Δθ|)).
  double PlannedTurnRate() const {
    const double error = HeadingReference() - position_.z();
    const double dt = options_.time_step;
    const double speed = std::min({max_velocity_.z(), std::sqrt(2.0 * max_acceleration_.z() * std::abs(error)),
                                   std::abs(error) / dt});
    const double desired = std::copysign(speed, error);
    const double reach = max_acceleration_.z() * dt;
    const double rate = std::clamp(desired, velocity_.z() - reach, velocity_.z() + reach);
    return std::clamp(rate, -max_velocity_.z(), max_velocity_.z());
  }

  /// [rad/s] the heading rate after braking the turn as hard as allowed for one step.
  double HoldTurnRate() const {
    const double reach = max_acceleration_.z() * options_.time_step;
    return velocity_.z() - std::copysign(std::min(std::abs(velocity_.z()), reach), velocity_.z());
  }

  /// The candidates, best first: those outside every velocity obstacle by cost, then the others
  /// by decreasing time to collision (the standard fallback when none is outside).
  std::vector<Candidate> RankedCandidates(double brake_time) {
    const double dt = options_.time_step;
    const Eigen::Vector2d current = velocity_.head<2>();
    const Eigen::Vector2d reach = max_acceleration_.head<2>() * dt;
    const Eigen::Vector2d low = (current - reach).cwiseMax(-max_velocity_.head<2>());
    const Eigen::Vector2d high = (current + reach).cwiseMin(max_velocity_.head<2>());
    const Eigen::Vector2d preferred = PreferredVelocity();

    // Standing still, the preferred velocity, the current one and a polar grid aligned with the
    // preferred direction; each one out of reach in one step is replaced by the nearest
    // reachable velocity (its projection onto the box the acceleration limits allow).
    std::vector<Eigen::Vector2d> velocities = {Eigen::Vector2d::Zero(), preferred, current};
    const double base_heading = preferred.squaredNorm() > 0.0 ? std::atan2(preferred.y(), preferred.x()) : 0.0;
    for (int s = 1; s <= options_.speed_samples; ++s) {
      const double speed = planar_speed_ * s / options_.speed_samples;
      for (int h = 0; h < options_.heading_samples; ++h) {
        const double heading = base_heading + 2.0 * kPi * h / options_.heading_samples;
        velocities.emplace_back(speed * std::cos(heading), speed * std::sin(heading));
      }
    }
    std::vector<Candidate> candidates;
    candidates.reserve(velocities.size() + 1);
    for (const Eigen::Vector2d& velocity : velocities) {
      Candidate candidate;
      candidate.velocity = velocity.cwiseMax(low).cwiseMin(high);
      candidates.push_back(candidate);
    }
    // Braking along the stop certified at the previous step (always free of the scene).
    Candidate brake;
    brake.velocity = brake_time > 0.0 ? Eigen::Vector2d(current * (1.0 - dt / brake_time)) : Eigen::Vector2d::Zero();
    brake.brake = true;
    candidates.push_back(brake);

    for (Candidate& candidate : candidates) {
      candidate.cost = (candidate.velocity - preferred).norm() + kChangePenalty * (candidate.velocity - current).norm();
      for (const std::vector<DiscStretch>& stretches : disc_stretches_) {
        candidate.time_to_collision = std::min(candidate.time_to_collision,
                                               TimeToCollisionAlong(stretches, position_.head<2>(), candidate.velocity));
      }
    }
    const double horizon = options_.horizon;
    std::stable_sort(candidates.begin(), candidates.end(), [horizon](const Candidate& a, const Candidate& b) {
      const bool a_clear = a.time_to_collision > horizon, b_clear = b.time_to_collision > horizon;
      if (a_clear != b_clear) return a_clear;
      if (!a_clear && a.time_to_collision != b.time_to_collision) return a.time_to_collision > b.time_to_collision;
      return a.cost < b.cost;
    });
    return candidates;
  }

  /// The step from the current state to the end velocity (planar velocity, turn rate) with
  /// constant acceleration over one control step, when it stays within the joint limits, is free
  /// of the scene along its curve, and can then stop (the stop BrakeTime gives) free of the scene.
  bool StepIsFree(const Piece& step, const Eigen::Vector3d& end_position, const Eigen::Vector3d& end_velocity) const {
    const double dt = step.duration;
    for (int i = 0; i < 3; ++i) {
      const double coefficients[3] = {step.coefficients(i, 0), step.coefficients(i, 1), step.coefficients(i, 2)};
      double low = 0.0, high = 0.0;
      poly::Range(coefficients, 3, dt, &low, &high);
      if (low < lower_[i] || high > upper_[i]) return false;
    }
    // The velocity is linear over the step, so its largest magnitude is at an end.
    const Eigen::VectorXd speed_bound = Eigen::VectorXd(dt * velocity_.cwiseAbs().cwiseMax(end_velocity.cwiseAbs()));
    if (speed_bound.maxCoeff() > 0.0) {
      const auto curve = [&step](double s, Eigen::VectorXd* q) { *q = PositionAt(step, s * step.duration); };
      if (!checker_.IsCurveCertified(curve, speed_bound)) return false;
    }
    const double brake_time = BrakeTime(end_velocity);
    if (brake_time == 0.0) return true;
    const Eigen::Vector3d rest = end_position + 0.5 * brake_time * end_velocity;
    return checker_.IsMotionFree(Configuration(end_position), Configuration(rest), kMotionStep);
  }

  /// Chooses and appends one control step.
  void TakeStep() {
    const double dt = options_.time_step;
    for (std::size_t d = 0; d < discs_.size(); ++d) {
      disc_stretches_[d].clear();
      const double radius = base_radius_ + discs_[d].radius + options_.margin;
      AppendStretches(discs_[d], time_, options_.horizon, radius, &disc_stretches_[d]);
    }
    const double brake_time = BrakeTime(velocity_);
    const std::vector<Candidate> ranked = RankedCandidates(brake_time);
    const double planned_turn = PlannedTurnRate();
    const double hold_turn = HoldTurnRate();

    const auto make_step = [&](const Eigen::Vector2d& planar, double turn_rate, Piece* step, Eigen::Vector3d* end_position,
                               Eigen::Vector3d* end_velocity) {
      const Eigen::Vector3d acceleration = (Eigen::Vector3d(planar.x(), planar.y(), turn_rate) - velocity_) / dt;
      *step = ConstantAccelerationPiece(0.0, dt, position_, velocity_, acceleration);
      *end_position = PositionAt(*step, dt);
      *end_velocity = velocity_ + acceleration * dt;  // the piece's own derivative at dt
    };

    Piece step;
    Eigen::Vector3d end_position, end_velocity;
    bool chosen = false;
    int examined = 0;
    // Planar displacements [m] of the steps the scene refused. A candidate that would go at
    // least as far in nearly the same direction (within 1.5 heading samples) is skipped, so the
    // checks spread over directions — e.g. reach sliding along a wall — rather than trying
    // every speed into it.
    std::vector<Eigen::Vector2d> refused;
    const double skip_cosine = std::cos(1.5 * 2.0 * kPi / options_.heading_samples);
    const auto like_refused = [&](const Eigen::Vector2d& displacement) {
      return std::any_of(refused.begin(), refused.end(), [&](const Eigen::Vector2d& other) {
        const double length = displacement.norm(), other_length = other.norm();
        if (length == 0.0 || other_length == 0.0) return length == other_length;
        return length >= other_length && displacement.dot(other) >= skip_cosine * length * other_length;
      });
    };
    for (const Candidate& candidate : ranked) {
      if (candidate.brake || examined >= kMaxSceneChecks) break;
      // Displacement over the step at constant acceleration: the mean of the end velocities.
      const Eigen::Vector2d displacement = 0.5 * dt * (velocity_.head<2>() + candidate.velocity);
      if (like_refused(displacement)) continue;
      ++examined;
      // The planned turn first; when that step hits the scene, the same planar velocity with
      // the turn braked (a long body may need to translate before it can turn).
      make_step(candidate.velocity, planned_turn, &step, &end_position, &end_velocity);
      chosen = StepIsFree(step, end_position, end_velocity);
      if (!chosen && hold_turn != planned_turn) {
        make_step(candidate.velocity, hold_turn, &step, &end_position, &end_velocity);
        chosen = StepIsFree(step, end_position, end_velocity);
      }
      if (chosen) break;
      if (examined == 1) scene_blocked_ = true;  // the best candidate ran into the scene
      refused.push_back(displacement);
    }
    if (!chosen) {
      // Brake along the stop certified at the previous step: every coordinate in proportion, so
      // the step and the remaining stop lie on that straight segment (no new check needed).
      const double keep = brake_time > 0.0 ? 1.0 - dt / brake_time : 0.0;
      const Eigen::Vector3d acceleration = (keep * velocity_ - velocity_) / dt;
      step = ConstantAccelerationPiece(0.0, dt, position_, velocity_, acceleration);
      end_position = PositionAt(step, dt);
      end_velocity = velocity_ + acceleration * dt;
    }

    Append(step);
    position_ = end_position;
    velocity_ = end_velocity;
    ++result_.steps;
    result_.path.push_back(Configuration(position_));
    RecordDiscDistance(time_, position_.head<2>());

    const double remaining = RemainingPath();
    const double heading_error = std::abs(goal_.z() - position_.z());
    if (remaining < best_remaining_ - kProgressDistance) {
      best_remaining_ = remaining;
      last_progress_time_ = time_;
    }
    if (heading_error < best_heading_error_ - kProgressAngle) {
      best_heading_error_ = heading_error;
      last_progress_time_ = time_;
    }
  }

  const CollisionChecker& checker_;
  const std::vector<MovingDisc>& discs_;
  const VelocityObstacleOptions& options_;
  const Termination& termination_;
  const std::chrono::steady_clock::time_point wall_start_ = std::chrono::steady_clock::now();

  Eigen::Vector3d start_, goal_;
  KinematicLimits limits_;                            ///< velocity and acceleration only
  Eigen::Vector3d max_velocity_, max_acceleration_;   ///< [m/s, m/s, rad/s], [m/s², m/s², rad/s²]
  double planar_speed_ = 0.0;                         ///< [m/s] min of the x and y limits
  double planar_acceleration_ = 0.0;                  ///< [m/s²] min of the x and y limits
  Eigen::Vector3d lower_, upper_;                     ///< joint limits [m, m, rad]
  double base_radius_ = 0.0;                          ///< [m]

  std::vector<Eigen::Vector2d> waypoints_;  ///< guide vertices (x, y), then the goal's
  std::vector<double> waypoint_headings_;   ///< [rad] their headings θ
  std::vector<double> length_after_;        ///< [m] path length from waypoint k to the goal
  std::size_t target_ = 0;                  ///< the waypoint steered at
  Eigen::Vector3d leg_origin_ = Eigen::Vector3d::Zero();  ///< the state where it became the target
  bool scene_blocked_ = false;              ///< the last step's best candidate hit the scene

  std::vector<std::vector<DiscStretch>> disc_stretches_;  ///< per disc, from the current step's start

  Eigen::Vector3d position_ = Eigen::Vector3d::Zero();  ///< (x, y, θ) [m, m, rad]
  Eigen::Vector3d velocity_ = Eigen::Vector3d::Zero();  ///< [m/s, m/s, rad/s]
  double time_ = 0.0;                                   ///< [s] simulated
  double best_remaining_ = kInfinity, best_heading_error_ = kInfinity, last_progress_time_ = 0.0;

  std::vector<Piece> pieces_;
  VelocityObstacleResult result_;
};

}  // namespace

VelocityObstacleResult PlanWithVelocityObstacles(const CollisionChecker& checker, const Eigen::VectorXd& start,
                                                 const Eigen::VectorXd& goal, const std::vector<MovingDisc>& discs,
                                                 const KinematicLimits& limits, const JointPath& guide,
                                                 const VelocityObstacleOptions& options,
                                                 const Termination& termination) {
  const RobotModel& robot = checker.robot();
  if (robot.kind() != RobotKind::kPlanar || robot.num_dofs() != 3) {
    ThrowInvalid("robot '" + robot.name() + "' is " + ToString(robot.kind()) + " with " + std::to_string(robot.num_dofs()) +
                 " coordinates; velocity obstacles need a planar robot (x, y, theta)");
  }
  ValidatePlanarConfiguration(start, "start");
  ValidatePlanarConfiguration(goal, "goal");
  robot.ValidateConfiguration(start, "start");
  robot.ValidateConfiguration(goal, "goal");
  for (std::size_t k = 0; k < guide.size(); ++k) ValidatePlanarConfiguration(guide[k], "guide[" + std::to_string(k) + "]");
  ValidateDiscs(discs);
  limits.Validate(3);
  ValidateOptions(options);
  VelocityObstaclePlanner planner(checker, start, goal, discs, limits, guide, options, termination);
  return planner.Plan();
}

}  // namespace chasles
