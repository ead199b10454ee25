#include "chasles/pipeline/cartesian_path.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "chasles/robot/error.h"
#include "chasles/robot/inverse_kinematics.h"
#include "chasles/robot/lie_group.h"
#include "field_checks.h"

namespace chasles {
namespace {

using detail::CheckOpenRange;
using detail::CheckRange;

/// Rotation angle between two rotation matrices [rad].
double AngleBetween(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) { return LogSO3(a.transpose() * b).norm(); }

constexpr double kTwoPi = 6.283185307179586;
// Points of each step at which the link's pose is compared with the commanded line.
constexpr int kDeviationPoints = 7;
// Halvings of a step whose link strays from the line (a step ends up at least 1/256 long).
constexpr int kMaxLineSplits = 8;

}  // namespace

const char* ToString(CartesianStop stop) {
  switch (stop) {
    case CartesianStop::kComplete: return "COMPLETE";
    case CartesianStop::kStartInvalid: return "START_INVALID";
    case CartesianStop::kUnreachable: return "UNREACHABLE";
    case CartesianStop::kJointJump: return "JOINT_JUMP";
    case CartesianStop::kRelativeJump: return "RELATIVE_JUMP";
    case CartesianStop::kCollision: return "COLLISION";
    case CartesianStop::kCancelled: return "CANCELLED";
  }
  return "UNKNOWN";
}

void CartesianSpec::Validate(const RobotModel& robot) const {
  if (link < 0 || link >= robot.num_links()) {
    ThrowInvalid("link = " + std::to_string(link) + " is not a link of robot '" + robot.name() + "'");
  }
  if (waypoints.empty()) ThrowInvalid("waypoints: a Cartesian move needs at least one waypoint");
  if (waypoints.size() > 10000) {
    ThrowInvalid("waypoints: " + std::to_string(waypoints.size()) + " waypoints; at most 10000");
  }
  for (std::size_t i = 0; i < waypoints.size(); ++i) {
    const Eigen::Matrix4d& m = waypoints[i].matrix();
    if (!m.allFinite()) ThrowInvalid("waypoints[" + std::to_string(i) + "] must be finite");
    const Eigen::Matrix3d r = waypoints[i].linear();
    if (!(((r.transpose() * r) - Eigen::Matrix3d::Identity()).norm() < 1e-6) || !(r.determinant() > 0.0)) {
      ThrowInvalid("waypoints[" + std::to_string(i) + "].orientation must be a rotation (a unit quaternion)");
    }
  }
  CheckRange(max_step, 1e-4, 0.5, "max_step");
  CheckRange(max_rotation_step, 1e-3, 1.0, "max_rotation_step");
  CheckOpenRange(max_joint_jump, kTwoPi, "max_joint_jump");
  if (!(jump_threshold == 0.0 || (jump_threshold >= 1.0 && std::isfinite(jump_threshold)))) {
    ThrowInvalid("jump_threshold = " + FormatNumber(jump_threshold) + " must be 0 (off) or a finite value >= 1");
  }
  CheckRange(line_tolerance, 1e-5, 0.1, "line_tolerance");
  CheckOpenRange(position_tolerance, 0.01, "position_tolerance");
  CheckOpenRange(orientation_tolerance, 0.1, "orientation_tolerance");
  CheckRange(collision_resolution, 1e-4, 0.1, "collision_resolution");
}

Eigen::Isometry3d InterpolatePose(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b, double u) {
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.translation() = a.translation() + u * (b.translation() - a.translation());
  out.linear() = a.linear() * ExpSO3(u * LogSO3(a.linear().transpose() * b.linear()));
  return out;
}

CartesianPathResult ComputeCartesianPath(const CollisionChecker& checker, const Eigen::VectorXd& start,
                                         const CartesianSpec& spec, const std::function<bool()>& stop) {
  const RobotModel& robot = checker.robot();
  spec.Validate(robot);
  robot.ValidateConfiguration(start, "start.positions");
  CartesianPathResult out;
  std::vector<Eigen::Isometry3d> poses;
  const auto link_pose = [&](const Eigen::VectorXd& q) {
    robot.ForwardKinematics(q, &poses);
    return poses[static_cast<std::size_t>(spec.link)];
  };

  // The segments: from the start's link pose through each waypoint, each cut into steps no longer
  // than max_step in translation and max_rotation_step in rotation.
  std::vector<Eigen::Isometry3d> from;
  std::vector<int> steps;
  Eigen::Isometry3d previous = link_pose(start);
  for (const Eigen::Isometry3d& w : spec.waypoints) {
    const double length = (w.translation() - previous.translation()).norm();
    const double angle = AngleBetween(previous.linear(), w.linear());
    const int n = std::max({1, static_cast<int>(std::ceil(length / spec.max_step)),
                            static_cast<int>(std::ceil(angle / spec.max_rotation_step))});
    from.push_back(previous);
    steps.push_back(n);
    out.steps += n;
    previous = w;
  }
  out.path.push_back(start);
  if (spec.check_collisions && !checker.IsValid(start)) {
    const CollisionResult contact = checker.Check(start);
    out.stop = CartesianStop::kStartInvalid;
    out.message = "the start collides ('" + contact.link_a + "' / '" + contact.other + "')";
    return out;
  }

  IkRequest ik;
  ik.link = spec.link;
  ik.position_tolerance = spec.position_tolerance;
  ik.orientation_tolerance = spec.orientation_tolerance;
  ik.max_attempts = 1;  // from the previous state only: the path stays on its branch
  ik.max_iterations = 200;
  ik.time_budget = 1.0;
  ik.stop = stop;
  const auto where = [&](std::size_t i, int k) {
    return "waypoints[" + std::to_string(i) + "], step " + std::to_string(k) + " of " + std::to_string(steps[i]);
  };
  const auto end = [&](CartesianStop why, std::string message) {
    out.stop = why;
    out.message = std::move(message);
  };
  // One step from the last state to target `b` (the line from `a`): solved, tested for a jump,
  // split at its middle pose while the link strays more than line_tolerance from the line between
  // the states (up to kMaxLineSplits times), then checked for collisions. False ends the path.
  std::vector<int> steps_at{0};  // per state: whole steps achieved when it is reached
  const std::function<bool(const Eigen::Isometry3d&, const Eigen::Isometry3d&, int, const std::string&)> go =
      [&](const Eigen::Isometry3d& a, const Eigen::Isometry3d& b, int depth, const std::string& at) {
        const Eigen::VectorXd q = out.path.back();
        ik.target = b;
        ik.initial_guess = q;
        const IkResult solved = SolveIk(robot, ik);
        if (solved.solutions.empty()) {
          end(CartesianStop::kUnreachable, at + ": no inverse-kinematics solution near the previous state (best " +
                                               FormatNumber(solved.best_position_error) + " m, " +
                                               FormatNumber(solved.best_orientation_error) + " rad from the pose)");
          return false;
        }
        const Eigen::VectorXd next = solved.solutions.front();
        Eigen::Index joint = 0;
        const double jump = (next - q).cwiseAbs().maxCoeff(&joint);
        if (jump > spec.max_joint_jump) {
          end(CartesianStop::kJointJump, at + ": joint '" + robot.dof_names()[static_cast<std::size_t>(joint)] +
                                             "' would move " + FormatNumber(jump) + " rad in one step (max_joint_jump " +
                                             FormatNumber(spec.max_joint_jump) + ")");
          return false;
        }
        // The link between the states (joints moving linearly) against the line.
        double stray = 0.0, turn = 0.0;
        for (int p = 1; p <= kDeviationPoints; ++p) {
          const double u = static_cast<double>(p) / (kDeviationPoints + 1);
          const Eigen::Isometry3d x = link_pose(q + u * (next - q));
          const Eigen::Isometry3d line = InterpolatePose(a, b, u);
          stray = std::max(stray, (x.translation() - line.translation()).norm());
          turn = std::max(turn, AngleBetween(x.linear(), line.linear()));
        }
        if (stray > spec.line_tolerance && depth < kMaxLineSplits) {
          const Eigen::Isometry3d middle = InterpolatePose(a, b, 0.5);
          if (!go(a, middle, depth + 1, at)) return false;
          steps_at.back() = steps_at.size() > 1 ? steps_at[steps_at.size() - 2] : 0;  // a part of a step
          return go(middle, b, depth + 1, at);
        }
        if (spec.check_collisions) {
          const bool free = checker.IsMotionFree(q, next, spec.collision_resolution);
          if (!free) {
            const CollisionResult contact = checker.Check(next);
            end(CartesianStop::kCollision,
                at + ": the motion collides" +
                    (contact.in_collision ? " ('" + contact.link_a + "' / '" + contact.other + "' at the step's end)" : ""));
            return false;
          }
        }
        const Eigen::Isometry3d reached = link_pose(next);
        out.max_position_error = std::max(out.max_position_error, (reached.translation() - b.translation()).norm());
        out.max_orientation_error = std::max(out.max_orientation_error, AngleBetween(reached.linear(), b.linear()));
        out.max_line_deviation = std::max(out.max_line_deviation, stray);
        out.max_line_rotation_deviation = std::max(out.max_line_rotation_deviation, turn);
        out.path.push_back(next);
        steps_at.push_back(steps_at.back() + 1);
        return true;
      };
  int done = 0;
  for (std::size_t i = 0; i < spec.waypoints.size() && out.stop == CartesianStop::kComplete; ++i) {
    Eigen::Isometry3d a = from[i];
    for (int k = 1; k <= steps[i]; ++k) {
      if (stop && stop()) {
        end(CartesianStop::kCancelled, "cancelled at " + where(i, k));
        break;
      }
      const Eigen::Isometry3d b =
          k == steps[i] ? spec.waypoints[i] : InterpolatePose(from[i], spec.waypoints[i], static_cast<double>(k) / steps[i]);
      if (!go(a, b, 0, where(i, k))) break;
      ++done;
      a = b;
    }
    if (out.stop == CartesianStop::kComplete) out.waypoints_reached = static_cast<int>(i) + 1;
  }
  // MoveIt's relative jump test over the steps achieved.
  if (spec.jump_threshold > 0.0 && out.path.size() > 1) {
    double mean = 0.0;
    for (std::size_t s = 1; s < out.path.size(); ++s) mean += (out.path[s] - out.path[s - 1]).norm();
    mean /= static_cast<double>(out.path.size() - 1);
    for (std::size_t s = 1; s < out.path.size(); ++s) {
      const double d = (out.path[s] - out.path[s - 1]).norm();
      if (d > spec.jump_threshold * mean) {
        end(CartesianStop::kRelativeJump, "step " + std::to_string(s) + " moves the joints " + FormatNumber(d) +
                                              " rad, more than jump_threshold " + FormatNumber(spec.jump_threshold) +
                                              " × the mean step " + FormatNumber(mean));
        out.path.resize(s);
        done = steps_at[s - 1];
        // Waypoints reached: those whose last step is still in the path.
        int reached = 0, counted = 0;
        for (std::size_t w = 0; w < steps.size(); ++w) {
          counted += steps[w];
          if (counted <= done) reached = static_cast<int>(w) + 1;
        }
        out.waypoints_reached = reached;
        break;
      }
    }
  }
  out.fraction = out.steps > 0 ? static_cast<double>(done) / out.steps : 1.0;
  return out;
}

double TrajectoryLineDeviation(const RobotModel& robot, const CartesianSpec& spec, const Eigen::VectorXd& start,
                               const TimedTrajectory& trajectory) {
  std::vector<Eigen::Isometry3d> poses;
  robot.ForwardKinematics(start, &poses);
  std::vector<Eigen::Vector3d> corners{poses[static_cast<std::size_t>(spec.link)].translation()};
  for (const Eigen::Isometry3d& w : spec.waypoints) corners.push_back(w.translation());
  const auto distance = [&](const Eigen::Vector3d& p) {
    double nearest = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i + 1 < corners.size(); ++i) {
      const Eigen::Vector3d d = corners[i + 1] - corners[i];
      const double length2 = d.squaredNorm();
      const double u = length2 > 0.0 ? std::clamp((p - corners[i]).dot(d) / length2, 0.0, 1.0) : 0.0;
      nearest = std::min(nearest, (p - (corners[i] + u * d)).norm());
    }
    return nearest;  // spec.waypoints is not empty: at least one segment
  };
  const double duration = trajectory.duration();
  const long n = std::clamp(static_cast<long>(std::ceil(duration / 0.001)), 1L, 100000L);
  double out = 0.0;
  for (long i = 0; i <= n; ++i) {
    robot.ForwardKinematics(trajectory.Evaluate(duration * static_cast<double>(i) / n).q, &poses);
    out = std::max(out, distance(poses[static_cast<std::size_t>(spec.link)].translation()));
  }
  return out;
}

}  // namespace chasles
