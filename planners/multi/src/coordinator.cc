#include "chasles/multi/coordinator.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <numeric>
#include <set>
#include <tuple>
#include <utility>

#include "chasles/multi/space_time.h"
#include "chasles/robot/error.h"
#include "chasles/robot/inverse_kinematics.h"
#include "fleet_method.h"

namespace chasles {

const char* ToString(CoordinationMethod method) {
  switch (method) {
    case CoordinationMethod::kAuto: return "auto";
    case CoordinationMethod::kPrioritized: return "prioritized";
    case CoordinationMethod::kComposite: return "composite";
    case CoordinationMethod::kVelocityTuning: return "velocity_tuning";
    case CoordinationMethod::kSequential: return "sequential";
    case CoordinationMethod::kFleet: return "fleet";
    case CoordinationMethod::kVelocityObstacles: return "velocity_obstacles";
  }
  return "?";
}

const char* ToString(CoordinationCode code) {
  switch (code) {
    case CoordinationCode::kSuccess: return "success";
    case CoordinationCode::kNoSolution: return "no_solution";
    case CoordinationCode::kStartInCollision: return "start_in_collision";
    case CoordinationCode::kGoalInCollision: return "goal_in_collision";
    case CoordinationCode::kGoalUnreachable: return "goal_unreachable";
    case CoordinationCode::kStartsInConflict: return "starts_in_conflict";
    case CoordinationCode::kGoalsInConflict: return "goals_in_conflict";
    case CoordinationCode::kVerificationFailed: return "verification_failed";
    case CoordinationCode::kCancelled: return "cancelled";
    case CoordinationCode::kDeadlineExceeded: return "deadline_exceeded";
  }
  return "?";
}

namespace {

using Clock = std::chrono::steady_clock;

double SecondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

/// Extra distance [m] around each robot in the pair checks of the search, which samples more
/// coarsely (SpaceTimeOptions: 0.01 s, 0.02 rad) than the final verification (1 ms, 0.005 rad):
/// with it, a route the search accepts passes the verification.
constexpr double kSearchMargin = 0.02;
/// Composite planning is offered up to this team size (OMPL over the product space).
constexpr int kCompositeMaxRobots = 3;
constexpr int kCompositeMaxDofs = 14;

void CheckRange(double value, double lo, double hi, const std::string& field) {
  if (!std::isfinite(value) || value < lo || value > hi) {
    ThrowInvalid(field + " = " + FormatNumber(value) + " must be within [" + FormatNumber(lo) + ", " +
                 FormatNumber(hi) + "]");
  }
}

/// ResolveLimits names `trajectory.max_velocity[i]`; in a team the field is `robots[k].max_velocity[i]`.
KinematicLimits ResolveRobotLimits(const TeamRobotSpec& robot, int index) {
  TrajectorySpec spec;
  spec.max_velocity = robot.max_velocity;
  spec.max_acceleration = robot.max_acceleration;
  try {
    return ResolveLimits(*robot.placement.model, spec);
  } catch (const Error& e) {
    std::string message = e.what();
    const std::string from = "trajectory.";
    const std::string to = "robots[" + std::to_string(index) + "].";
    for (std::size_t at = message.find(from); at != std::string::npos; at = message.find(from, at + to.size())) {
      message.replace(at, from.size(), to);
    }
    throw Error(e.code(), message);
  }
}

std::string Describe(const CollisionResult& contact) {
  return "'" + contact.link_a + "' touches '" + contact.other + "'" + VoxelText(contact);
}

Eigen::VectorXd Concat(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  Eigen::VectorXd q(a.size() + b.size());
  q << a, b;
  return q;
}

/// A bound on how fast any joint of the trajectory moves [rad/s] (0 when it stands still).
double MaxJointSpeed(const TimedTrajectory& trajectory) {
  double speed = 0.0;
  for (const TimedTrajectory::Piece& piece : trajectory.pieces()) {
    if (piece.duration > 0.0) speed = std::max(speed, piece.MaxJointTravel() / piece.duration);
  }
  return speed;
}

/// When the robot stops moving for good: the end of the last piece with any motion.
double MotionEnd(const TimedTrajectory& trajectory) {
  double end = 0.0;
  for (const TimedTrajectory::Piece& piece : trajectory.pieces()) {
    if (piece.coefficients.cols() > 1 && piece.coefficients.rightCols(piece.coefficients.cols() - 1).cwiseAbs().maxCoeff() > 1e-12) {
      end = piece.t0 + piece.duration;
    }
  }
  return end;
}

/// The trajectory up to `end` (whole pieces; the ones after only stand still).
TimedTrajectory TruncatedAt(const TimedTrajectory& trajectory, double end) {
  std::vector<TimedTrajectory::Piece> pieces;
  for (const TimedTrajectory::Piece& piece : trajectory.pieces()) {
    if (piece.t0 >= end - 1e-12 && !pieces.empty()) break;
    pieces.push_back(piece);
  }
  return TimedTrajectory(std::move(pieces), trajectory.Evaluate(trajectory.duration()).q);
}

/// Robot k resolved: limits, goal, its checker alone in the scene.
struct Member {
  int index = 0;
  PlacedRobot placement;
  Eigen::VectorXd start, goal;
  KinematicLimits limits;
  /// Alone in the scene (self + scene), built when first needed (Coordinator::Own): a fleet of
  /// hundreds checks its ends on one checker per model (EndsChecker) and needs no other.
  std::shared_ptr<const CollisionChecker> own;
};

/// What one method produced: per member, a trajectory from t = 0.
struct Attempt {
  bool ok = false;
  bool out_of_time = false;  ///< failed because its budget ran out
  std::string message;
  std::vector<TimedTrajectory> trajectories;
  std::vector<JointPath> paths;
  std::vector<double> start_delay, wait_time;
  std::vector<int> order;
  int reorderings = 0;
};

/// A method's result that passed verification.
struct Verified {
  Attempt attempt;
  TeamVerificationReport verification;
  CoordinationMethod method = CoordinationMethod::kAuto;
  double makespan = 0.0;  ///< [s]
};

/// Something that moves in the robots' world: a team member (once planned) or a committed motion.
struct Actor {
  const PlacedRobot* placement = nullptr;
  const TimedTrajectory* trajectory = nullptr;
  double begin = 0.0;
  double until = std::numeric_limits<double>::infinity();
  /// The actor's configuration at time t, or false when it is absent then.
  bool StateAt(double t, Eigen::VectorXd* q) const {
    if (t < begin - 1e-12 || t > until + 1e-12) return false;
    *q = trajectory->Evaluate(t - begin).q;
    return true;
  }
};

class Coordinator {
 public:
  Coordinator(const CoordinationQuery& query, const PlannerRegistry& registry, const Termination& termination)
      : query_(query), registry_(registry), pipeline_(registry), termination_(termination) {}

  CoordinationOutcome Run();

