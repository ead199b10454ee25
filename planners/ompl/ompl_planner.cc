// OMPL-backed sampling planners behind the chasles::Planner interface.
//
// Reproducibility: every random stream is seeded from the request seed — state samplers
// (through JointSpace::allocDefaultStateSampler) and each planner's own RNG (goal bias,
// random walks) through a thin subclass. A planner that returns at its first solution is then
// reproducible. Anytime planners stop at their time budget, which depends on the machine;
// they are reproducible when `max_iterations` ends the run first. Two OMPL behaviours would
// break this and are replaced: PRM's roadmap grows beside a solution-checking thread in timed
// slices (SingleThreadPrm), and the direct informed sampler keeps a private clock-seeded RNG
// (SeededPathLengthObjective samples the informed set by rejection from our seeded stream).

#include <atomic>
#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <ompl/base/MotionValidator.h>
#include <ompl/base/PlannerData.h>
#include <ompl/base/ProblemDefinition.h>
#include <ompl/base/ScopedState.h>
#include <ompl/base/SpaceInformation.h>
#include <ompl/base/StateValidityChecker.h>
#include <ompl/base/goals/GoalSampleableRegion.h>
#include <ompl/base/goals/GoalStates.h>
#include <ompl/base/objectives/PathLengthOptimizationObjective.h>
#include <ompl/base/samplers/informed/RejectionInfSampler.h>
#include <ompl/base/spaces/RealVectorStateSpace.h>
#include <ompl/geometric/PathGeometric.h>
#include <ompl/geometric/planners/informedtrees/BITstar.h>
#include <ompl/geometric/planners/prm/LazyPRMstar.h>
#include <ompl/geometric/planners/prm/PRM.h>
#include <ompl/geometric/planners/prm/PRMstar.h>
#include <ompl/geometric/planners/rrt/InformedRRTstar.h>
#include <ompl/geometric/planners/rrt/RRT.h>
#include <ompl/geometric/planners/rrt/RRTConnect.h>
#include <ompl/geometric/planners/rrt/RRTstar.h>
#include <ompl/util/Console.h>

#include "chasles/planners/registry.h"
#include "chasles/robot/error.h"

namespace ob = ompl::base;
namespace og = ompl::geometric;

namespace chasles {
namespace {

/// SplitMix64: decorrelates the seeds of the several random streams of one request.
std::uint32_t MixSeed(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  x ^= x >> 31;
  const auto s = static_cast<std::uint32_t>(x);
  return s == 0 ? 1u : s;
}

class SeededSampler : public ob::RealVectorStateSampler {
 public:
  SeededSampler(const ob::StateSpace* space, std::uint32_t seed) : ob::RealVectorStateSampler(space) {
    rng_.setLocalSeed(seed);
  }
};

/// Joint space: a bounded real vector space whose samplers draw from the request seed.
class JointSpace : public ob::RealVectorStateSpace {
 public:
  JointSpace(unsigned int dim, std::uint64_t seed) : ob::RealVectorStateSpace(dim), seed_(seed) {}
  ob::StateSamplerPtr allocDefaultStateSampler() const override {
    return std::make_shared<SeededSampler>(this, MixSeed(seed_ + 0x100 + counter_++));
  }

 private:
  std::uint64_t seed_;
  mutable std::atomic<std::uint64_t> counter_{0};
};

/// Path length, with informed sampling by rejection from the space's (seeded) sampler.
/// OMPL's default direct informed sampler keeps a private, clock-seeded RNG; rejection
/// sampling draws the same uniform distribution over the informed set from our seeded stream.
class SeededPathLengthObjective : public ob::PathLengthOptimizationObjective {
 public:
  using ob::PathLengthOptimizationObjective::PathLengthOptimizationObjective;
  ob::InformedSamplerPtr allocInformedStateSampler(const ob::ProblemDefinitionPtr& problem,
                                                   unsigned int max_calls) const override {
    return std::make_shared<ob::RejectionInfSampler>(problem, max_calls);
  }
};

void ToEigen(const ob::State* state, int n, Eigen::VectorXd* q) {
  const double* v = state->as<ob::RealVectorStateSpace::StateType>()->values;
  q->resize(n);
  for (int i = 0; i < n; ++i) (*q)[i] = v[i];
}

void FromEigen(const Eigen::VectorXd& q, ob::State* state) {
  double* v = state->as<ob::RealVectorStateSpace::StateType>()->values;
  for (int i = 0; i < q.size(); ++i) v[i] = q[i];
}

class ValidityChecker : public ob::StateValidityChecker {
 public:
  ValidityChecker(const ob::SpaceInformationPtr& si, std::shared_ptr<const CollisionChecker> checker,
                  std::atomic<std::uint64_t>* checks)
      : ob::StateValidityChecker(si), checker_(std::move(checker)), checks_(checks) {}
  bool isValid(const ob::State* state) const override {
    thread_local Eigen::VectorXd q;
    ToEigen(state, checker_->robot().num_dofs(), &q);
    checks_->fetch_add(1, std::memory_order_relaxed);
    return checker_->IsValid(q);
  }

