#include "chasles/multi/team.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <unordered_map>
#include <unordered_set>
#include <utility>

#include "chasles/collision/proximity.h"
#include "chasles/optimizers/verification.h"
#include "chasles/robot/error.h"

namespace chasles {
namespace {

std::string RobotLabel(std::size_t k, const std::string& name) {
  return "robots[" + std::to_string(k) + "] '" + name + "'";
}

/// The fixed transform a moving joint contributes at configuration value q, with the same
/// convention as RobotModel's FK: child = parent · origin · motion(axis, q).
Eigen::Isometry3d FrozenOrigin(const Joint& joint, double q) {
  Eigen::Isometry3d motion = Eigen::Isometry3d::Identity();
  switch (joint.type) {
    case JointType::kRevolute:
    case JointType::kContinuous:
      motion.linear() = Eigen::AngleAxisd(q, joint.axis).toRotationMatrix();
      break;
    case JointType::kPrismatic:
      motion.translation() = joint.axis * q;
      break;
    case JointType::kFixed:
      break;
  }
  Eigen::Isometry3d origin = joint.origin * motion;
  origin.makeAffine();
  return origin;
}

/// A name for the joint that fixes robot `prefix` to the world: "<prefix>/base", or with a
/// numeric suffix when the robot has a joint called "base" (or "base_2", …) of its own.
std::string BaseJointName(const RobotModel& model, const std::string& prefix) {
  std::unordered_set<std::string> taken;
  for (const Joint& joint : model.joints()) taken.insert(joint.name);
  std::string name = "base";
  for (int suffix = 2; taken.count(name) != 0; ++suffix) name = "base_" + std::to_string(suffix);
  return prefix + "/" + name;
}

void ValidatePlacements(const std::vector<PlacedRobot>& robots) {
  if (robots.empty()) ThrowInvalid("robots is empty: a team needs at least one robot");
  std::unordered_map<std::string, std::size_t> seen;
  for (std::size_t k = 0; k < robots.size(); ++k) {
    const PlacedRobot& robot = robots[k];
    if (robot.name.empty()) {
      ThrowInvalid("robots[" + std::to_string(k) + "].name is empty; every robot needs a name (its link and joint prefix)");
    }
    const auto [it, fresh] = seen.emplace(robot.name, k);
    if (!fresh) {
      ThrowInvalid("robots[" + std::to_string(k) + "].name = '" + robot.name + "' is used by robots[" +
                   std::to_string(it->second) + "] too; robot names must be unique");
    }
    const std::string label = RobotLabel(k, robot.name);
    if (robot.model == nullptr) ThrowInvalid(label + ": model is null");
    const Eigen::Isometry3d& pose = robot.base_pose;
    if (!pose.matrix().allFinite()) ThrowInvalid(label + ": base_pose must be finite");
    const Eigen::Matrix3d r = pose.linear();
    const double error = (r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
    if (!(error <= 1e-6) || !(r.determinant() > 0.0)) {
      ThrowInvalid(label + ": base_pose rotation must be a rotation matrix (orthonormal to 1e-6, determinant +1); |RᵀR − I| = " +
                   FormatNumber(error) + ", det R = " + FormatNumber(r.determinant()));
    }
    if (robot.frozen_at.size() != 0) robot.model->ValidateConfiguration(robot.frozen_at, label + " frozen_at");
  }
}

/// Motion model of the composite: the movable robot's when there is one, kArm for several.
MotionModel CompositeMotion(const std::vector<PlacedRobot>& robots) {
  std::vector<std::size_t> movable;
  for (std::size_t k = 0; k < robots.size(); ++k) {
    if (robots[k].frozen_at.size() == 0) movable.push_back(k);
  }
  if (movable.size() == 1) return robots[movable.front()].model->motion();
  if (movable.size() > 1) {
    for (std::size_t k : movable) {
      const RobotKind kind = robots[k].model->kind();
      if (IsCar(kind)) {
        throw Error(ErrorCode::kFailedPrecondition,
                    RobotLabel(k, robots[k].name) + " is a " + ToString(kind) + " and " + std::to_string(movable.size()) +
                        " robots are movable: a composite of several movable robots has no car motions "
                        "(freeze the others, or plan the car on its own)");
      }
    }
  }
  return MotionModel{};
}

}  // namespace

std::shared_ptr<const RobotModel> ComposeRobots(const std::vector<PlacedRobot>& robots, const CompositionOptions& options) {
  ValidatePlacements(robots);
  const MotionModel motion = CompositeMotion(robots);

  std::vector<Link> links;
  std::vector<Joint> joints;
  std::vector<std::pair<std::string, std::string>> allowed;
  links.emplace_back();
  links.back().name = "world";

  for (const PlacedRobot& robot : robots) {
    const RobotModel& model = *robot.model;
    const std::string prefix = robot.name + "/";
    const int first_link = static_cast<int>(links.size());
    const bool frozen = robot.frozen_at.size() != 0;

    for (const Link& link : model.links()) {
      links.push_back(link);
      links.back().name = prefix + link.name;
      links.back().parent_joint = -1;  // FromTree recomputes it
    }

    Joint base;
    base.name = BaseJointName(model, robot.name);
    base.type = JointType::kFixed;
    base.parent_link = 0;
    base.child_link = first_link + model.root_link();
    base.origin = Eigen::Isometry3d::Identity();
    base.origin.linear() = robot.base_pose.linear();
    base.origin.translation() = robot.base_pose.translation();
    joints.push_back(base);

    // The robot's joints keep their (topological) order, so the composite's configuration is
    // the movable robots' configurations concatenated. A mimic joint keeps following its joint
    // (index shifted); frozen, it is fixed at its value like the rest.
    const int first_joint = static_cast<int>(joints.size());
    for (const Joint& joint : model.joints()) {
      Joint copy = joint;
      copy.name = prefix + joint.name;
      copy.parent_link = first_link + joint.parent_link;
      copy.child_link = first_link + joint.child_link;
      if (frozen && joint.type != JointType::kFixed) {
        copy.origin = FrozenOrigin(joint, joint.Position(robot.frozen_at));
        copy.type = JointType::kFixed;
        copy.mimic.reset();
      }
      if (copy.mimic) copy.mimic->joint += first_joint;
      copy.dof = -1;
      joints.push_back(std::move(copy));
    }

    const AllowedCollisionMatrix& acm = model.allowed_collisions();
    for (int a = 0; a < model.num_links(); ++a) {
      allowed.emplace_back("world", links[first_link + a].name);
      for (int b = a + 1; b < model.num_links(); ++b) {
        if (!options.self_collisions || acm.IsAllowed(a, b)) {
          allowed.emplace_back(links[first_link + a].name, links[first_link + b].name);
        }
      }
    }
  }
  return RobotModel::FromTree("team", std::move(links), std::move(joints), allowed, motion);
}

std::vector<int> CompositeOffsets(const std::vector<PlacedRobot>& robots) {
  std::vector<int> offsets;
  offsets.reserve(robots.size() + 1);
  int offset = 0;
  for (std::size_t k = 0; k < robots.size(); ++k) {
    offsets.push_back(offset);
    if (robots[k].frozen_at.size() != 0) continue;
    if (robots[k].model == nullptr) ThrowInvalid(RobotLabel(k, robots[k].name) + ": model is null");
    offset += robots[k].model->num_dofs();
  }
  offsets.push_back(offset);
  return offsets;
}

TimedTrajectory ComposeTrajectories(const std::vector<TimedTrajectory>& trajectories) {
  if (trajectories.empty()) ThrowInvalid("trajectories is empty: a team needs at least one trajectory");
  double end = 0.0;
  int degree = 0;
  for (std::size_t k = 0; k < trajectories.size(); ++k) {
    const TimedTrajectory& trajectory = trajectories[k];
    if (trajectory.empty()) ThrowInvalid("trajectories[" + std::to_string(k) + "] is empty");
    end = std::max(end, trajectory.duration());
    degree = std::max(degree, trajectory.degree());
  }

  // Every trajectory on [0, end]: one that ends earlier holds its end position.
  std::vector<TimedTrajectory> parts;
  parts.reserve(trajectories.size());
  Eigen::Index rows = 0;
  for (const TimedTrajectory& trajectory : trajectories) {
    const double duration = trajectory.duration();
    if (duration < end) {
      parts.push_back(ConcatenateTrajectories({trajectory, HoldTrajectory(trajectory.Evaluate(duration).q, end - duration)}));
    } else {
      parts.push_back(trajectory);
    }
    rows += trajectory.num_dofs();
  }

  // The union of the piece boundaries; boundaries closer than the tolerance are one.
  const double merge = 1e-12 * std::max(1.0, end);
  std::vector<double> times;
  for (const TimedTrajectory& part : parts) {
    for (const TimedTrajectory::Piece& piece : part.pieces()) times.push_back(piece.t0);
  }
  std::sort(times.begin(), times.end());
  std::vector<double> bounds{0.0};
  for (double t : times) {
    if (t - bounds.back() > merge && end - t > merge) bounds.push_back(t);
  }
  bounds.push_back(end);  // all trajectories last 0 s: one piece of 0 s

  // Each interval: every trajectory's polynomial re-expanded about the interval's start
  // (Taylor shift: c'_k = p⁽ᵏ⁾(s) / k!), padded to the highest degree.
  std::vector<TimedTrajectory::Piece> pieces(bounds.size() - 1);
  std::vector<std::size_t> cursor(parts.size(), 0);
  for (std::size_t j = 0; j + 1 < bounds.size(); ++j) {
    TimedTrajectory::Piece& piece = pieces[j];
    piece.t0 = bounds[j];
    piece.duration = bounds[j + 1] - bounds[j];
    piece.coefficients = Eigen::MatrixXd::Zero(rows, degree + 1);
    const double middle = 0.5 * (bounds[j] + bounds[j + 1]);
    Eigen::Index row = 0;
    for (std::size_t k = 0; k < parts.size(); ++k) {
      const std::vector<TimedTrajectory::Piece>& own = parts[k].pieces();
      std::size_t& c = cursor[k];
      while (c + 1 < own.size() && own[c + 1].t0 <= middle) ++c;
      const TimedTrajectory::Piece& source = own[c];
      const double shift = bounds[j] - source.t0;
      const int size = static_cast<int>(source.coefficients.cols());
      if (shift == 0.0) {
        piece.coefficients.block(row, 0, source.coefficients.rows(), size) = source.coefficients;
      } else {
        for (Eigen::Index i = 0; i < source.coefficients.rows(); ++i) {
          const Eigen::VectorXd p = source.coefficients.row(i).transpose();
          double factorial = 1.0;
          for (int order = 0; order < size; ++order) {
            if (order > 1) factorial *= static_cast<double>(order);
            piece.coefficients(row + i, order) = poly::EvalDerivative(p.data(), size, order, shift) / factorial;
          }
        }
      }
      row += source.coefficients.rows();
    }
  }

  Eigen::VectorXd end_position(rows);
  Eigen::Index row = 0;
  for (const TimedTrajectory& trajectory : trajectories) {
    end_position.segment(row, trajectory.num_dofs()) = trajectory.Evaluate(trajectory.duration()).q;
    row += trajectory.num_dofs();
  }
  return TimedTrajectory(std::move(pieces), std::move(end_position));
}

KinematicLimits ComposeLimits(const std::vector<KinematicLimits>& limits) {
  if (limits.empty()) ThrowInvalid("limits is empty: a team needs at least one robot's limits");
  Eigen::Index rows = 0;
  for (std::size_t k = 0; k < limits.size(); ++k) {
    const KinematicLimits& own = limits[k];
    const std::string label = "limits[" + std::to_string(k) + "]";
    if (own.max_jerk.size() != 0) {
      ThrowInvalid(label + ".max_jerk has " + std::to_string(own.max_jerk.size()) +
                   " values; coordination supports no jerk limits (leave it empty)");
    }
    if (own.max_effort.size() != 0) {
      ThrowInvalid(label + ".max_effort has " + std::to_string(own.max_effort.size()) +
                   " values; coordination supports no effort limits (leave it empty)");
    }
    if (own.max_acceleration.size() != own.max_velocity.size()) {
      ThrowInvalid(label + ".max_acceleration has " + std::to_string(own.max_acceleration.size()) +
                   " values, max_velocity " + std::to_string(own.max_velocity.size()) + "; they must match");
    }
    rows += own.max_velocity.size();
  }
  KinematicLimits out;
  out.gravity = limits.front().gravity;
  out.max_velocity.resize(rows);
  out.max_acceleration.resize(rows);
  Eigen::Index row = 0;
  for (const KinematicLimits& own : limits) {
    const Eigen::Index n = own.max_velocity.size();
    out.max_velocity.segment(row, n) = own.max_velocity;
    out.max_acceleration.segment(row, n) = own.max_acceleration;
    row += n;
  }
  return out;
}

namespace {

/// The smallest distance between two robots of the team composite (links grouped by their
/// "<name>/" prefix) at instants distance_period apart (fewer on long motions), capped.
double MinRobotDistance(const CollisionChecker& team_checker, const std::vector<TimedTrajectory>& trajectories,
                        const TeamVerificationOptions& options) {
  const RobotModel& team = team_checker.robot();
  std::map<std::string, std::vector<int>> by_robot;
  for (int l = 0; l < team.num_links(); ++l) {
    const std::string& name = team.links()[l].name;
    const std::size_t slash = name.find('/');
    if (slash != std::string::npos) by_robot[name.substr(0, slash)].push_back(l);
  }
  if (by_robot.size() < 2) return kMaxReportedRobotDistance;
  std::vector<std::vector<int>> groups;
  for (auto& [name, links] : by_robot) groups.push_back(std::move(links));
  const LinkGroupDistance distance(team_checker.robot_ptr(), std::move(groups));
  const TimedTrajectory motion = ComposeTrajectories(trajectories);
  const double duration = motion.duration();
  const int instants = std::max(
      1, std::min(std::max(1, options.max_distance_instants),
                  static_cast<int>(std::ceil(duration / std::max(options.distance_period, 1e-9)))));
  double best = kMaxReportedRobotDistance;
  for (int k = 0; k <= instants && best > 0.0; ++k) {
    const double t = k == instants ? duration : duration * k / instants;
    best = std::min(best, distance.Min(motion.Evaluate(t).q, best));
  }
  return best;
}

}  // namespace

TeamVerificationReport VerifyTeam(const CollisionChecker& team_checker, const std::vector<TimedTrajectory>& trajectories,
                                  const std::vector<Eigen::VectorXd>& starts, const std::vector<Eigen::VectorXd>& goals,
                                  const std::vector<KinematicLimits>& limits, const TeamVerificationOptions& options) {
  for (const auto& [field, value] : {std::pair<const char*, double>{"time_step", options.time_step},
                                     std::pair<const char*, double>{"max_joint_step", options.max_joint_step}}) {
    if (!std::isfinite(value) || !(value > 0.0)) {
      ThrowInvalid(std::string("options.") + field + " = " + FormatNumber(value) + " must be finite and > 0");
    }
  }
  if (trajectories.empty()) ThrowInvalid("trajectories is empty: a team needs at least one trajectory");
  const std::size_t n = trajectories.size();
  for (const auto& [field, size] : {std::pair<const char*, std::size_t>{"starts", starts.size()},
                                    std::pair<const char*, std::size_t>{"goals", goals.size()},
                                    std::pair<const char*, std::size_t>{"limits", limits.size()}}) {
    if (size != n) {
      ThrowInvalid(std::string(field) + " has " + std::to_string(size) + " entries, trajectories " + std::to_string(n) +
                   "; one per robot");
    }
  }

  TeamVerificationReport report;
  Eigen::Index rows = 0;
  for (std::size_t k = 0; k < n; ++k) {
    const std::string label = "[" + std::to_string(k) + "]";
    if (trajectories[k].empty()) {
      report.reason = "trajectories" + label + " is empty";
      return report;
    }
    const Eigen::Index dofs = trajectories[k].num_dofs();
    for (const auto& [field, size] : {std::pair<const char*, Eigen::Index>{"starts", starts[k].size()},
                                      std::pair<const char*, Eigen::Index>{"goals", goals[k].size()},
                                      std::pair<const char*, Eigen::Index>{"limits.max_velocity", limits[k].max_velocity.size()}}) {
      if (size != dofs) {
        ThrowInvalid(std::string(field) + label + " has " + std::to_string(size) + " values, trajectories" + label +
                     " has " + std::to_string(dofs) + " joints");
      }
    }
    rows += dofs;
  }
  const RobotModel& team = team_checker.robot();
  if (rows != team.num_dofs()) {
    ThrowInvalid("the trajectories have " + std::to_string(rows) + " joints in all, the team checker's robot '" +
                 team.name() + "' has " + std::to_string(team.num_dofs()));
  }

  Eigen::VectorXd start(rows), goal(rows);
  Eigen::Index row = 0;
  for (std::size_t k = 0; k < n; ++k) {
    const Eigen::Index dofs = trajectories[k].num_dofs();
    start.segment(row, dofs) = starts[k];
    goal.segment(row, dofs) = goals[k];
    row += dofs;
  }

  VerificationOptions verification;
  verification.max_joint_step = options.max_joint_step;
  verification.max_time_step = options.time_step;
  const VerificationReport own =
      VerifyTrajectory(ComposeTrajectories(trajectories), start, goal, team_checker, ComposeLimits(limits), verification);
  report.ok = own.ok;
  report.reason = own.reason;
  report.states_checked = static_cast<std::uint64_t>(std::max(0, own.states_checked));
  report.max_velocity_ratio = own.max_velocity_ratio;
  report.max_acceleration_ratio = own.max_acceleration_ratio;
  report.collision_guarantee = own.collision_guarantee;
  report.collision_guarantee_reason = own.collision_guarantee_reason;
  if (report.ok && options.measure_robot_distance) report.min_robot_distance = MinRobotDistance(team_checker, trajectories, options);
  return report;
}

}  // namespace chasles