 private:
  // --- checkers -------------------------------------------------------------------------------
  /// All members, self + scene, built when first needed (FLEET never needs it).
  const std::shared_ptr<const CollisionChecker>& Team() {
    if (!team_) {
      std::vector<PlacedRobot> placements;
      for (const Member& m : members_) placements.push_back(m.placement);
      team_ = std::make_shared<CollisionChecker>(ComposeRobots(placements), SceneFor(placements));
    }
    return team_;
  }
  /// Robot k alone in the scene (self + scene), built on first use.
  std::shared_ptr<const CollisionChecker> Own(int k) { return Own(&members_[static_cast<std::size_t>(k)]); }
  std::shared_ptr<const CollisionChecker> Own(Member* m) {
    if (!m->own) m->own = std::make_shared<CollisionChecker>(ComposeRobots({m->placement}), SceneFor({m->placement}));
    return m->own;
  }
  /// A checker for a member's start and goal: one per model for robots whose base frame is the
  /// scene frame when the scene allows no pairs (the same checks as Own's, link names without
  /// the robot's prefix: messages name the robot themselves); else Own.
  const CollisionChecker& EndsChecker(Member* m) {
    if (!m->placement.base_pose.matrix().isIdentity(0.0) || !query_.scene->allowed_collisions().empty()) {
      return *Own(m);
    }
    std::shared_ptr<const CollisionChecker>& shared = ends_[m->placement.model.get()];
    if (!shared) shared = std::make_shared<CollisionChecker>(m->placement.model, query_.scene);
    return *shared;
  }

  /// A sphere (world centre, radius) that holds every collision shape of the robot at q.
  static std::pair<Eigen::Vector3d, double> BoundingSphere(const PlacedRobot& robot, const Eigen::VectorXd& q) {
    std::vector<Eigen::Isometry3d> poses;
    robot.model->ForwardKinematics(q, &poses);
    std::vector<std::pair<Eigen::Vector3d, double>> balls;  // per shape, world
    for (int l = 0; l < robot.model->num_links(); ++l) {
      for (const Shape& shape : robot.model->links()[l].collision) {
        balls.emplace_back(robot.base_pose * (poses[l] * shape.pose).translation(), BoundingRadius(shape));
      }
    }
    if (balls.empty()) return {robot.base_pose.translation(), 0.0};
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    for (const auto& [c, r] : balls) centre += c;
    centre /= static_cast<double>(balls.size());
    double radius = 0.0;
    for (const auto& [c, r] : balls) radius = std::max(radius, (c - centre).norm() + r);
    return {centre, radius};
  }

  /// Robot a (first) against b, nothing else: the pair composite without self checks over an
  /// empty scene; `padding` around both robots.
  const CollisionChecker& Pair(const PlacedRobot& a, const PlacedRobot& b, double padding) {
    const auto key = std::make_tuple(a.name, b.name, padding);
    auto it = pairs_.find(key);
    if (it == pairs_.end()) {
      PlacedRobot pa = a, pb = b;
      pa.frozen_at.resize(0);
      pb.frozen_at.resize(0);
      CompositionOptions options;
      options.self_collisions = false;
      CollisionOptions collision;
      collision.padding = padding;
      auto checker = std::make_shared<CollisionChecker>(ComposeRobots({pa, pb}, options),
                                                        std::make_shared<Scene>(), collision);
      it = pairs_.emplace(key, std::move(checker)).first;
    }
    return *it->second;
  }
  double SearchPadding() const { return 0.5 * query_.robot_padding + kSearchMargin; }
  double ExactPadding() const { return 0.5 * query_.robot_padding; }

  /// The query's scene for a composition of `robots`: its allowed pairs (named by the robots'
  /// own links) renamed to the composite's links, "<robot>/<link>", once per robot that has the
  /// link; pairs of links none of them has are left out.
  std::shared_ptr<const Scene> SceneFor(const std::vector<PlacedRobot>& robots) const {
    const Scene& scene = *query_.scene;
    if (scene.allowed_collisions().empty()) return query_.scene;
    auto renamed = std::make_shared<Scene>();
    for (const SceneObject& object : scene.objects()) renamed->AddObject(object);
    for (const OccupancyMap& map : scene.occupancy_maps()) renamed->AddOccupancyMap(map);
    for (const AllowedCollision& pair : scene.allowed_collisions()) {
      for (const PlacedRobot& robot : robots) {
        if (robot.model->FindLink(pair.link) < 0) continue;
        const bool link_pair = robot.model->FindLink(pair.other) >= 0;
        renamed->AllowCollision(robot.name + "/" + pair.link, link_pair ? robot.name + "/" + pair.other : pair.other);
      }
    }
    return renamed;
  }

  /// Robot k alone, the listed other members standing at fixed configurations.
  std::shared_ptr<const CollisionChecker> WithFrozen(int k, const std::vector<std::pair<int, Eigen::VectorXd>>& frozen) {
    std::vector<PlacedRobot> robots{members_[k].placement};
    for (const auto& [j, q] : frozen) {
      robots.push_back(members_[j].placement);
      robots.back().frozen_at = q;
    }
    return std::make_shared<CollisionChecker>(ComposeRobots(robots), SceneFor(robots));
  }

  // --- single-robot planning ------------------------------------------------------------------
  struct SinglePlan {
    bool ok = false;
    bool out_of_time = false;  ///< failed because its budget ran out (not proof that none exists)
    std::string message;
    JointPath path;
    TimedTrajectory trajectory;
  };
  SinglePlan PlanSingle(int k, std::shared_ptr<const CollisionChecker> checker, const Termination& termination,
                        std::uint64_t seed_offset) {
    const Member& m = members_[k];
    SinglePlan result;
    if ((m.goal - m.start).cwiseAbs().maxCoeff() <= 1e-9) {
      result.ok = true;
      result.path = {m.start};
      result.trajectory = HoldTrajectory(m.start, 0.0);
      return result;
    }
    PlanQuery plan;
    plan.checker = std::move(checker);
    plan.start = m.start;
    plan.goal = m.goal;
    plan.goal_tolerance = 1e-6;
    plan.planner_id = query_.planner_id;
    plan.parameters = query_.parameters;
    plan.seed = query_.seed + 7919 * static_cast<std::uint64_t>(k) + seed_offset;
    plan.collision_resolution = query_.collision_resolution;
    plan.trajectory.method = PostProcessing::kTimeOptimal;
    plan.trajectory.max_velocity = m.limits.max_velocity;
    plan.trajectory.max_acceleration = m.limits.max_acceleration;
    plan.sample_period = 1.0;
    const PlanOutcome outcome = pipeline_.Plan(plan, termination);
    if (outcome.code != PlanOutcomeCode::kSuccess) {
      result.out_of_time = outcome.code == PlanOutcomeCode::kNoPathWithinBudget ||
                           outcome.code == PlanOutcomeCode::kApproximateOnly || termination.ShouldStop();
      result.message = std::string(ToString(outcome.code)) + (outcome.message.empty() ? "" : ": " + outcome.message);
      return result;
    }
    result.ok = true;
    result.path = outcome.path;
    result.trajectory = outcome.trajectory;
    return result;
  }
  /// Robot k's path planned alone (cached; a plan that ran out of time is tried again, with the
  /// share of the budget left then, on the next call).
  const SinglePlan& Alone(int k) {
    auto it = alone_.find(k);
    if (it == alone_.end() || (it->second.out_of_time && !termination_.ShouldStop())) {
      const double share = std::min(10.0, std::max(0.05, termination_.SecondsLeft() / (2.0 * members_.size())));
      SinglePlan plan = PlanSingle(k, Own(k), termination_.WithBudget(std::chrono::duration<double>(share)), 0);
      if (plan.out_of_time) {
        plan.message = "found no path alone within " + FormatNumber(share) + " s (" + plan.message + ")";
      }
      it = alone_.insert_or_assign(k, std::move(plan)).first;
    }
    return it->second;
  }