 private:
  std::shared_ptr<const CollisionChecker> checker_;
  std::atomic<std::uint64_t>* checks_;
};

/// Motion validation delegated to the checker: certified (no state on the segment collides)
/// when checker->certifies_motion(), otherwise discrete at the request's resolution.
class MotionChecker : public ob::MotionValidator {
 public:
  MotionChecker(const ob::SpaceInformationPtr& si, std::shared_ptr<const CollisionChecker> checker,
                double max_step, std::atomic<std::uint64_t>* checks)
      : ob::MotionValidator(si), checker_(std::move(checker)), max_step_(max_step), checks_(checks) {}

  bool checkMotion(const ob::State* s1, const ob::State* s2) const override {
    thread_local Eigen::VectorXd a, b;
    const int n = checker_->robot().num_dofs();
    ToEigen(s1, n, &a);
    ToEigen(s2, n, &b);
    CheckCounters counters;
    const bool ok = checker_->certifies_motion() ? checker_->IsMotionCertified(a, b, &counters)
                                                 : checker_->IsMotionValid(a, b, max_step_, &counters);
    checks_->fetch_add(counters.state_checks, std::memory_order_relaxed);
    ok ? ++valid_ : ++invalid_;
    return ok;
  }

  /// Walks s1 → s2 in order and reports the last valid state and its fraction.
  bool checkMotion(const ob::State* s1, const ob::State* s2,
                   std::pair<ob::State*, double>& last_valid) const override {
    thread_local Eigen::VectorXd a, b, q;
    const int n = checker_->robot().num_dofs();
    ToEigen(s1, n, &a);
    ToEigen(s2, n, &b);
    bool certified = false;
    if (checker_->certifies_motion()) {
      CheckCounters counters;
      certified = checker_->IsMotionCertified(a, b, &counters);
      checks_->fetch_add(counters.state_checks, std::memory_order_relaxed);
      if (certified) {
        ++valid_;
        return true;
      }
    }
    const double span = (b - a).cwiseAbs().maxCoeff();
    const int steps = std::max(1, static_cast<int>(std::ceil(span / max_step_)));
    for (int k = 1; k <= steps; ++k) {
      const double s = static_cast<double>(k) / steps;
      q = k == steps ? b : Eigen::VectorXd(a + s * (b - a));
      checks_->fetch_add(1, std::memory_order_relaxed);
      if (!checker_->IsValid(q)) {
        const double s_last = static_cast<double>(k - 1) / steps;
        if (last_valid.first != nullptr) {
          FromEigen(Eigen::VectorXd(a + s_last * (b - a)), last_valid.first);
        }
        last_valid.second = s_last;
        ++invalid_;
        return false;
      }
    }
    if (checker_->certifies_motion()) {
      // Every sample is valid but the certified check rejected the segment (a contact between
      // samples, or a graze): keep only a.
      if (last_valid.first != nullptr) FromEigen(a, last_valid.first);
      last_valid.second = 0.0;
      ++invalid_;
      return false;
    }
    ++valid_;
    return true;
  }

