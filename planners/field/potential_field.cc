// potential_field: gradient descent in configuration space on an attractive + repulsive
// potential, with random-walk escapes from local minima (after Khatib 1986 and Barraquand &
// Latombe's randomized potential field planner; Choset et al., Principles of Robot Motion, ch. 4).
//
// Potential (dimensionless), q and the goal g in joint space:
//   U_att = ζ/2 ‖q − g‖²                    when ‖q − g‖ <= d*,
//           d* ζ ‖q − g‖ − ζ d*²/2          beyond (conic: a bounded pull far from the goal);
//   U_rep = Σ_links η/2 (1/d − 1/ρ0)²       for each link whose nearest obstacle is at d < ρ0.
// The repulsive force on a link, F = η (1/d − 1/ρ0)/d² n̂ (n̂ from the obstacle's nearest point
// to the link's), acts at the link's nearest point and maps to joint space through the
// transpose of that point's Jacobian (linear rows): ∇U_rep = −Σ J_vᵀ F.
//
// Descent: steps of length α = min(s·step, ‖q − g‖) along −∇U/‖∇U‖, clamped to the joint
// limits; the scale s halves whenever the direction turns back (an overshoot: a fixed
// normalized step would oscillate round a minimum) and regrows by 1.5 up to 1 otherwise; a step
// whose state or motion is invalid is halved, down to step/64. Every accepted step is a
// validated motion (certified when the checker certifies motions, else discrete at max_step),
// so the path is the descent itself (thinned: a waypoint is dropped only when the chord that
// replaces it is a validated motion too). Within `step` of the goal (or within goal_tolerance)
// the exact goal is connected by a validated motion. With additional goals the descent aims at
// the acceptable goal nearest the start.
//
// Local minimum: the gradient vanishes, the step scale falls below 1/64, a step cannot be taken
// even at step/64, or the distance to the goal improves by less than one `step` over
// kStallWindow steps. Escape: a random walk of walk_length valid steps of length `step` from the
// current minimum, then descent again. The search moves on to the new minimum when its
// potential is lower or when it lies in another basin (farther than kSameMinimum steps): a walk
// over the minima, so a chain of escapes can round an obstacle whose far side is no lower. The
// walk is correlated (each step's direction is the previous one perturbed by up to kWalkTurn
// per coordinate, a fresh direction after a blocked step), so it travels about
// walk_length·step rather than √walk_length·step: far enough to leave a minimum's basin in a
// few tries. The walks draw from std::mt19937_64 seeded from the request seed (portable, so
// seeded runs repeat). A run that ends stuck reports kLocalMinimum with an empty path — never a
// path that misses the goal; one stopped by its budget while still descending reports
// kNoSolution.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "chasles/collision/proximity.h"
#include "chasles/robot/error.h"
#include "chasles/robot/kinematics.h"
#include "field.h"

namespace chasles::field {
namespace {

constexpr int kStallWindow = 25;        // steps over which the distance to the goal must improve
constexpr int kHalvings = 6;            // a step is halved at most this often (to step/64)
constexpr double kMinScale = 1.0 / 64;  // the descent's step shrinks no further at a minimum
constexpr int kWalkTries = 10;          // random directions tried per walk step
constexpr double kWalkTurn = 0.5;       // per-coordinate perturbation of a walk's heading
constexpr double kSameMinimum = 10.0;   // minima closer than this many steps share a basin
constexpr double kMinGradient = 1e-12;  // below this the gradient has vanished
constexpr double kMinDistance = 1e-6;   // repulsion is evaluated no closer than this [m]

class PotentialFieldPlanner : public Planner {
 public:
  explicit PotentialFieldPlanner(PlannerSpec spec) : spec_(std::move(spec)) {}

  const PlannerSpec& spec() const override { return spec_; }

  void Setup(const PlanningProblem& problem) override {
    Clear();
    const ParameterValues params = ResolveParameters(spec_, problem.parameters);
    problem_ = problem;
    zeta_ = params.at("attractive_gain");
    d_star_ = params.at("attractive_radius");
    eta_ = params.at("repulsive_gain");
    rho0_ = params.at("influence_distance");
    step_ = params.at("step");
    random_walks_ = static_cast<int>(params.at("random_walks"));
    walk_length_ = static_cast<int>(params.at("walk_length"));
    max_steps_ = static_cast<std::uint64_t>(params.at("max_steps"));
    // Descend toward the acceptable goal nearest the start; the path ends exactly there.
    goal_ = problem.goal;
    for (const Eigen::VectorXd& g : problem.additional_goals) {
      if ((g - problem.start).norm() < (goal_ - problem.start).norm()) goal_ = g;
    }
    proximity_ = std::make_unique<ObstacleProximity>(problem.checker);
  }