  // --- methods --------------------------------------------------------------------------------
  std::vector<int> PriorityOrder() const {
    std::vector<int> order(members_.size());
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(),
                     [this](int a, int b) { return query_.robots[a].priority > query_.robots[b].priority; });
    return order;
  }
  Attempt RunPriorityLoop(bool prm, const Termination& termination);
  Attempt RunComposite(const Termination& termination);
  Attempt RunSequential(const Termination& termination);
  /// FLEET (fleet_method.h); its summary and verification are kept in fleet_.
  Attempt RunFleetMethod(const Termination& termination) {
    std::vector<detail::FleetMember> fleet_members;
    for (const Member& m : members_) fleet_members.push_back({&m.placement, m.start, m.goal, m.limits});
    fleet_ = detail::RunFleet(query_, fleet_members, termination);
    if (!fleet_->applicable && query_.method == CoordinationMethod::kFleet) {
      ThrowInvalid("method = FLEET cannot plan this team: " + fleet_->why_not);
    }
    Attempt attempt;
    attempt.ok = fleet_->ok;
    attempt.out_of_time = fleet_->out_of_time;
    attempt.message = fleet_->applicable ? fleet_->message : "not applicable: " + fleet_->why_not;
    if (!attempt.ok) return attempt;
    attempt.trajectories = fleet_->trajectories;
    attempt.paths = fleet_->paths;
    attempt.start_delay = fleet_->start_delay;
    attempt.wait_time = fleet_->wait_time;
    return attempt;
  }
  Attempt RunMethod(CoordinationMethod method, const Termination& termination) {
    switch (method) {
      case CoordinationMethod::kPrioritized: return RunPriorityLoop(true, termination);
      case CoordinationMethod::kVelocityTuning: return RunPriorityLoop(false, termination);
      case CoordinationMethod::kComposite: return RunComposite(termination);
      case CoordinationMethod::kSequential: return RunSequential(termination);
      case CoordinationMethod::kFleet: return RunFleetMethod(termination);
      case CoordinationMethod::kVelocityObstacles: return RunVelocityObstacles(termination);
      case CoordinationMethod::kAuto: break;
    }
    Attempt none;
    none.message = "no method";
    return none;
  }

  /// VELOCITY_OBSTACLES: the one robot steered among query_.moving_discs along its path alone.
  Attempt RunVelocityObstacles(const Termination& termination) {
    Attempt attempt;
    attempt.order = {0};
    const SinglePlan& alone = Alone(0);
    if (!alone.ok) {
      attempt.message = "robot '" + members_[0].placement.name + "' " +
                        (alone.out_of_time ? alone.message : "has no path even alone: " + alone.message);
      attempt.out_of_time = alone.out_of_time;
      return attempt;
    }
    const Member& m = members_[0];
    const VelocityObstacleResult steered = PlanWithVelocityObstacles(
        *Own(0), m.start, m.goal, query_.moving_discs, m.limits, alone.path, VelocityObstacleOptions{}, termination);
    if (!steered.reached) {
      attempt.message = steered.message;
      attempt.out_of_time = termination.ShouldStop();
      return attempt;
    }
    attempt.ok = true;
    attempt.trajectories = {steered.trajectory};
    attempt.paths = {steered.path};
    attempt.start_delay = {0.0};
    attempt.wait_time = {0.0};
    char closest[64];
    std::snprintf(closest, sizeof closest, "%.1f mm", 1e3 * steered.min_disc_distance);
    attempt.message = "steered in " + std::to_string(steered.steps) + " steps of 0.1 s along its path alone (" +
                      std::to_string(alone.path.size()) + " states); closest approach to a disc " + closest;
    return attempt;
  }

  /// The joint verification of an attempt; "" when it passes.
  std::string Verify(const Attempt& attempt, TeamVerificationReport* report);

  // --- the methods in turn (Run's phases 3 and 4) -------------------------------------------------
  /// The query's method, or AUTO's order: FLEET first for planar bases, then PRIORITIZED,
  /// VELOCITY_TUNING, COMPOSITE, SEQUENTIAL.
  std::vector<CoordinationMethod> Methods() const;
  /// One try of `method` within `stage`, verified; its report goes to *attempts, a verified
  /// result with a smaller makespan than *best replaces it, and a try its stage stopped (not the
  /// request's budget) is listed in *stopped.
  void TryMethod(CoordinationMethod method, const Termination& stage, std::optional<Verified>* best,
                 std::vector<CoordinationMethod>* stopped, std::vector<MethodAttemptReport>* attempts);
  /// The budget policy: with several methods the first tries share 60 % of the budget (each a
  /// share of what is left of it, the last all of it) and stop at the first success; then the
  /// methods their shares stopped come back, each with an equal part of what is left. The
  /// verified result with the smallest makespan, if any.
  std::optional<Verified> RunMethods(const std::vector<CoordinationMethod>& methods,
                                     std::vector<MethodAttemptReport>* attempts);
  /// The robots' plans (samples unless knots replace them), makespan, order and verification of
  /// the chosen result into *out.
  void TakeResult(const Verified& best, CoordinationOutcome* out);