 private:
  std::shared_ptr<const CollisionChecker> checker_;
  double max_step_;
  std::atomic<std::uint64_t>* checks_;
};

/// Seeds a planner's own RNG (goal bias, random walks) from the request seed.
template <class P>
class Seeded : public P {
 public:
  Seeded(const ob::SpaceInformationPtr& si, std::uint32_t seed) : P(si) { this->rng_.setLocalSeed(seed); }
};

/// PRM / PRM* run on one thread: OMPL's own roadmap growth, expansion and solution search,
/// in slices of a fixed number of termination checks, instead of OMPL's solution-checking
/// thread and timed slices. The roadmap then depends only on the seed, so a seeded run repeats.
/// A first-solution PRM stops at the first connection; PRM* keeps the best path until `ptc`.
template <class Base>
class SingleThreadPrm : public Base {
 public:
  SingleThreadPrm(const ob::SpaceInformationPtr& si, std::uint32_t seed) : Base(si) { this->rng_.setLocalSeed(seed); }

  ob::PlannerStatus solve(const ob::PlannerTerminationCondition& ptc) override {
    this->checkValidity();
    auto* goal = dynamic_cast<ob::GoalSampleableRegion*>(this->pdef_->getGoal().get());
    if (goal == nullptr) return ob::PlannerStatus::UNRECOGNIZED_GOAL_TYPE;
    while (const ob::State* start = this->pis_.nextStart()) {
      this->startM_.push_back(this->addMilestone(this->si_->cloneState(start)));
    }
    if (this->startM_.empty()) return ob::PlannerStatus::INVALID_START;
    if (this->goalM_.empty()) {
      if (const ob::State* g = this->pis_.nextGoal(ptc)) this->goalM_.push_back(this->addMilestone(this->si_->cloneState(g)));
    }
    if (this->goalM_.empty()) return ob::PlannerStatus::INVALID_GOAL;
    if (!this->sampler_) this->sampler_ = this->si_->allocValidStateSampler();
    if (!this->simpleSampler_) this->simpleSampler_ = this->si_->allocStateSampler();

    constexpr unsigned kBounceSteps = 5;  // length of an expansion's random bounce walk
    // Termination checks per expansion slice; a growth slice gets twice as many (about two
    // milestones). The solution check after each slice is a disjoint-set lookup until start
    // and goal share a component, so checking this often costs little and finds paths early.
    constexpr unsigned kGrowSlice = 2;
    std::vector<ob::State*> work(kBounceSteps);
    this->si_->allocStates(work);
    ob::PathPtr solution;
    bool satisfied = false;
    bool grow = true;  // 2:1 growth to expansion, as OMPL's PRM does by time
    while (!satisfied && !ptc) {
      unsigned left = grow ? 2 * kGrowSlice : kGrowSlice;
      const ob::PlannerTerminationCondition slice([&ptc, &left] { return ptc() || left-- == 0; });
      if (grow) {
        this->growRoadmap(slice, work[0]);
      } else {
        this->expandRoadmap(slice, work);
      }
      grow = !grow;
      satisfied = this->maybeConstructSolution(this->startM_, this->goalM_, solution);
    }
    this->si_->freeStates(work);
    if (!solution) return ob::PlannerStatus::TIMEOUT;
    ob::PlannerSolution found(solution);
    found.setPlannerName(this->getName());
    this->pdef_->addSolutionPath(found);
    return ob::PlannerStatus::EXACT_SOLUTION;
  }
};

enum class Kind { kPrm, kPrmStar, kLazyPrmStar, kRrt, kRrtStar, kInformedRrtStar, kRrtConnect, kBitStar };

ParameterSpec RangeParam() {
  return {"range", "maximum length of a tree extension (Euclidean joint distance) [rad]; 0 = 20% of the joint-space diagonal",
          ParameterType::kDouble, 0.0, 0.0, 100.0};
}
ParameterSpec GoalBiasParam() {
  return {"goal_bias", "probability of sampling the goal [-]", ParameterType::kDouble, 0.05, 0.0, 1.0};
}
ParameterSpec RewireParam() {
  return {"rewire_factor", "multiplier of the optimal rewiring radius / neighbour count [-]",
          ParameterType::kDouble, 1.1, 1.0, 10.0};
}
ParameterSpec IterationsParam() {
  return {"max_iterations",
          "stop after this many termination checks (about one per iteration); 0 = run to the time budget. "
          "Set it for reproducible anytime runs",
          ParameterType::kInt, 0.0, 0.0, 1e9};
}

class OmplPlanner : public Planner {
 public:
  OmplPlanner(Kind kind, PlannerSpec spec) : kind_(kind), spec_(std::move(spec)) {}

