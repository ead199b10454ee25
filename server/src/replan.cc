#include "chasles/server/replan.h"

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "chasles/multi/moving_obstacles.h"
#include "chasles/robot/error.h"
#include "chasles/server/convert.h"
#include "chasles/server/convert_multi.h"

namespace chasles {
namespace {

/// Binomial coefficient C(n, k) for the small n of trajectory pieces.
double Binomial(int n, int k) {
  double c = 1.0;
  for (int i = 1; i <= k; ++i) c = c * static_cast<double>(n - k + i) / static_cast<double>(i);
  return c;
}

/// The piece re-expanded about local time `tau0` and cut there: q(τ0 + s) = Σⱼ sʲ Σₖ≥ⱼ cₖ C(k, j) τ0^(k−j).
TimedTrajectory::Piece PieceFrom(const TimedTrajectory::Piece& piece, double tau0) {
  TimedTrajectory::Piece out;
  out.duration = std::max(0.0, piece.duration - tau0);
  const int columns = static_cast<int>(piece.coefficients.cols());
  out.coefficients = Eigen::MatrixXd::Zero(piece.coefficients.rows(), columns);
  for (int j = 0; j < columns; ++j) {
    for (int k = j; k < columns; ++k) {
      out.coefficients.col(j) += piece.coefficients.col(k) * Binomial(k, j) * std::pow(tau0, k - j);
    }
  }
  return out;
}

}  // namespace

google::protobuf::RepeatedPtrField<v1::MovingObstacle> ShiftedMovingObstacles(
    const google::protobuf::RepeatedPtrField<v1::MovingObstacle>& obstacles, double origin) {
  const std::vector<MovingObstacle> parsed = MovingObstaclesFromProto(obstacles);
  google::protobuf::RepeatedPtrField<v1::MovingObstacle> out;
  for (int i = 0; i < obstacles.size(); ++i) {
    v1::MovingObstacle* shifted = out.Add();
    *shifted = obstacles.Get(i);
    shifted->clear_waypoints();
    const MovingObstacle& obstacle = parsed[static_cast<std::size_t>(i)];
    v1::TimedPose* now = shifted->add_waypoints();
    now->set_time(0.0);
    PoseToProto(obstacle.PoseAt(origin), now->mutable_pose());
    for (const v1::TimedPose& waypoint : obstacles.Get(i).waypoints()) {
      if (waypoint.time() <= origin) continue;
      v1::TimedPose* later = shifted->add_waypoints();
      *later = waypoint;
      later->set_time(waypoint.time() - origin);
    }
  }
  return out;
}

TimedTrajectory BrakingTrajectory(const Eigen::VectorXd& q, const Eigen::VectorXd& v,
                                  const Eigen::VectorXd& max_acceleration) {
  if (v.size() != q.size() || max_acceleration.size() != q.size()) {
    ThrowInvalid("braking: " + std::to_string(q.size()) + " positions, " + std::to_string(v.size()) +
                 " velocities and " + std::to_string(max_acceleration.size()) + " acceleration limits");
  }
  double stop = 0.0;  // T [s]
  for (Eigen::Index i = 0; i < q.size(); ++i) {
    if (!std::isfinite(q[i]) || !std::isfinite(v[i])) ThrowInvalid("braking: joint " + std::to_string(i) + " is not finite");
    if (!(max_acceleration[i] > 0.0) || !std::isfinite(max_acceleration[i])) {
      ThrowInvalid("braking: max_acceleration[" + std::to_string(i) + "] = " + FormatNumber(max_acceleration[i]) +
                   " must be finite and > 0");
    }
    stop = std::max(stop, std::abs(v[i]) / max_acceleration[i]);
  }
  TimedTrajectory::Piece piece;
  piece.duration = stop;
  if (stop == 0.0) {
    piece.coefficients = q;
    return TimedTrajectory({piece}, q);
  }
  piece.coefficients.resize(q.size(), 3);
  piece.coefficients.col(0) = q;
  piece.coefficients.col(1) = v;
  piece.coefficients.col(2) = -0.5 * v / stop;
  return TimedTrajectory({piece}, q + 0.5 * stop * v);
}

TimedTrajectory TrajectoryFrom(const TimedTrajectory& trajectory, double from) {
  const Eigen::VectorXd last = trajectory.Evaluate(trajectory.duration()).q;
  std::vector<TimedTrajectory::Piece> pieces;
  double t = 0.0;
  for (const TimedTrajectory::Piece& piece : trajectory.pieces()) {
    if (piece.t0 + piece.duration <= from) continue;  // over by then
    TimedTrajectory::Piece cut = from > piece.t0 ? PieceFrom(piece, from - piece.t0) : piece;
    cut.t0 = t;
    t += cut.duration;
    pieces.push_back(std::move(cut));
  }
  if (pieces.empty()) {  // from at or past the end: standing there
    TimedTrajectory::Piece stand;
    stand.coefficients = last;
    pieces.push_back(std::move(stand));
  }
  return TimedTrajectory(std::move(pieces), last);
}

TimedTrajectory Concatenated(const TimedTrajectory& first, const TimedTrajectory& second) {
  std::vector<TimedTrajectory::Piece> pieces;
  double t = 0.0;
  for (const TimedTrajectory* part : {&first, &second}) {
    for (TimedTrajectory::Piece piece : part->pieces()) {
      if (piece.duration == 0.0) continue;  // a stand of no time adds nothing
      piece.t0 = t;
      t += piece.duration;
      pieces.push_back(std::move(piece));
    }
  }
  if (pieces.empty()) return second;
  return TimedTrajectory(std::move(pieces), second.Evaluate(second.duration()).q);
}

std::string FindTrajectoryCollision(const CollisionChecker& checker, const TimedTrajectory& trajectory, double from,
                                    double max_step) {
  double speed = 0.0;  // [rad/s] bound on any joint's speed
  for (const TimedTrajectory::Piece& piece : trajectory.pieces()) {
    if (piece.duration > 0.0) speed = std::max(speed, piece.MaxJointTravel() / piece.duration);
  }
  const double end = trajectory.duration();
  const double span = std::max(0.0, end - from);
  const long steps = speed > 0.0 ? std::max(1L, static_cast<long>(std::ceil(span * speed / max_step))) : 1L;
  const auto describe = [&](double t) {
    const CollisionResult contact = checker.Check(trajectory.Evaluate(t).q);
    std::string text = "at t = " + FormatNumber(t) + " s";
    if (contact.in_collision) {
      text += " ('" + contact.link_a + "' " +
              (contact.violation.empty() ? "touches '" + contact.other + "'" + VoxelText(contact) : contact.violation) + ")";
    }
    return text;
  };
  Eigen::VectorXd previous = trajectory.Evaluate(from).q;
  if (!checker.IsValid(previous)) return describe(from);
  for (long i = 1; i <= steps; ++i) {
    const double t = from + span * static_cast<double>(i) / static_cast<double>(steps);
    const Eigen::VectorXd q = trajectory.Evaluate(t).q;
    if (!checker.IsMotionFree(previous, q, max_step)) {
      // The first colliding state of the step, on a finer grid.
      const double t0 = from + span * static_cast<double>(i - 1) / static_cast<double>(steps);
      for (int k = 1; k <= 16; ++k) {
        const double tk = t0 + (t - t0) * k / 16.0;
        if (!checker.IsValid(trajectory.Evaluate(tk).q)) return describe(tk);
      }
      return describe(t);
    }
    previous = q;
  }
  return "";
}

}  // namespace chasles