  const CoordinationQuery& query_;
  const PlannerRegistry& registry_;
  const PlanningPipeline pipeline_;
  const Termination termination_;
  std::vector<Member> members_;
  std::shared_ptr<const CollisionChecker> team_;  ///< all members, self + scene (Team())
  std::map<std::tuple<std::string, std::string, double>, std::shared_ptr<const CollisionChecker>> pairs_;
  std::map<int, SinglePlan> alone_;
  std::optional<detail::FleetAttempt> fleet_;
  std::map<const RobotModel*, std::shared_ptr<const CollisionChecker>> ends_;  ///< EndsChecker's, per model
};

Attempt Coordinator::RunPriorityLoop(bool prm, const Termination& termination) {
  Attempt attempt;
  const int n = static_cast<int>(members_.size());
  const int max_reorderings = query_.max_reorderings > 0 ? query_.max_reorderings : 2 * n;
  std::vector<int> order = PriorityOrder();
  std::set<std::vector<int>> tried;
  std::string last_failure;
  for (int round = 0; round <= max_reorderings; ++round) {
    tried.insert(order);
    attempt.order = order;
    attempt.reorderings = round;
    attempt.trajectories.assign(n, TimedTrajectory());
    attempt.paths.assign(n, JointPath());
    attempt.start_delay.assign(n, 0.0);
    attempt.wait_time.assign(n, 0.0);
    int failed = -1;
    std::vector<double> blocked_by;  // per actor: conflicts counted while the failed robot searched
    std::vector<int> actor_member;   // actor index → member index (-1: committed motion)
    for (int position = 0; position < n && failed < 0; ++position) {
      if (termination.ShouldStop()) {
        attempt.message = "stopped before every robot was planned (time budget, deadline or cancellation)";
        attempt.out_of_time = true;
        return attempt;
      }
      const int k = order[position];
      const Member& m = members_[k];
      const SinglePlan& alone = Alone(k);
      if (!alone.ok) {
        attempt.message = "robot '" + m.placement.name + "' " +
                          (alone.out_of_time ? alone.message : "has no path even alone: " + alone.message);
        attempt.out_of_time = alone.out_of_time;
        return attempt;
      }
      // Moving obstacles: the robots planned before it, then the committed motions.
      std::vector<Actor> actors;
      actor_member.clear();
      double hold_until = 0.0;
      for (int p = 0; p < position; ++p) {
        const int j = order[p];
        actors.push_back(Actor{&members_[j].placement, &attempt.trajectories[j], 0.0,
                               std::numeric_limits<double>::infinity()});
        actor_member.push_back(j);
        hold_until = std::max(hold_until, attempt.trajectories[j].duration());
      }
      for (const CommittedMotion& c : query_.committed) {
        actors.push_back(Actor{&c.placement, &c.trajectory, c.begin, c.until});
        actor_member.push_back(-1);
        // One that stays for good (a moving obstacle) stands still after its motion: the goal
        // must be held clear until then, and a check at that time covers the rest.
        hold_until = std::max(hold_until, std::isfinite(c.until) ? c.until : c.begin + c.trajectory.duration());
      }
      blocked_by.assign(actors.size(), 0.0);
      std::vector<const CollisionChecker*> checkers;
      for (const Actor& a : actors) checkers.push_back(&Pair(m.placement, *a.placement, SearchPadding()));
      Eigen::VectorXd other;
      const ConflictFree conflict_free = [&](const Eigen::VectorXd& q, double t) {
        for (std::size_t a = 0; a < actors.size(); ++a) {
          if (!actors[a].StateAt(t, &other)) continue;
          if (checkers[a]->Check(Concat(q, other)).in_collision) {
            blocked_by[a] += 1.0;
            return false;
          }
        }
        return true;
      };

      // The roadmap: its path alone; with PRM also a path around the planned robots' goals and
      // an OMPL PRM of its configuration space.
      std::vector<JointPath> seeds{alone.path};
      RoadmapOptions roadmap_options;
      roadmap_options.seed = query_.seed + 104729 * static_cast<std::uint64_t>(k + 1);
      roadmap_options.prm_vertices = 0;
      // A car cannot follow a PRM's straight edges: its roadmap is its own path (chords of its curves).
      if (prm && alone.path.size() > 1 && !IsCar(m.placement.model->kind())) {
        roadmap_options.prm_vertices = m.placement.model->num_dofs() <= 3 ? 300 : 200;
        if (position > 0) {
          std::vector<std::pair<int, Eigen::VectorXd>> frozen;
          for (int p = 0; p < position; ++p) frozen.emplace_back(order[p], members_[order[p]].goal);
          const auto around = WithFrozen(k, frozen);
          if (around->IsValid(m.start) && around->IsValid(m.goal)) {
            const double share = std::max(0.05, std::min(2.0, termination.SecondsLeft() / (2.0 * n)));
            SinglePlan detour = PlanSingle(k, around, termination.WithBudget(std::chrono::duration<double>(share)), 1);
            if (detour.ok) seeds.push_back(detour.path);
          }
        }
      }
      const Roadmap roadmap = BuildRoadmap(*Own(k), seeds, roadmap_options, termination);
      int goal_vertex = -1;
      for (int v = 0; v < static_cast<int>(roadmap.vertices.size()); ++v) {
        if ((roadmap.vertices[v] - m.goal).cwiseAbs().maxCoeff() <= 1e-12) {
          goal_vertex = v;
          break;
        }
      }
      if (goal_vertex < 0) {
        attempt.message = "internal: robot '" + m.placement.name + "': the roadmap lost its goal vertex";
        return attempt;
      }
      SpaceTimeOptions options;
      options.hold_until = std::isfinite(hold_until) ? hold_until : 0.0;
      const double alone_time = alone.trajectory.duration();
      options.horizon = std::max(60.0, options.hold_until + 4.0 * alone_time + 10.0);
      const SpaceTimeResult found = SearchSpaceTime(roadmap, 0, goal_vertex, m.limits, conflict_free, options, termination);
      if (!found.found && termination.ShouldStop()) {
        attempt.message = "stopped while robot '" + m.placement.name + "' searched space-time (" +
                          std::to_string(position) + " robots planned before it): " + found.message;
        attempt.out_of_time = true;
        return attempt;
      }
      if (!found.found) {
        failed = k;
        last_failure = "robot '" + m.placement.name + "' found no way past the robots before it (" +
                       std::to_string(position) + " planned) and the committed motions: " + found.message;
        const auto most = std::max_element(blocked_by.begin(), blocked_by.end());
        if (most != blocked_by.end() && *most > 0.0) {
          const std::size_t a = static_cast<std::size_t>(most - blocked_by.begin());
          last_failure += "; most conflicts with " + (actor_member[a] >= 0 ? "robot '" + members_[actor_member[a]].placement.name + "'"
                                                                          : query_.committed[a - static_cast<std::size_t>(position)].id);
        }
        break;
      }
      attempt.trajectories[k] = found.trajectory;
      attempt.paths[k] = found.path;
      attempt.start_delay[k] = found.start_delay;
      attempt.wait_time[k] = found.wait_time;
    }
    if (failed < 0) {
      attempt.ok = true;
      attempt.message = std::string(prm ? "prioritized" : "velocity tuning") + " in order " ;
      for (std::size_t i = 0; i < order.size(); ++i) attempt.message += (i ? ", " : "") + members_[order[i]].placement.name;
      if (round > 0) attempt.message += " after " + std::to_string(round) + " reordering" + (round > 1 ? "s" : "");
      return attempt;
    }
    // Reorder: the failed robot goes just before the planned robot that blocked it most.
    int culprit = -1;
    double most = 0.0;
    for (std::size_t a = 0; a < blocked_by.size(); ++a) {
      if (actor_member[a] >= 0 && blocked_by[a] > most) {
        most = blocked_by[a];
        culprit = actor_member[a];
      }
    }
    std::vector<int> next = order;
    next.erase(std::find(next.begin(), next.end(), failed));
    if (culprit >= 0) {
      next.insert(std::find(next.begin(), next.end(), culprit), failed);
    } else {
      next.insert(next.begin(), failed);
    }
    if (tried.count(next)) {
      next = order;
      next.erase(std::find(next.begin(), next.end(), failed));
      next.insert(next.begin(), failed);
    }
    if (tried.count(next)) {
      attempt.message = last_failure + "; every reordering tried";
      return attempt;
    }
    order = next;
  }
  attempt.message = last_failure + "; gave up after " + std::to_string(max_reorderings) + " reorderings";
  return attempt;
}

Attempt Coordinator::RunComposite(const Termination& termination) {
  Attempt attempt;
  const int n = static_cast<int>(members_.size());
  if (n > kCompositeMaxRobots || Team()->robot().num_dofs() > kCompositeMaxDofs) {
    attempt.message = "the composite space of " + std::to_string(n) + " robots has " +
                      std::to_string(Team()->robot().num_dofs()) + " joints; composite planning is offered up to " +
                      std::to_string(kCompositeMaxRobots) + " robots and " + std::to_string(kCompositeMaxDofs) + " joints";
    return attempt;
  }
  for (const Member& m : members_) {
    if (IsCar(m.placement.model->kind())) {
      attempt.message = "robot '" + m.placement.name + "' is a car: the composite space has no car motions";
      return attempt;
    }
  }
  PlanQuery plan;
  plan.checker = Team();
  const std::vector<int> offsets = CompositeOffsets([this] {
    std::vector<PlacedRobot> p;
    for (const Member& m : members_) p.push_back(m.placement);
    return p;
  }());
  const int dofs = Team()->robot().num_dofs();
  plan.start.resize(dofs);
  plan.goal.resize(dofs);
  plan.trajectory.max_velocity.resize(dofs);
  plan.trajectory.max_acceleration.resize(dofs);
  for (int k = 0; k < n; ++k) {
    const int size = static_cast<int>(members_[k].start.size());
    plan.start.segment(offsets[k], size) = members_[k].start;
    plan.goal.segment(offsets[k], size) = members_[k].goal;
    plan.trajectory.max_velocity.segment(offsets[k], size) = members_[k].limits.max_velocity;
    plan.trajectory.max_acceleration.segment(offsets[k], size) = members_[k].limits.max_acceleration;
  }
  plan.goal_tolerance = 1e-6;
  plan.planner_id = query_.planner_id;
  plan.parameters = query_.parameters;
  plan.seed = query_.seed;
  plan.collision_resolution = query_.collision_resolution;
  plan.trajectory.method = PostProcessing::kTimeOptimal;
  plan.sample_period = 1.0;
  const PlanOutcome outcome = pipeline_.Plan(plan, termination);
  if (outcome.code != PlanOutcomeCode::kSuccess) {
    attempt.message = std::string("composite planning: ") + ToString(outcome.code) +
                      (outcome.message.empty() ? "" : ": " + outcome.message);
    return attempt;
  }
  attempt.ok = true;
  attempt.message = "one " + std::string(ToString(RobotKind::kArm)) + " path of " + std::to_string(outcome.path.size()) +
                    " waypoints in the " + std::to_string(dofs) + "-joint composite space";
  attempt.trajectories.resize(n);
  attempt.paths.resize(n);
  attempt.start_delay.assign(n, 0.0);
  attempt.wait_time.assign(n, 0.0);
  for (int k = 0; k < n; ++k) {
    const int size = static_cast<int>(members_[k].start.size());
    TimedTrajectory own = TrajectoryRows(outcome.trajectory, offsets[k], size);
    attempt.trajectories[k] = TruncatedAt(own, MotionEnd(own));
    for (const Eigen::VectorXd& q : outcome.path) {
      const Eigen::VectorXd part = q.segment(offsets[k], size);
      if (attempt.paths[k].empty() || (attempt.paths[k].back() - part).cwiseAbs().maxCoeff() > 0.0) {
        attempt.paths[k].push_back(part);
      }
    }
  }
  attempt.order = PriorityOrder();
  return attempt;
}

Attempt Coordinator::RunSequential(const Termination& termination) {
  Attempt attempt;
  const int n = static_cast<int>(members_.size());
  const std::vector<int> order = PriorityOrder();
  attempt.order = order;
  attempt.trajectories.assign(n, TimedTrajectory());
  attempt.paths.assign(n, JointPath());
  attempt.start_delay.assign(n, 0.0);
  attempt.wait_time.assign(n, 0.0);
  double clock = 0.0;
  for (int position = 0; position < n; ++position) {
    const int k = order[position];
    std::vector<std::pair<int, Eigen::VectorXd>> frozen;
    for (int p = 0; p < n; ++p) {
      if (p != position) frozen.emplace_back(order[p], p < position ? members_[order[p]].goal : members_[order[p]].start);
    }
    const double share = std::max(0.05, termination.SecondsLeft() / (n - position));
    const SinglePlan plan =
        PlanSingle(k, WithFrozen(k, frozen), termination.WithBudget(std::chrono::duration<double>(share)), 2);
    if (!plan.ok) {
      attempt.message = "robot '" + members_[k].placement.name + "' cannot move with the others at their " +
                        "starts or goals: " + plan.message;
      return attempt;
    }
    attempt.trajectories[k] = DelayedTrajectory(plan.trajectory, clock);
    attempt.paths[k] = plan.path;
    attempt.start_delay[k] = clock;
    attempt.wait_time[k] = clock;
    clock += plan.trajectory.duration();
  }
  // Committed motions are not waited for here: the joint check below rejects a clash.
  attempt.ok = true;
  attempt.message = "one robot after another";
  return attempt;
}

std::string Coordinator::Verify(const Attempt& attempt, TeamVerificationReport* report) {
  std::vector<Eigen::VectorXd> starts, goals;
  std::vector<KinematicLimits> limits;
  for (const Member& m : members_) {
    starts.push_back(m.start);
    goals.push_back(m.goal);
    limits.push_back(m.limits);
  }
  TeamVerificationOptions options;
  options.time_step = query_.time_step;
  options.max_joint_step = query_.collision_resolution;
  *report = VerifyTeam(*Team(), attempt.trajectories, starts, goals, limits, options);
  if (!report->ok) return report->reason;
  if (query_.robot_padding > 0.0 && members_.size() > 1) {
    std::vector<PlacedRobot> placements;
    for (const Member& m : members_) placements.push_back(m.placement);
    CompositionOptions pairs_only;
    pairs_only.self_collisions = false;
    CollisionOptions padded;
    padded.padding = ExactPadding();
    const CollisionChecker apart(ComposeRobots(placements, pairs_only), std::make_shared<Scene>(), padded);
    TeamVerificationOptions spacing_options = options;
    spacing_options.measure_robot_distance = false;  // measured on the unpadded shapes above
    const TeamVerificationReport spacing = VerifyTeam(apart, attempt.trajectories, starts, goals, limits, spacing_options);
    report->states_checked += spacing.states_checked;
    if (!spacing.ok) return "robots closer than robot_padding = " + FormatNumber(query_.robot_padding) + " m: " + spacing.reason;
    if (spacing.collision_guarantee != "certified" && report->collision_guarantee == "certified") {
      report->collision_guarantee = "discrete";
      report->collision_guarantee_reason = "robot_padding between robots: " + spacing.collision_guarantee_reason;
    }
  }
  if (!query_.committed.empty() && report->collision_guarantee == "certified") {
    // FindMotionConflict checks committed motions at discrete times.
    report->collision_guarantee = "discrete";
    report->collision_guarantee_reason =
        "certified against the scene, itself and each other, but against the workcell's committed trajectories "
        "and moving obstacles only at states at most " + FormatNumber(query_.time_step) + " s and " +
        FormatNumber(query_.collision_resolution) + " rad (m for prismatic and base joints) apart";
  }
  for (std::size_t k = 0; k < members_.size(); ++k) {
    CommittedMotion mine;
    mine.id = "robot '" + members_[k].placement.name + "'";
    mine.placement = members_[k].placement;
    mine.trajectory = attempt.trajectories[k];
    mine.begin = 0.0;
    mine.until = std::numeric_limits<double>::infinity();
    for (const CommittedMotion& c : query_.committed) {
      const std::string conflict =
          FindMotionConflict(mine, c, ExactPadding(), query_.time_step, query_.collision_resolution);
      if (!conflict.empty()) return conflict;
    }
  }
  return "";
}

std::vector<CoordinationMethod> Coordinator::Methods() const {
  if (query_.method != CoordinationMethod::kAuto) return {query_.method};
  std::vector<CoordinationMethod> methods;
  // Planar bases that FLEET can plan go to it first (it scales to hundreds of robots).
  if (detail::FleetInapplicable(query_).empty()) methods.push_back(CoordinationMethod::kFleet);
  for (CoordinationMethod method : {CoordinationMethod::kPrioritized, CoordinationMethod::kVelocityTuning,
                                    CoordinationMethod::kComposite, CoordinationMethod::kSequential}) {
    methods.push_back(method);
  }
  return methods;
}

void Coordinator::TryMethod(CoordinationMethod method, const Termination& stage, std::optional<Verified>* best,
                            std::vector<CoordinationMethod>* stopped, std::vector<MethodAttemptReport>* attempts) {
  const Clock::time_point t_method = Clock::now();
  MethodAttemptReport report;
  report.method = method;
  Attempt attempt = RunMethod(method, stage);
  TeamVerificationReport verification;
  if (method == CoordinationMethod::kFleet && fleet_) {
    verification = fleet_->verification;  // its own: the lattice and dependencies prove it (fleet.h)
  } else if (attempt.ok) {
    const std::string failure = Verify(attempt, &verification);
    if (!failure.empty()) {
      attempt.ok = false;
      attempt.message = "its result failed the joint verification: " + failure;
    }
  }
  report.seconds = SecondsSince(t_method);
  report.succeeded = attempt.ok;
  report.message = attempt.message;
  if (attempt.ok) {
    for (const TimedTrajectory& t : attempt.trajectories) report.makespan = std::max(report.makespan, t.duration());
    if (!*best || report.makespan < (*best)->makespan) {
      *best = Verified{std::move(attempt), verification, method, report.makespan};
    }
  } else if ((attempt.out_of_time || stage.ShouldStop()) && !termination_.ShouldStop()) {
    stopped->push_back(method);
  }
  attempts->push_back(report);
}

std::optional<Verified> Coordinator::RunMethods(const std::vector<CoordinationMethod>& methods,
                                                std::vector<MethodAttemptReport>* attempts) {
  const std::vector<double> shares = {0.4, 0.5, 0.6};  // of what is left of the first round, per first try
  std::optional<Verified> best;
  std::vector<CoordinationMethod> stopped;  // methods whose share ran out, in order
  const Termination first_round =
      methods.size() == 1 ? termination_
                          : termination_.WithBudget(std::chrono::duration<double>(0.6 * termination_.SecondsLeft()));
  for (std::size_t i = 0; i < methods.size() && !best; ++i) {
    if (termination_.ShouldStop()) break;
    const bool last = i + 1 == methods.size();
    const double share = methods.size() == 1 || last ? 1.0 : shares[std::min(i, shares.size() - 1)];
    TryMethod(methods[i], first_round.WithBudget(std::chrono::duration<double>(share * first_round.SecondsLeft())),
              &best, &stopped, attempts);
  }
  if (methods.size() > 1) {
    // After a success, only the methods tried before it come back (they may find a shorter
    // makespan).
    const std::vector<CoordinationMethod> again = stopped;
    for (std::size_t j = 0; j < again.size(); ++j) {
      if (termination_.ShouldStop()) break;
      const double share = 1.0 / static_cast<double>(again.size() - j);
      TryMethod(again[j], termination_.WithBudget(std::chrono::duration<double>(share * termination_.SecondsLeft())),
                &best, &stopped, attempts);
    }
  }
  return best;
}

void Coordinator::TakeResult(const Verified& best, CoordinationOutcome* out) {
  const Attempt& attempt = best.attempt;
  out->verification = best.verification;
  out->method = best.method;
  if (best.method == CoordinationMethod::kFleet && fleet_) out->fleet = fleet_->summary;
  for (int k : attempt.order) out->order.push_back(members_[k].placement.name);
  out->reorderings = attempt.reorderings;
  for (std::size_t k = 0; k < members_.size(); ++k) {
    const Member& m = members_[k];
    RobotPlan plan;
    plan.name = m.placement.name;
    plan.trajectory = attempt.trajectories[k];
    plan.duration = plan.trajectory.duration();
    plan.start_delay = attempt.start_delay[k];
    plan.wait_time = attempt.wait_time[k];
    plan.path = attempt.paths[k];
    plan.goal = m.goal;
    plan.limits = m.limits;
    // Gravity in the robot's base frame, for its torques.
    const Eigen::Vector3d gravity = m.placement.base_pose.linear().transpose() * Eigen::Vector3d(0.0, 0.0, -9.81);
    if (!query_.knots_replace_samples || plan.trajectory.degree() > 2) {
      plan.samples = SampleTrajectory(plan.trajectory, *m.placement.model, query_.sample_period, gravity,
                                      query_.sample_cap);
    }
    out->makespan = std::max(out->makespan, plan.duration);
    out->sum_of_durations += plan.duration;
    out->robots.push_back(std::move(plan));
  }
}

CoordinationOutcome Coordinator::Run() {
  const Clock::time_point t_start = Clock::now();
  CoordinationOutcome out;
  query_.Validate(registry_);
  const auto finish = [&](CoordinationCode code, std::string message) {
    out.code = code;
    out.message = std::move(message);
    out.seconds = SecondsSince(t_start);
    return out;
  };

  // 1. Members: limits, checkers alone, pose goals. The scene's allowed pairs name links of the
  //    team's robots (each robot's checker gets the pairs of its own links).
  const int n = static_cast<int>(query_.robots.size());
  const std::vector<AllowedCollision>& allowed = query_.scene->allowed_collisions();
  for (std::size_t i = 0; i < allowed.size(); ++i) {
    const bool known = std::any_of(query_.robots.begin(), query_.robots.end(), [&](const TeamRobotSpec& robot) {
      return robot.placement.model->FindLink(allowed[i].link) >= 0;
    });
    if (!known) {
      ThrowInvalid("scene.allowed_collisions[" + std::to_string(i) + "].link1 = '" + allowed[i].link +
                   "' is not a link of any robot of the team");
    }
  }
  for (int k = 0; k < n; ++k) {
    const TeamRobotSpec& spec = query_.robots[k];
    Member m;
    m.index = k;
    m.placement = spec.placement;
    m.placement.frozen_at.resize(0);
    m.start = spec.start;
    m.limits = ResolveRobotLimits(spec, k);
    const std::string who = "robot '" + spec.placement.name + "'";
    const CollisionChecker& ends = EndsChecker(&m);
    const CollisionResult start_contact = ends.Check(m.start);
    if (start_contact.in_collision) {
      return finish(CoordinationCode::kStartInCollision, who + ": start is in collision: " + Describe(start_contact));
    }
    if (spec.pose_goal) {
      const PoseGoalSpec& pose = *spec.pose_goal;
      IkRequest ik;
      SetPoseGoalIk(pose, termination_.SecondsLeft(), &ik);
      ik.max_solutions = 1;  // one goal state per robot
      ik.seed = query_.seed + k;
      ik.initial_guess = m.start;
      const CollisionChecker& own = ends;
      ik.accept = [&own](const Eigen::VectorXd& q) { return own.IsValid(q); };
      ik.stop = [this] { return termination_.ShouldStop(); };
      const IkResult solved = SolveIk(*spec.placement.model, ik);
      if (solved.solutions.empty()) {
        return finish(CoordinationCode::kGoalUnreachable, who + ": pose goal for link '" +
                                                              spec.placement.model->links()[pose.link].name +
                                                              "' has no collision-free IK solution: " + solved.message);
      }
      m.goal = solved.solutions.front();
    } else {
      m.goal = spec.goal;
      const CollisionResult goal_contact = ends.Check(m.goal);
      if (goal_contact.in_collision) {
        return finish(CoordinationCode::kGoalInCollision, who + ": goal is in collision: " + Describe(goal_contact));
      }
    }
    members_.push_back(std::move(m));
  }
  // 2. Starts and goals pairwise, and starts against committed motions at t = 0. Pairs whose
  //    bounding spheres (padding included) are apart at both ends need no pair checker.
  std::vector<std::pair<Eigen::Vector3d, double>> start_bounds, goal_bounds;
  for (const Member& m : members_) {
    start_bounds.push_back(BoundingSphere(m.placement, m.start));
    goal_bounds.push_back(BoundingSphere(m.placement, m.goal));
  }
  const auto apart = [&](const std::vector<std::pair<Eigen::Vector3d, double>>& bounds, int a, int b) {
    return (bounds[a].first - bounds[b].first).norm() > bounds[a].second + bounds[b].second + 2.0 * ExactPadding();
  };
  for (int a = 0; a < n; ++a) {
    for (int b = a + 1; b < n; ++b) {
      if (apart(start_bounds, a, b) && apart(goal_bounds, a, b)) continue;
      const CollisionChecker& pair = Pair(members_[a].placement, members_[b].placement, ExactPadding());
      const CollisionResult starts = pair.Check(Concat(members_[a].start, members_[b].start));
      if (starts.in_collision) {
        return finish(CoordinationCode::kStartsInConflict, "robots '" + members_[a].placement.name + "' and '" +
                                                               members_[b].placement.name + "' collide at their starts: " +
                                                               Describe(starts));
      }
      const CollisionResult goals = pair.Check(Concat(members_[a].goal, members_[b].goal));
      if (goals.in_collision) {
        return finish(CoordinationCode::kGoalsInConflict, "robots '" + members_[a].placement.name + "' and '" +
                                                              members_[b].placement.name +
                                                              "' collide at their goals, so they cannot both end there: " +
                                                              Describe(goals));
      }
    }
    for (const CommittedMotion& c : query_.committed) {
      Eigen::VectorXd other;
      const Actor actor{&c.placement, &c.trajectory, c.begin, c.until};
      if (!actor.StateAt(0.0, &other)) continue;
      const CollisionResult contact = Pair(members_[a].placement, c.placement, ExactPadding()).Check(Concat(members_[a].start, other));
      if (contact.in_collision) {
        return finish(CoordinationCode::kStartsInConflict, "robot '" + members_[a].placement.name +
                                                               "' at its start collides with committed trajectory " + c.id +
                                                               " at t = 0: " + Describe(contact));
      }
    }
  }

  // 3. The methods, then 4. the result.
  const std::optional<Verified> best = RunMethods(Methods(), &out.attempts);
  if (best) {
    TakeResult(*best, &out);
    return finish(CoordinationCode::kSuccess, std::string(ToString(best->method)) + ": " + best->attempt.message);
  }
  const StopReason reason = termination_.Reason();
  if (reason == StopReason::kCancelled) return finish(CoordinationCode::kCancelled, "cancelled");
  if (reason == StopReason::kDeadline) return finish(CoordinationCode::kDeadlineExceeded, "deadline exceeded");
  std::string message = "no method found conflict-free trajectories";
  if (out.attempts.empty()) message += " before the time budget ran out";
  for (const MethodAttemptReport& a : out.attempts) message += std::string("; ") + ToString(a.method) + ": " + a.message;
  return finish(CoordinationCode::kNoSolution, message);
}

}  // namespace