  const PlannerSpec& spec() const override { return spec_; }

  void Setup(const PlanningProblem& problem) override {
    Clear();
    problem_ = problem;
    const ParameterValues params = ResolveParameters(spec_, problem.parameters);
    const RobotModel& robot = problem.checker->robot();
    const int n = robot.num_dofs();

    auto space = std::make_shared<JointSpace>(n, problem.seed);
    ob::RealVectorBounds bounds(n);
    for (int i = 0; i < n; ++i) {
      bounds.setLow(i, robot.lower_limits()[i]);
      bounds.setHigh(i, robot.upper_limits()[i]);
    }
    space->setBounds(bounds);
    si_ = std::make_shared<ob::SpaceInformation>(space);
    si_->setStateValidityChecker(std::make_shared<ValidityChecker>(si_, problem.checker, &checks_));
    si_->setMotionValidator(std::make_shared<MotionChecker>(si_, problem.checker, problem.max_step, &checks_));
    si_->setup();

    pdef_ = std::make_shared<ob::ProblemDefinition>(si_);
    ob::ScopedState<> start(space), goal(space);
    FromEigen(problem.start, start.get());
    FromEigen(problem.goal, goal.get());
    pdef_->addStartState(start);
    if (problem.additional_goals.empty()) {
      pdef_->setGoalState(goal, std::max(problem.goal_tolerance, 1e-9));
    } else {
      auto goals = std::make_shared<ob::GoalStates>(si_);
      goals->addState(goal);
      for (const Eigen::VectorXd& q : problem.additional_goals) {
        ob::ScopedState<> g(space);
        FromEigen(q, g.get());
        goals->addState(g);
      }
      goals->setThreshold(std::max(problem.goal_tolerance, 1e-9));
      pdef_->setGoal(goals);
    }
    auto objective = std::make_shared<SeededPathLengthObjective>(si_);
    if (!spec_.optimizing) {
      // Any path satisfies a first-solution planner; without this PRM keeps refining until
      // the budget ends (its objective's default threshold is never met).
      objective->setCostThreshold(ob::Cost(std::numeric_limits<double>::infinity()));
    }
    pdef_->setOptimizationObjective(objective);

    const std::uint32_t seed = MixSeed(problem.seed);
    max_iterations_ = static_cast<std::uint64_t>(params.count("max_iterations") ? params.at("max_iterations") : 0);
    switch (kind_) {
      case Kind::kPrm: {
        auto p = std::make_shared<SingleThreadPrm<og::PRM>>(si_, seed);
        p->setMaxNearestNeighbors(static_cast<unsigned>(params.at("max_nearest_neighbors")));
        planner_ = p;
        break;
      }
      case Kind::kPrmStar:
        planner_ = std::make_shared<SingleThreadPrm<og::PRMstar>>(si_, seed);
        break;
      case Kind::kLazyPrmStar: {
        auto p = std::make_shared<og::LazyPRMstar>(si_);
        if (params.at("range") > 0) p->setRange(params.at("range"));
        planner_ = p;
        break;
      }
      case Kind::kRrt: {
        auto p = std::make_shared<Seeded<og::RRT>>(si_, seed);
        if (params.at("range") > 0) p->setRange(params.at("range"));
        p->setGoalBias(params.at("goal_bias"));
        planner_ = p;
        break;
      }
      case Kind::kRrtStar:
      case Kind::kInformedRrtStar: {
        std::shared_ptr<og::RRTstar> p;
        if (kind_ == Kind::kRrtStar) {
          p = std::make_shared<Seeded<og::RRTstar>>(si_, seed);
        } else {
          p = std::make_shared<Seeded<og::InformedRRTstar>>(si_, seed);
        }
        if (params.at("range") > 0) p->setRange(params.at("range"));
        p->setGoalBias(params.at("goal_bias"));
        p->setRewireFactor(params.at("rewire_factor"));
        planner_ = p;
        break;
      }
      case Kind::kRrtConnect: {
        auto p = std::make_shared<Seeded<og::RRTConnect>>(si_, seed);
        if (params.at("range") > 0) p->setRange(params.at("range"));
        planner_ = p;
        break;
      }
      case Kind::kBitStar: {
        auto p = std::make_shared<og::BITstar>(si_, "kBITstar");  // k-nearest is the default mode
        p->setSamplesPerBatch(static_cast<unsigned>(params.at("samples_per_batch")));
        p->setRewireFactor(params.at("rewire_factor"));
        planner_ = p;
        break;
      }
    }
    planner_->setProblemDefinition(pdef_);
    planner_->setup();
  }