  PlannerResult Solve(const Termination& termination) override;

  void Clear() override {
    proximity_.reset();
    problem_ = PlanningProblem();
  }

 private:
  enum class Outcome { kGoal, kStuck, kStopped, kMaxSteps };

  /// ∇U at q into *grad; returns U.
  double Gradient(const Eigen::VectorXd& q, Eigen::VectorXd* grad) const;
  /// Descends from q (the path's last state), appending accepted states to *path.
  Outcome Descend(const Termination& termination, std::vector<Eigen::VectorXd>* path);
  /// A random walk from the path's last state, appending accepted states to *path.
  Outcome Walk(const Termination& termination, UniformStream* random, std::vector<Eigen::VectorXd>* path);
  /// The motion q → next, next clamped into the joint limits, when next is valid.
  bool TryStep(const Eigen::VectorXd& q, Eigen::VectorXd* next);
  /// Fewer states: each kept state joins the farthest of the next 2..32 states whose straight
  /// motion is valid.
  std::vector<Eigen::VectorXd> Thin(const std::vector<Eigen::VectorXd>& path);
  bool StepBudgetLeft() const { return max_steps_ == 0 || steps_ < max_steps_; }

  PlannerSpec spec_;
  PlanningProblem problem_;
  Eigen::VectorXd goal_;
  std::unique_ptr<ObstacleProximity> proximity_;
  double zeta_ = 1.0, d_star_ = 1.0, eta_ = 0.0, rho0_ = 0.1, step_ = 0.05;
  int random_walks_ = 0, walk_length_ = 1;
  std::uint64_t max_steps_ = 0;
  // Per Solve.
  std::uint64_t steps_ = 0;
  std::uint64_t checks_ = 0;
  double last_gradient_norm_ = 0.0;
};

double PotentialFieldPlanner::Gradient(const Eigen::VectorXd& q, Eigen::VectorXd* grad) const {
  const Eigen::VectorXd e = q - goal_;
  const double rho = e.norm();
  double u;
  if (rho <= d_star_) {
    u = 0.5 * zeta_ * rho * rho;
    *grad = zeta_ * e;
  } else {
    u = d_star_ * zeta_ * rho - 0.5 * zeta_ * d_star_ * d_star_;
    *grad = (d_star_ * zeta_ / rho) * e;
  }
  if (eta_ <= 0.0) return u;
  thread_local std::vector<LinkProximity> near;
  proximity_->Query(q, rho0_, &near);
  const RobotModel& robot = problem_.checker->robot();
  std::vector<Eigen::Isometry3d> poses;
  for (const LinkProximity& p : near) {
    if (!p.found() || !(p.distance < rho0_)) continue;
    const Eigen::Vector3d away = p.link_point - p.obstacle_point;
    if (away.norm() <= 0.0) continue;  // contact: no direction (such states are never valid)
    const double d = std::max(p.distance, kMinDistance);
    const double excess = 1.0 / d - 1.0 / rho0_;
    u += 0.5 * eta_ * excess * excess;
    const Eigen::Vector3d force = (eta_ * excess / (d * d)) * away.normalized();
    if (poses.empty()) robot.ForwardKinematics(q, &poses);
    const Eigen::Vector3d local = poses[p.link].inverse() * p.link_point;
    const Jacobian jac = PointJacobian(robot, q, p.link, local);
    *grad -= jac.bottomRows<3>().transpose() * force;
  }
  return u;
}

bool PotentialFieldPlanner::TryStep(const Eigen::VectorXd& q, Eigen::VectorXd* next) {
  const RobotModel& robot = problem_.checker->robot();
  *next = next->cwiseMax(robot.lower_limits()).cwiseMin(robot.upper_limits());
  if (*next == q) return false;
  if (!StateValid(*problem_.checker, *next, &checks_)) return false;
  return MotionValid(*problem_.checker, q, *next, problem_.max_step, &checks_);
}

PotentialFieldPlanner::Outcome PotentialFieldPlanner::Descend(const Termination& termination,
                                                              std::vector<Eigen::VectorXd>* path) {
  Eigen::VectorXd q = path->back();
  Eigen::VectorXd grad, next, previous_dir;
  double scale = 1.0;  // of `step`: halved when the descent turns back, regrown by 1.5 otherwise
  double best = (q - goal_).norm();
  double window_start = best;
  int window_steps = 0;
  for (;;) {
    if (termination.ShouldStop()) return Outcome::kStopped;
    const double dist = (q - goal_).norm();
    if ((q - goal_).cwiseAbs().maxCoeff() <= problem_.goal_tolerance || dist <= step_) {
      if (MotionValid(*problem_.checker, q, goal_, problem_.max_step, &checks_)) {
        path->push_back(goal_);
        return Outcome::kGoal;
      }
    }
    if (!StepBudgetLeft()) return Outcome::kMaxSteps;
    Gradient(q, &grad);
    last_gradient_norm_ = grad.norm();
    if (!(last_gradient_norm_ > kMinGradient)) return Outcome::kStuck;
    const Eigen::VectorXd dir = -grad / last_gradient_norm_;
    if (previous_dir.size() == dir.size() && previous_dir.dot(dir) < 0.0) {
      scale *= 0.5;  // overshot a valley floor or a minimum
      if (scale < kMinScale) return Outcome::kStuck;
    } else {
      scale = std::min(1.0, 1.5 * scale);
    }
    previous_dir = dir;
    double alpha = std::min(scale * step_, dist);
    bool moved = false;
    for (int h = 0; h <= kHalvings && !moved; ++h, alpha *= 0.5) {
      next = q + alpha * dir;
      moved = TryStep(q, &next);
    }
    if (!moved) return Outcome::kStuck;
    ++steps_;
    q = next;
    path->push_back(q);
    best = std::min(best, (q - goal_).norm());
    if (++window_steps == kStallWindow) {
      if (window_start - best < step_) return Outcome::kStuck;
      window_start = best;
      window_steps = 0;
    }
  }
}

PotentialFieldPlanner::Outcome PotentialFieldPlanner::Walk(const Termination& termination, UniformStream* random,
                                                           std::vector<Eigen::VectorXd>* path) {
  const int n = static_cast<int>(goal_.size());
  Eigen::VectorXd heading = Eigen::VectorXd::Zero(n), dir(n), next;
  for (int s = 0; s < walk_length_; ++s) {
    if (termination.ShouldStop()) return Outcome::kStopped;
    if (!StepBudgetLeft()) return Outcome::kMaxSteps;
    const Eigen::VectorXd q = path->back();
    bool moved = false;
    for (int t = 0; t < kWalkTries && !moved; ++t) {
      // Correlated: the previous heading plus a uniform perturbation of up to kWalkTurn per
      // coordinate; a fresh direction when there is no heading (first step, or blocked).
      for (int i = 0; i < n; ++i) dir[i] = heading[i] + random->Next(-1.0, 1.0) * (t == 0 ? kWalkTurn : 1.0);
      if (dir.norm() < 1e-3) continue;
      dir.normalize();
      next = q + step_ * dir;
      moved = TryStep(q, &next);
      if (!moved) heading.setZero();
    }
    if (!moved) break;  // boxed in: the walk ends here
    heading = dir;
    ++steps_;
    path->push_back(next);
  }
  return Outcome::kStuck;  // the walk itself never reaches the goal; descent follows
}

std::vector<Eigen::VectorXd> PotentialFieldPlanner::Thin(const std::vector<Eigen::VectorXd>& path) {
  std::vector<Eigen::VectorXd> out{path.front()};
  std::size_t i = 0;
  while (i + 1 < path.size()) {
    std::size_t next = i + 1, tried = 0;
    for (std::size_t jump = 32; jump >= 2; jump /= 2) {
      const std::size_t j = std::min(i + jump, path.size() - 1);
      if (j <= i + 1 || j == tried) continue;
      tried = j;
      if (MotionValid(*problem_.checker, path[i], path[j], problem_.max_step, &checks_)) {
        next = j;
        break;
      }
    }
    i = next;
    out.push_back(path[i]);
  }
  return out;
}

PlannerResult PotentialFieldPlanner::Solve(const Termination& termination) {
  if (!proximity_) ThrowInvalid("planner '" + spec_.id + "': Solve() called before Setup()");
  const auto t0 = Termination::Clock::now();
  PlannerResult result;
  steps_ = 0;
  checks_ = 0;
  last_gradient_norm_ = 0.0;
  const auto finish = [&](PlannerResult r) {
    r.state_checks = checks_;
    r.graph_states = steps_;
    r.solve_seconds = std::chrono::duration<double>(Termination::Clock::now() - t0).count();
    return r;
  };
  if (StoppedByClient(termination, spec_.id, &result)) return finish(result);
  if (!EndpointsValid(problem_, goal_, spec_.id, &result, &checks_)) return finish(result);

  UniformStream random(problem_.seed);
  Eigen::VectorXd grad;
  // `path` ends at the current minimum; a walk and its descent are tried on a copy.
  std::vector<Eigen::VectorXd> path{problem_.start};
  Outcome outcome = Descend(termination, &path);
  bool stuck = outcome == Outcome::kStuck;  // in a local minimum, escaping
  double current_u = Gradient(path.back(), &grad);
  // The lowest minimum found, for the report.
  Eigen::VectorXd lowest = path.back();
  double lowest_u = current_u, lowest_gradient = grad.norm();
  int walks = 0;
  while (stuck && walks < random_walks_) {
    ++walks;
    std::vector<Eigen::VectorXd> attempt = path;
    outcome = Walk(termination, &random, &attempt);
    if (outcome == Outcome::kStuck) outcome = Descend(termination, &attempt);
    if (outcome == Outcome::kGoal) {
      path = std::move(attempt);
      stuck = false;
      break;
    }
    if (outcome != Outcome::kStuck) break;  // stopped or out of steps while escaping
    const double u = Gradient(attempt.back(), &grad);
    const bool lower = u < current_u;
    const bool elsewhere = (attempt.back() - path.back()).norm() > kSameMinimum * step_;
    if (lower || elsewhere) {  // move on from there; a walk back into the same basin is dropped
      current_u = u;
      path = std::move(attempt);
      if (u < lowest_u) {
        lowest = path.back();
        lowest_u = u;
        lowest_gradient = grad.norm();
      }
    }
  }

  if (outcome == Outcome::kGoal) {
    result.path = Thin(path);
    result.path.front() = problem_.start;
    result.path.back() = goal_;
    result.status = PlanStatus::kExactSolution;
    result.message = spec_.id + " reached the goal in " + std::to_string(steps_) + " steps" +
                     (walks > 0 ? " and " + std::to_string(walks) + " random walks" : std::string()) + "; " +
                     std::to_string(result.path.size()) + " waypoints";
    return finish(result);
  }
  if (StoppedByClient(termination, spec_.id, &result)) return finish(result);
  const Eigen::VectorXd& q = stuck ? lowest : path.back();
  const std::string where = "at q = " + FormatConfig(q) + ", " + FormatNumber((q - goal_).norm()) +
                            " rad from the goal, gradient norm " + FormatNumber(lowest_gradient);
  const std::string budget = outcome == Outcome::kMaxSteps ? "max_steps = " + std::to_string(max_steps_) + " steps"
                                                           : "the time budget";
  if (stuck) {
    result.status = PlanStatus::kLocalMinimum;
    result.message = spec_.id + " stopped in a local minimum " + where + " after " + std::to_string(walks) +
                     " random walk" + (walks == 1 ? "" : "s") +
                     (outcome == Outcome::kStuck ? "" : " (escapes cut short by " + budget + ")") +
                     "; try more random_walks or longer walk_length, or a sampling planner";
  } else {
    result.status = PlanStatus::kNoSolution;
    result.message = spec_.id + " did not reach the goal within " + budget + "; the descent was at q = " +
                     FormatConfig(q) + ", " + FormatNumber((q - goal_).norm()) + " rad from the goal";
  }
  return finish(result);
}

}  // namespace

PlannerSpec PotentialFieldSpec() {
  PlannerSpec spec;
  spec.id = "potential_field";
  spec.description =
      "Artificial potential field: normalized gradient descent in configuration space on a quadratic/conic attraction "
      "to the goal plus FCL-distance repulsion of every link from its nearest obstacle (mapped through the point "
      "Jacobian), with random-walk escapes from local minima. Returns at the goal, or LOCAL_MINIMUM with no path";
  spec.optimizing = false;
  spec.parameters = {
      {"attractive_gain", "ζ, weight of the attraction to the goal [1/rad²] (the potential is dimensionless)",
       ParameterType::kDouble, 1.0, 1e-6, 1e6},
      {"attractive_radius", "d*, joint-space distance to the goal where the attraction turns from quadratic to conic [rad]",
       ParameterType::kDouble, 1.0, 1e-6, 100.0},
      {"repulsive_gain", "η, weight of the repulsion from obstacles [m²]; 0 = none", ParameterType::kDouble, 0.01, 0.0,
       1e6},
      {"influence_distance", "ρ0, obstacles farther than this from a link do not repel it [m]", ParameterType::kDouble,
       0.2, 1e-4, 10.0},
      {"step", "length of a descent or random-walk step (Euclidean joint distance) [rad]", ParameterType::kDouble, 0.05,
       1e-4, 1.0},
      {"random_walks", "random walks tried to escape local minima [-]; 0 = report the first local minimum",
       ParameterType::kInt, 50.0, 0.0, 100000.0},
      {"walk_length", "steps of one random walk [-]", ParameterType::kInt, 80.0, 1.0, 100000.0},
      {"max_steps", "stop after this many descent and walk steps in total [-]; 0 = until the time budget",
       ParameterType::kInt, 0.0, 0.0, 1e9},
  };
  return spec;
}

std::unique_ptr<Planner> MakePotentialFieldPlanner(const PlannerSpec& spec) {
  return std::make_unique<PotentialFieldPlanner>(spec);
}

}  // namespace chasles::field