void CoordinationQuery::Validate(const PlannerRegistry& registry) const {
  if (!scene) ThrowInvalid("scene: no scene was given");
  if (max_robots < 1) ThrowInvalid("max_robots = " + std::to_string(max_robots) + " must be >= 1");
  if (robots.empty() || robots.size() > static_cast<std::size_t>(max_robots)) {
    ThrowInvalid("robots has " + std::to_string(robots.size()) + " entries; a team has 1 to " +
                 std::to_string(max_robots) + " robots on this server (chasles-server --max-team-robots)");
  }
  std::map<std::string, int> names;
  for (std::size_t k = 0; k < robots.size(); ++k) {
    const TeamRobotSpec& r = robots[k];
    const std::string field = "robots[" + std::to_string(k) + "]";
    CheckName(field + ".name", r.placement.name);
    const auto [it, inserted] = names.emplace(r.placement.name, static_cast<int>(k));
    if (!inserted) {
      ThrowInvalid(field + ".name = '" + r.placement.name + "' is already the name of robots[" +
                   std::to_string(it->second) + "]; robot names must be unique");
    }
    if (!r.placement.model) ThrowInvalid(field + ": no robot model");
    if (!r.placement.base_pose.matrix().allFinite()) ThrowInvalid(field + ".base_pose must be finite");
    const RobotModel& model = *r.placement.model;
    model.ValidateConfiguration(r.start, field + ".start.positions");
    if (r.pose_goal) {
      if (model.kind() != RobotKind::kArm) {
        throw Error(ErrorCode::kFailedPrecondition, field + ".pose_goal: pose goals need inverse kinematics of an arm; robot '" +
                                                        r.placement.name + "' is a " + ToString(model.kind()) +
                                                        " robot — give its goal in goal.positions");
      }
      if (r.pose_goal->link < 0 || r.pose_goal->link >= model.num_links()) {
        ThrowInvalid(field + ".pose_goal.link is not a link of robot '" + r.placement.name + "'");
      }
      if (!r.pose_goal->pose.matrix().allFinite()) ThrowInvalid(field + ".pose_goal.pose must be finite");
    } else {
      model.ValidateConfiguration(r.goal, field + ".goal.positions");
    }
    ResolveRobotLimits(r, static_cast<int>(k));
  }
  if (!std::isfinite(time_budget) || time_budget <= 0.0 || time_budget > 600.0) {
    ThrowInvalid("time_budget = " + FormatNumber(time_budget) + " must be within (0, 600]");
  }
  CheckRange(collision_resolution, 1e-4, 0.1, "collision_resolution");
  CheckRange(time_step, 1e-4, 0.01, "time_step");
  CheckRange(sample_period, 1e-4, 1.0, "sample_period");
  CheckRange(robot_padding, 0.0, 0.5, "robot_padding");
  CheckRange(fleet_resolution, 0.0, 10.0, "fleet_resolution");
  if (method == CoordinationMethod::kFleet) {
    const std::string why = detail::FleetInapplicable(*this);
    if (!why.empty()) ThrowInvalid("method = FLEET cannot plan this team: " + why);
  }
  if (method == CoordinationMethod::kVelocityObstacles) {
    if (robots.size() != 1 || robots.front().placement.model->kind() != RobotKind::kPlanar) {
      ThrowInvalid("method velocity_obstacles steers one planar base (x, y, theta); this query has " +
                   std::to_string(robots.size()) + " robots, the first a " +
                   ToString(robots.front().placement.model->kind()) + " robot");
    }
    if (robots.front().pose_goal) ThrowInvalid("method velocity_obstacles needs a joint goal (x, y, theta)");
  }
  if (max_reorderings < 0) ThrowInvalid("max_reorderings = " + std::to_string(max_reorderings) + " must be >= 0");
  const PlannerSpec& spec = registry.Spec(planner_id);  // throws NotFound
  ResolveParameters(spec, parameters);
  for (std::size_t c = 0; c < committed.size(); ++c) {
    const CommittedMotion& m = committed[c];
    const std::string field = "committed[" + std::to_string(c) + "] (" + m.id + ")";
    if (!m.placement.model) ThrowInvalid(field + ": no robot model");
    if (m.trajectory.empty() || m.trajectory.num_dofs() != m.placement.model->num_dofs()) {
      ThrowInvalid(field + ": the trajectory must have the robot's " + std::to_string(m.placement.model->num_dofs()) +
                   " joints");
    }
    if (names.count(m.placement.name)) {
      ThrowInvalid(field + ": robot name '" + m.placement.name + "' is also a team robot; leave a robot's own "
                   "reservations out");
    }
  }
}