  PlannerResult Solve(const Termination& termination) override {
    PlannerResult result;
    if (!planner_) ThrowInvalid("planner '" + spec_.id + "': Solve() called before Setup()");
    const auto t0 = Termination::Clock::now();
    checks_.store(0);
    std::atomic<std::uint64_t> evaluations{0};
    const std::uint64_t max_iterations = max_iterations_;
    ob::PlannerTerminationCondition ptc([&termination, &evaluations, max_iterations] {
      if (max_iterations > 0 && evaluations.fetch_add(1, std::memory_order_relaxed) >= max_iterations) {
        return true;
      }
      return termination.ShouldStop();
    });
    const ob::PlannerStatus status = planner_->solve(ptc);
    result.solve_seconds = std::chrono::duration<double>(Termination::Clock::now() - t0).count();

    ob::PlannerData data(si_);
    planner_->getPlannerData(data);
    result.graph_states = data.numVertices();

    const bool exact = status == ob::PlannerStatus::EXACT_SOLUTION;
    const bool approximate = status == ob::PlannerStatus::APPROXIMATE_SOLUTION;
    if (exact || approximate) {
      auto* path = pdef_->getSolutionPath()->as<og::PathGeometric>();
      const int n = problem_.checker->robot().num_dofs();
      for (const ob::State* s : path->getStates()) {
        Eigen::VectorXd q;
        ToEigen(s, n, &q);
        result.path.push_back(std::move(q));
      }
    }
    if (exact) {
      FinishAtGoal(&result);
    } else if (approximate) {
      result.status = PlanStatus::kApproximateSolution;
      result.message = spec_.id + " found only an approximate solution, " +
                       std::to_string(pdef_->getSolutionDifference()) + " rad from the goal";
    } else {
      switch (termination.Reason()) {
        case StopReason::kCancelled:
          result.status = PlanStatus::kCancelled;
          result.message = "cancelled by the client";
          break;
        case StopReason::kDeadline:
          result.status = PlanStatus::kDeadlineExceeded;
          result.message = "the gRPC deadline passed before " + spec_.id + " found a path";
          break;
        default:
          result.status = PlanStatus::kNoSolution;
          result.message = spec_.id + " found no path within the budget (" +
                           std::to_string(result.solve_seconds) + " s, " +
                           std::to_string(result.graph_states) + " states)";
      }
    }
    result.state_checks = checks_.load();
    return result;
  }

  void Clear() override {
    if (planner_) planner_->clear();
    planner_.reset();
    pdef_.reset();
    si_.reset();
    checks_.store(0);
  }

 private:
  /// The goal test accepts states within the tolerance; the returned path ends exactly at
  /// the requested goal, so connect it when the last state is not the goal itself.
  void FinishAtGoal(PlannerResult* result) const {
    CheckCounters counters;
    const Eigen::VectorXd& last = result->path.back();
    // The goal state the path reached: the nearest of the acceptable ones.
    const Eigen::VectorXd* goal = &problem_.goal;
    for (const Eigen::VectorXd& g : problem_.additional_goals) {
      if ((g - last).norm() < (*goal - last).norm()) goal = &g;
    }
    if (last != *goal) {
      const bool connects = problem_.checker->certifies_motion()
                                ? problem_.checker->IsMotionCertified(last, *goal, &counters)
                                : problem_.checker->IsMotionValid(last, *goal, problem_.max_step, &counters);
      if (connects) {
        result->path.push_back(*goal);
      } else {
        result->status = PlanStatus::kApproximateSolution;
        result->message = spec_.id + " reached the goal region but the final connection to the exact goal collides";
        checks_.fetch_add(counters.state_checks);
        return;
      }
    }
    checks_.fetch_add(counters.state_checks);
    result->path.front() = problem_.start;  // bit-exact start
    result->status = PlanStatus::kExactSolution;
    result->message = spec_.id + " found a path with " + std::to_string(result->path.size()) + " waypoints";
  }