std::string FindMotionConflict(const CommittedMotion& a, const CommittedMotion& b, double padding, double time_step,
                               double max_joint_step) {
  if (!(time_step > 0.0) || !(max_joint_step > 0.0)) ThrowInvalid("FindMotionConflict: steps must be > 0");
  const double begin = std::max(a.begin, b.begin);
  const double until = std::min(a.until, b.until);
  if (!(until >= begin)) return "";
  PlacedRobot pa = a.placement, pb = b.placement;
  pa.frozen_at.resize(0);
  pb.frozen_at.resize(0);
  CompositionOptions options;
  options.self_collisions = false;
  CollisionOptions collision;
  collision.padding = padding;
  const CollisionChecker pair(ComposeRobots({pa, pb}, options), std::make_shared<Scene>(), collision);
  // Past both motions' ends the robots stand still: one check covers the rest.
  const double moving_until = std::min(until, std::max(a.begin + a.trajectory.duration(), b.begin + b.trajectory.duration()));
  const double speed = std::max(MaxJointSpeed(a.trajectory), MaxJointSpeed(b.trajectory));
  double dt = time_step;
  if (speed > 0.0) dt = std::min(dt, max_joint_step / speed);
  const double span = std::max(0.0, moving_until - begin);
  const long steps = std::max(1L, static_cast<long>(std::ceil(span / dt)));
  for (long i = 0; i <= steps; ++i) {
    const double t = begin + span * static_cast<double>(i) / static_cast<double>(steps);
    const Eigen::VectorXd qa = a.trajectory.Evaluate(t - a.begin).q;
    const Eigen::VectorXd qb = b.trajectory.Evaluate(t - b.begin).q;
    const CollisionResult contact = pair.Check(Concat(qa, qb));
    if (contact.in_collision) {
      return a.id + " and " + b.id + " collide at t = " + FormatNumber(t) + " s: " + Describe(contact);
    }
  }
  return "";
}

CoordinationOutcome Coordinate(const CoordinationQuery& query, const PlannerRegistry& registry,
                               const Termination& termination) {
  const Termination bounded = termination.WithBudget(std::chrono::duration<double>(query.time_budget));
  Coordinator coordinator(query, registry, bounded);
  return coordinator.Run();
}

void CheckName(const std::string& field, const std::string& name) {
  const bool valid = !name.empty() && name.size() <= 64 && std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '.' ||
           c == '-';
  });
  if (!valid) ThrowInvalid(field + " = '" + name + "' must be 1 to 64 characters of [A-Za-z0-9_.-]");
}

}  // namespace chasles