  Kind kind_;
  PlannerSpec spec_;
  PlanningProblem problem_;
  ob::SpaceInformationPtr si_;
  ob::ProblemDefinitionPtr pdef_;
  ob::PlannerPtr planner_;
  std::uint64_t max_iterations_ = 0;
  mutable std::atomic<std::uint64_t> checks_{0};
};

/// Every OMPL planner plans for arms, planar bodies and free flyers (a real vector space), and
/// for cars in OMPL's Dubins / Reeds–Shepp state spaces when the planner's assumptions hold:
/// roadmaps and BIT* join states in either direction, so they need a symmetric steering
/// function (Reeds–Shepp), not Dubins, whose curve from a to b is not the curve from b to a.
void Add(PlannerRegistry* registry, Kind kind, PlannerSpec spec) {
  const bool tree = kind == Kind::kRrt || kind == Kind::kRrtStar || kind == Kind::kInformedRrtStar ||
                    kind == Kind::kRrtConnect;
  spec.robot_kinds = {RobotKind::kArm, RobotKind::kPlanar, RobotKind::kFreeFlyer, RobotKind::kReedsSheppCar};
  if (tree) spec.robot_kinds.push_back(RobotKind::kDubinsCar);
  spec.refusal_reason = "its roadmap joins states in both directions, but a Dubins car's curve from a to b is not "
                        "the reverse of its curve from b to a";
  PlannerSpec copy = spec;
  registry->Register(std::move(spec), [kind, copy] { return std::make_unique<OmplPlanner>(kind, copy); });
}

}  // namespace

void RegisterOmplPlanners(PlannerRegistry* registry) {
  ompl::msg::setLogLevel(ompl::msg::LOG_WARN);
  Add(registry, Kind::kRrtConnect,
      {"rrt_connect", "RRT-Connect (OMPL): bidirectional RRT, returns at the first solution", false,
       {RangeParam()}});
  Add(registry, Kind::kRrt,
      {"rrt", "RRT (OMPL): single-tree rapidly-exploring random tree with goal bias", false,
       {RangeParam(), GoalBiasParam()}});
  Add(registry, Kind::kRrtStar,
      {"rrt_star", "RRT* (OMPL): asymptotically optimal RRT, refines path length until the budget ends", true,
       {RangeParam(), GoalBiasParam(), RewireParam(), IterationsParam()}});
  Add(registry, Kind::kInformedRrtStar,
      {"informed_rrt_star",
       "Informed RRT* (OMPL): RRT* that samples the ellipsoid that can still improve the path", true,
       {RangeParam(), GoalBiasParam(), RewireParam(), IterationsParam()}});
  Add(registry, Kind::kPrm,
      {"prm", "PRM (OMPL): probabilistic roadmap, k-nearest connections, returns at the first solution", false,
       {{"max_nearest_neighbors", "neighbours each new milestone tries to connect to [-]", ParameterType::kInt,
         10.0, 1.0, 1000.0}}});
  Add(registry, Kind::kPrmStar,
      {"prm_star", "PRM* (OMPL): asymptotically optimal roadmap, refines until the budget ends", true,
       {IterationsParam()}});
  Add(registry, Kind::kLazyPrmStar,
      {"lazy_prm_star",
       "LazyPRM* (OMPL): roadmap whose edges are collision-checked only on candidate paths; refines until the budget ends",
       true, {RangeParam(), IterationsParam()}});
  Add(registry, Kind::kBitStar,
      {"bit_star", "BIT* (OMPL): batch informed trees, anytime asymptotically optimal", true,
       {{"samples_per_batch", "states sampled per batch [-]", ParameterType::kInt, 100.0, 1.0, 100000.0},
        RewireParam(), IterationsParam()}});
}

}  // namespace chasles
