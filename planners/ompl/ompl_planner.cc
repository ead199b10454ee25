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

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <ompl/base/ConstrainedSpaceInformation.h>
#include <ompl/base/Constraint.h>
#include <ompl/base/MotionValidator.h>
#include <ompl/base/PlannerData.h>
#include <ompl/base/ProblemDefinition.h>
#include <ompl/base/ProjectionEvaluator.h>
#include <ompl/base/ScopedState.h>
#include <ompl/base/SpaceInformation.h>
#include <ompl/base/StateValidityChecker.h>
#include <ompl/base/goals/GoalSampleableRegion.h>
#include <ompl/base/goals/GoalStates.h>
#include <ompl/base/objectives/PathLengthOptimizationObjective.h>
#include <ompl/base/samplers/informed/RejectionInfSampler.h>
#include <ompl/base/spaces/DubinsStateSpace.h>
#include <ompl/base/spaces/RealVectorStateSpace.h>
#include <ompl/base/spaces/ReedsSheppStateSpace.h>
#include <ompl/base/spaces/constraint/ProjectedStateSpace.h>
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

/// Fraction of each path-constraint tolerance the planners aim for: the states they project
/// keep a margin (tolerance/5) for the chords between them, which the checker certifies against
/// the whole tolerance, and for the timing's blends.
constexpr double kConstraintShrink = 0.8;
/// The default range [rad] of a tree planner with path constraints in the joint space.
constexpr double kConstrainedRange = 0.5;

/// A seeded sampler whose samples are projected onto the path constraints (tightened by
/// kConstraintShrink); a sample that does not project is redrawn, up to 20 times (the last
/// draw is returned as it is: the validity checker rejects it).
class ProjectingSampler : public SeededSampler {
 public:
  ProjectingSampler(const ob::StateSpace* space, std::uint32_t seed, const PathConstraints* constraints)
      : SeededSampler(space, seed), constraints_(constraints) {}
  void sampleUniform(ob::State* state) override {
    for (int attempt = 0; attempt < 20; ++attempt) {
      SeededSampler::sampleUniform(state);
      if (Project(state)) return;
    }
  }
  void sampleUniformNear(ob::State* state, const ob::State* near, double distance) override {
    SeededSampler::sampleUniformNear(state, near, distance);
    Project(state);
  }
  void sampleGaussian(ob::State* state, const ob::State* mean, double std_dev) override {
    SeededSampler::sampleGaussian(state, mean, std_dev);
    Project(state);
  }

 private:
  bool Project(ob::State* state) const {
    double* v = state->as<ob::RealVectorStateSpace::StateType>()->values;
    const int n = constraints_->robot().num_dofs();
    Eigen::VectorXd q = Eigen::Map<const Eigen::VectorXd>(v, n);
    const bool ok = constraints_->Project(&q, kConstraintShrink);
    Eigen::Map<Eigen::VectorXd>(v, n) = q;
    return ok;
  }
  const PathConstraints* constraints_;
};

/// Joint space: a bounded real vector space whose samplers draw from the request seed (and,
/// with ProjectSamples, project their samples onto path constraints).
class JointSpace : public ob::RealVectorStateSpace {
 public:
  JointSpace(unsigned int dim, std::uint64_t seed) : ob::RealVectorStateSpace(dim), seed_(seed) {}
  /// Samplers allocated from now on project onto `constraints` (null: plain uniform samples),
  /// and so does interpolate: a tree's step towards a sample ends on the constraints too.
  void ProjectSamples(const PathConstraints* constraints) { project_onto_ = constraints; }
  /// With ProjectSamples: the straight interpolation projected onto the constraints, when that
  /// keeps at least half of the step's progress towards `to` (else the straight interpolation).
  /// The bound on progress matters: RRT-Connect extends towards the other tree in a loop that
  /// ends only when a step is trapped or arrives; projected steps that turned back would never end.
  void interpolate(const ob::State* from, const ob::State* to, double t, ob::State* state) const override {
    ob::RealVectorStateSpace::interpolate(from, to, t, state);
    if (project_onto_ == nullptr || t <= 0.0 || t >= 1.0) return;
    double* v = state->as<ob::RealVectorStateSpace::StateType>()->values;
    const int n = static_cast<int>(getDimension());
    const Eigen::Map<const Eigen::VectorXd> a(from->as<ob::RealVectorStateSpace::StateType>()->values, n);
    const Eigen::Map<const Eigen::VectorXd> b(to->as<ob::RealVectorStateSpace::StateType>()->values, n);
    Eigen::VectorXd q = Eigen::Map<const Eigen::VectorXd>(v, n);
    const double d = (b - a).norm();
    if (project_onto_->Project(&q, kConstraintShrink) && (b - q).norm() <= d - 0.5 * t * d) {
      Eigen::Map<Eigen::VectorXd>(v, n) = q;
    }
  }
  /// As constructed with `seed`: the next sampler draws what a new space's first would.
  void Reseed(std::uint64_t seed) {
    seed_ = seed;
    counter_ = 0;
  }
  ob::StateSamplerPtr allocDefaultStateSampler() const override {
    const std::uint32_t seed = MixSeed(seed_ + 0x100 + counter_++);
    if (project_onto_ != nullptr) return std::make_shared<ProjectingSampler>(this, seed, project_onto_);
    return std::make_shared<SeededSampler>(this, seed);
  }
  /// No default projection: none of the planners offered here uses one (OMPL's projection
  /// planners — KPIECE, SBL, EST — are not), and registering it made every setup sample the
  /// space to estimate its bounds, ~40% of a typical RRT-Connect plan on the Panda.
  void registerProjections() override {}

 private:
  std::uint64_t seed_;
  mutable std::atomic<std::uint64_t> counter_{0};
  const PathConstraints* project_onto_ = nullptr;
};

/// Path constraints as one OMPL constraint for its projected state space: F(q) = the norm of
/// the errors' excess over TightenedBounds(kConstraintShrink) (zero inside the tightened band, as
/// MoveIt's box constraints), projected by PathConstraints::Project.
class ExcessConstraint : public ob::Constraint {
 public:
  explicit ExcessConstraint(const PathConstraints* constraints)
      : ob::Constraint(static_cast<unsigned>(constraints->robot().num_dofs()), 1, 1e-8),
        constraints_(constraints),
        bounds_(constraints->TightenedBounds(kConstraintShrink)) {}
  void function(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> out) const override {
    thread_local Eigen::VectorXd q, e;
    q = x;
    constraints_->Errors(q, &e);
    out[0] = (e.cwiseAbs() - bounds_).cwiseMax(0.0).norm();
  }
  bool project(Eigen::Ref<Eigen::VectorXd> x) const override {
    thread_local Eigen::VectorXd q;
    q = x;
    const bool ok = constraints_->Project(&q, kConstraintShrink);
    x = q;
    return ok;
  }

 private:
  const PathConstraints* constraints_;
  Eigen::VectorXd bounds_;  // TightenedBounds(kConstraintShrink)
};

/// The first joint with fixed 0.1 rad cells: a projection for OMPL's wrapper spaces, whose
/// setup wraps the joint space's default projection unconditionally (and logs an error when
/// there is none). None of our planners uses it; it costs nothing to set up (no sampling).
class FirstJointProjection : public ob::ProjectionEvaluator {
 public:
  explicit FirstJointProjection(const ob::StateSpace* space) : ob::ProjectionEvaluator(space) {}
  unsigned int getDimension() const override { return 1; }
  void defaultCellSizes() override { cellSizes_.assign(1, 0.1); }
  void project(const ob::State* state, Eigen::Ref<Eigen::VectorXd> projection) const override {
    projection[0] = state->as<ob::RealVectorStateSpace::StateType>()->values[0];
  }
};

/// OMPL's projected state space with a bounded discrete geodesic and partial steps. OMPL 1.5's walks on while
/// each projected step gets any closer to the target, so where the constraints turn the steps
/// back (most of the way to a joint limit, or across the band) it took millions of tiny steps —
/// seconds per RRT extension. Here a step must bring the target at least a tenth of delta
/// closer, and the walk stops after λ·distance/delta steps (a geodesic no longer than λ times the
/// straight distance, OMPL's own bound on its length).
class BoundedProjectedSpace : public ob::ProjectedStateSpace {
 public:
  using ob::ProjectedStateSpace::ProjectedStateSpace;

  bool discreteGeodesic(const ob::State* from, const ob::State* to, bool interpolate = false,
                        std::vector<ob::State*>* geodesic = nullptr) const override {
    if (geodesic != nullptr) {
      geodesic->clear();
      geodesic->push_back(cloneState(from));
    }
    double dist = distance(from, to);
    if (dist <= delta_) {
      if (geodesic != nullptr && dist > 0.0) geodesic->push_back(cloneState(to));
      return true;
    }
    const int max_steps = static_cast<int>(std::ceil(lambda_ * dist / delta_)) + 1;
    ob::State* previous = cloneState(from);
    ob::State* scratch = allocState();
    const auto& validity = si_->getStateValidityChecker();
    bool reached = false;
    for (int k = 0; k < max_steps && !reached; ++k) {
      WrapperStateSpace::interpolate(previous, to, std::min(1.0, delta_ / dist), scratch);
      if (!constraint_->project(scratch) || !(interpolate || validity->isValid(scratch))) break;
      if (distance(previous, scratch) > lambda_ * delta_) break;  // the projection jumped
      const double next = distance(scratch, to);
      if (next > dist - 0.1 * std::min(delta_, dist)) break;  // no real progress
      dist = next;
      copyState(previous, scratch);
      if (geodesic != nullptr) geodesic->push_back(cloneState(scratch));
      reached = dist <= delta_;
    }
    if (reached && geodesic != nullptr) geodesic->push_back(cloneState(to));
    freeState(previous);
    freeState(scratch);
    return reached;
  }
  /// The state a fraction t of the way from `from` to `to`. OMPL 1.5 returns `from` itself when
  /// the geodesic does not reach `to`, so a tree never grew towards a sample it could not reach
  /// all the way; here it grows as far as the geodesic got (the state at t·distance along it,
  /// or its last).
  void interpolate(const ob::State* from, const ob::State* to, double t, ob::State* state) const override {
    std::vector<ob::State*> geodesic;
    if (discreteGeodesic(from, to, true, &geodesic)) {
      copyState(state, geodesicInterpolate(geodesic, t));
    } else {
      const double want = t * distance(from, to);
      double walked = 0.0;
      std::size_t k = 0;
      for (; k + 1 < geodesic.size(); ++k) {
        const double step = distance(geodesic[k], geodesic[k + 1]);
        if (walked + step > want) break;
        walked += step;
      }
      copyState(state, geodesic.empty() ? from : geodesic[k]);
    }
    for (ob::State* g : geodesic) freeState(g);
  }
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

constexpr double kPi = 3.14159265358979323846;

/// x into (-π, π].
double WrapAngle(double x) {
  x = std::remainder(x, 2.0 * kPi);
  return x <= -kPi ? x + 2.0 * kPi : x;
}

/// How OMPL states map to configuration vectors: a real vector state is the configuration; a
/// car's SE(2) state (x, y, yaw) is (x, y, θ) with θ = yaw in (-π, π] (callers unwrap paths).
struct StateMap {
  int n = 0;
  bool se2 = false;
  bool constrained = false;  ///< states of a ProjectedStateSpace over the joint space

  void ToEigen(const ob::State* state, Eigen::VectorXd* q) const {
    q->resize(n);
    if (constrained) {
      *q = *state->as<ob::ConstrainedStateSpace::StateType>();
      return;
    }
    if (se2) {
      const auto* s = state->as<ob::SE2StateSpace::StateType>();
      (*q)[0] = s->getX();
      (*q)[1] = s->getY();
      (*q)[2] = s->getYaw();
      return;
    }
    const double* v = state->as<ob::RealVectorStateSpace::StateType>()->values;
    for (int i = 0; i < n; ++i) (*q)[i] = v[i];
  }
  void FromEigen(const Eigen::VectorXd& q, ob::State* state) const {
    if (constrained) {
      state->as<ob::ConstrainedStateSpace::StateType>()->copy(q);
      return;
    }
    if (se2) {
      auto* s = state->as<ob::SE2StateSpace::StateType>();
      s->setXY(q[0], q[1]);
      s->setYaw(WrapAngle(q[2]));
      return;
    }
    double* v = state->as<ob::RealVectorStateSpace::StateType>()->values;
    for (int i = 0; i < q.size(); ++i) v[i] = q[i];
  }
};

/// Uniform SE(2) samples (x, y in the bounds, yaw in [-π, π)) from the request seed; OMPL's
/// compound sampler would give each component a generator seeded from the clock.
class SeededSe2Sampler : public ob::StateSampler {
 public:
  SeededSe2Sampler(const ob::StateSpace* space, std::uint32_t seed) : ob::StateSampler(space) {
    rng_.setLocalSeed(seed);
  }
  void sampleUniform(ob::State* state) override {
    const ob::RealVectorBounds& b = space_->as<ob::SE2StateSpace>()->getBounds();
    auto* s = state->as<ob::SE2StateSpace::StateType>();
    s->setXY(rng_.uniformReal(b.low[0], b.high[0]), rng_.uniformReal(b.low[1], b.high[1]));
    s->setYaw(rng_.uniformReal(-kPi, kPi));
  }
  void sampleUniformNear(ob::State* state, const ob::State* near, double distance) override {
    const ob::RealVectorBounds& b = space_->as<ob::SE2StateSpace>()->getBounds();
    const auto* c = near->as<ob::SE2StateSpace::StateType>();
    auto* s = state->as<ob::SE2StateSpace::StateType>();
    s->setXY(std::clamp(rng_.uniformReal(c->getX() - distance, c->getX() + distance), b.low[0], b.high[0]),
             std::clamp(rng_.uniformReal(c->getY() - distance, c->getY() + distance), b.low[1], b.high[1]));
    s->setYaw(WrapAngle(rng_.uniformReal(c->getYaw() - distance, c->getYaw() + distance)));
  }
  void sampleGaussian(ob::State* state, const ob::State* mean, double std_dev) override {
    const ob::RealVectorBounds& b = space_->as<ob::SE2StateSpace>()->getBounds();
    const auto* c = mean->as<ob::SE2StateSpace::StateType>();
    auto* s = state->as<ob::SE2StateSpace::StateType>();
    s->setXY(std::clamp(rng_.gaussian(c->getX(), std_dev), b.low[0], b.high[0]),
             std::clamp(rng_.gaussian(c->getY(), std_dev), b.low[1], b.high[1]));
    s->setYaw(WrapAngle(rng_.gaussian(c->getYaw(), std_dev)));
  }
};

/// A car's state space (OMPL's Dubins or Reeds–Shepp SE(2) space) with seeded samplers.
template <class Base>
class CarSpace : public Base {
 public:
  CarSpace(double turning_radius, std::uint64_t seed) : Base(turning_radius), seed_(seed) {}
  ob::StateSamplerPtr allocDefaultStateSampler() const override {
    return std::make_shared<SeededSe2Sampler>(this, MixSeed(seed_ + 0x100 + counter_++));
  }

 private:
  std::uint64_t seed_;
  mutable std::atomic<std::uint64_t> counter_{0};
};

class ValidityChecker : public ob::StateValidityChecker {
 public:
  ValidityChecker(const ob::SpaceInformationPtr& si, std::shared_ptr<const CollisionChecker> checker,
                  StateMap map, std::atomic<std::uint64_t>* checks)
      : ob::StateValidityChecker(si), checker_(std::move(checker)), map_(map), checks_(checks) {}
  bool isValid(const ob::State* state) const override {
    thread_local Eigen::VectorXd q;
    map_.ToEigen(state, &q);
    checks_->fetch_add(1, std::memory_order_relaxed);
    return checker_->IsValid(q);
  }

 private:
  std::shared_ptr<const CollisionChecker> checker_;
  StateMap map_;
  std::atomic<std::uint64_t>* checks_;
};

/// Motion validation delegated to the checker: certified (no state on the segment collides)
/// when checker->certifies_motion(), otherwise discrete at the request's resolution.
class MotionChecker : public ob::MotionValidator {
 public:
  MotionChecker(const ob::SpaceInformationPtr& si, std::shared_ptr<const CollisionChecker> checker,
                double max_step, StateMap map, std::atomic<std::uint64_t>* checks)
      : ob::MotionValidator(si), checker_(std::move(checker)), max_step_(max_step), map_(map), checks_(checks) {}

  bool checkMotion(const ob::State* s1, const ob::State* s2) const override {
    thread_local Eigen::VectorXd a, b;
    map_.ToEigen(s1, &a);
    map_.ToEigen(s2, &b);
    CheckCounters counters;
    const bool ok = checker_->IsMotionFree(a, b, max_step_, &counters);
    checks_->fetch_add(counters.state_checks, std::memory_order_relaxed);
    ok ? ++valid_ : ++invalid_;
    return ok;
  }

  /// Walks s1 → s2 in order and reports the last valid state and its fraction.
  bool checkMotion(const ob::State* s1, const ob::State* s2,
                   std::pair<ob::State*, double>& last_valid) const override {
    thread_local Eigen::VectorXd a, b, q;
    map_.ToEigen(s1, &a);
    map_.ToEigen(s2, &b);
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
          map_.FromEigen(Eigen::VectorXd(a + s_last * (b - a)), last_valid.first);
        }
        last_valid.second = s_last;
        ++invalid_;
        return false;
      }
    }
    if (checker_->certifies_motion()) {
      // Every sample is valid but the certified check rejected the segment (a contact between
      // samples, or a graze): keep only a.
      if (last_valid.first != nullptr) map_.FromEigen(a, last_valid.first);
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
  StateMap map_;
  std::atomic<std::uint64_t>* checks_;
};

/// Motions in OMPL's projected state space (path constraints): the discrete geodesic from s1
/// towards s2 (steps of the space's delta, each projected onto the tightened constraints) must
/// reach s2, and each chord between its consecutive states must pass the checker — certified,
/// with the constraints over the whole chord, when checker->certifies_motion(). The returned
/// path is made of the same chords (GeodesicStates), so what was checked is what is returned.
class GeodesicMotionChecker : public ob::MotionValidator {
 public:
  GeodesicMotionChecker(const ob::SpaceInformationPtr& si, std::shared_ptr<const CollisionChecker> checker,
                        double max_step, StateMap map, std::atomic<std::uint64_t>* checks)
      : ob::MotionValidator(si), checker_(std::move(checker)), max_step_(max_step), map_(map), checks_(checks) {}

  bool checkMotion(const ob::State* s1, const ob::State* s2) const override {
    std::pair<ob::State*, double> unused(nullptr, 0.0);
    return checkMotion(s1, s2, unused);
  }

  bool checkMotion(const ob::State* s1, const ob::State* s2,
                   std::pair<ob::State*, double>& last_valid) const override {
    std::vector<Eigen::VectorXd> states;
    bool ok = GeodesicStates(*si_, map_, s1, s2, &states);
    std::size_t k = 0;
    for (; ok && k + 1 < states.size(); ++k) {
      CheckCounters counters;
      ok = checker_->IsMotionFree(states[k], states[k + 1], max_step_, &counters);
      checks_->fetch_add(counters.state_checks, std::memory_order_relaxed);
      if (!ok) break;
    }
    if (!ok) {
      if (last_valid.first != nullptr) {
        if (states.empty()) {
          si_->copyState(last_valid.first, s1);
        } else {
          map_.FromEigen(states[k], last_valid.first);
        }
      }
      last_valid.second = states.size() > 1 ? static_cast<double>(k) / static_cast<double>(states.size() - 1) : 0.0;
    }
    ok ? ++valid_ : ++invalid_;
    return ok;
  }

  /// The states of the discrete geodesic s1 → s2 (s1 first, s2 last) in *states; false when it
  /// does not reach s2 (*states then holds how far it got).
  static bool GeodesicStates(const ob::SpaceInformation& si, const StateMap& map, const ob::State* s1,
                             const ob::State* s2, std::vector<Eigen::VectorXd>* states) {
    const auto& space = *si.getStateSpace()->as<BoundedProjectedSpace>();
    std::vector<ob::State*> geodesic;
    const bool reached = space.discreteGeodesic(s1, s2, true, &geodesic);
    states->clear();
    for (ob::State* g : geodesic) {
      Eigen::VectorXd q;
      map.ToEigen(g, &q);
      states->push_back(std::move(q));
      space.freeState(g);
    }
    return reached;  // BoundedProjectedSpace's geodesic starts at s1 and, reached, ends at s2
  }

 private:
  std::shared_ptr<const CollisionChecker> checker_;
  double max_step_;
  StateMap map_;
  std::atomic<std::uint64_t>* checks_;
};

/// A car's motions follow its Dubins / Reeds–Shepp curve: states along the curve no more than
/// `max_step` apart (in metres of arc and radians of heading) must be valid.
class CarMotionChecker : public ob::MotionValidator {
 public:
  CarMotionChecker(const ob::SpaceInformationPtr& si, std::shared_ptr<const CollisionChecker> checker,
                   double max_step, double turning_radius, StateMap map, std::atomic<std::uint64_t>* checks)
      : ob::MotionValidator(si),
        checker_(std::move(checker)),
        step_(max_step * std::min(1.0, turning_radius)),  // heading changes by at most arc / radius
        map_(map),
        checks_(checks) {}

  bool checkMotion(const ob::State* s1, const ob::State* s2) const override {
    std::pair<ob::State*, double> unused(nullptr, 0.0);
    return checkMotion(s1, s2, unused);
  }

  bool checkMotion(const ob::State* s1, const ob::State* s2,
                   std::pair<ob::State*, double>& last_valid) const override {
    thread_local Eigen::VectorXd q;
    const int steps = std::max(1, static_cast<int>(std::ceil(si_->distance(s1, s2) / step_)));
    ob::State* s = si_->allocState();
    bool ok = true;
    for (int k = 1; k <= steps && ok; ++k) {
      si_->getStateSpace()->interpolate(s1, s2, static_cast<double>(k) / steps, s);
      map_.ToEigen(s, &q);
      checks_->fetch_add(1, std::memory_order_relaxed);
      if (!checker_->IsValid(q)) {
        ok = false;
        const double t_last = static_cast<double>(k - 1) / steps;
        if (last_valid.first != nullptr) si_->getStateSpace()->interpolate(s1, s2, t_last, last_valid.first);
        last_valid.second = t_last;
      }
    }
    si_->freeState(s);
    ok ? ++valid_ : ++invalid_;
    return ok;
  }

 private:
  std::shared_ptr<const CollisionChecker> checker_;
  double step_;
  StateMap map_;
  std::atomic<std::uint64_t>* checks_;
};

/// Seeds a planner's own RNG (goal bias, random walks) from the request seed.
template <class P>
class Seeded : public P {
 public:
  Seeded(const ob::SpaceInformationPtr& si, std::uint32_t seed) : P(si) { Reseed(seed); }
  /// As constructed with `seed`.
  void Reseed(std::uint32_t seed) { this->rng_.setLocalSeed(seed); }
};

/// RRT-Connect that counts its trees' states itself. getPlannerData copies every state and edge
/// into a graph only for the count: ~20 µs of a 0.3 ms Panda plan, and its vertices are exactly
/// the two trees' motions (the connection adds an edge between states already in them).
class CountedRrtConnect : public Seeded<og::RRTConnect> {
 public:
  using Seeded<og::RRTConnect>::Seeded;
  std::size_t TreeStates() const { return (tStart_ ? tStart_->size() : 0) + (tGoal_ ? tGoal_->size() : 0); }
};

/// A thread's last RRT-Connect and its joint space, kept for the next request with the same
/// joint bounds and range. Building them (space, space information, planner and its two
/// nearest-neighbour trees) took ~45 µs of a ~0.3 ms Panda plan, most of it in code and memory
/// the rest of a request had evicted from the caches. Kept between requests: no tree states
/// (clear() frees them), no checker (its validity checker and motion validator are dropped).
/// Reused, both are reseeded, so a request draws exactly what it would from new ones.
struct ReusableRrtConnect {
  Eigen::VectorXd lower, upper;  // the joint bounds
  double range = 0.0;            // the resolved range parameter (0 = OMPL's default)
  std::shared_ptr<JointSpace> space;
  ob::SpaceInformationPtr si;
  std::shared_ptr<CountedRrtConnect> planner;

  bool Fits(const RobotModel& robot, double r) const {
    return r == range && lower.size() == robot.num_dofs() && lower == robot.lower_limits() &&
           upper == robot.upper_limits();
  }
};
thread_local std::unique_ptr<ReusableRrtConnect> t_reusable_rrt_connect;

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
  return {"range",
          "maximum length of a tree extension (Euclidean joint distance) [rad]; 0 = 20% of the joint-space diagonal "
          "(0.5 rad with path constraints, unless constrained_space)",
          ParameterType::kDouble, 0.0, 0.0, 100.0};
}
ParameterSpec GoalBiasParam() {
  return {"goal_bias", "probability of sampling the goal [-]", ParameterType::kDouble, 0.05, 0.0, 1.0};
}
ParameterSpec RewireParam() {
  return {"rewire_factor", "multiplier of the optimal rewiring radius / neighbour count [-]",
          ParameterType::kDouble, 1.1, 1.0, 10.0};
}
ParameterSpec ConstrainedSpaceParam() {
  return {"constrained_space",
          "with path constraints: 0 = plan in the joint space with samples projected onto them (straight steps, "
          "certified within the tolerances; the default: it solved 20/20 carry-a-glass problems where the projected "
          "space solved 6, docs/benchmarks.md), 1 = plan in OMPL's projected state space (every step projected); "
          "ignored without path constraints",
          ParameterType::kBool, 0.0, 0.0, 1.0};
}
ParameterSpec ConstraintDeltaParam() {
  return {"constraint_delta",
          "with path constraints in the projected space: the step along the constraints between projected states "
          "(Euclidean joint distance) [rad]",
          ParameterType::kDouble, 0.05, 0.001, 1.0};
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
  // OMPL 1.5.2's ~LazyPRM() is defaulted and frees none of its roadmap's states (fixed upstream
  // by ompl/ompl#909 for issue #833): without clear() first, every lazy_prm_star solve leaked its
  // roadmap. Clear() frees the states of any planner.
  ~OmplPlanner() override { Clear(); }

  const PlannerSpec& spec() const override { return spec_; }

  void Setup(const PlanningProblem& problem) override {
    Clear();
    problem_ = problem;
    const ParameterValues params = ResolveParameters(spec_, problem.parameters);
    const RobotModel& robot = problem.checker->robot();
    CheckRobotKind(spec_, robot);
    const int n = robot.num_dofs();

    map_.n = n;
    map_.se2 = IsCar(robot.kind());
    const PathConstraints* constraints = problem.checker->path_constraints();
    if (constraints != nullptr && map_.se2) {
      ThrowInvalid("path_constraints: planner '" + spec_.id + "' plans a car's path along its curves, which cannot "
                   "follow path constraints; plan for a car without them");
    }
    const bool projected_space = constraints != nullptr && params.at("constrained_space") != 0.0;
    map_.constrained = projected_space;
    // Projected samples take short steps unless told otherwise: a straight step of 20 % of the
    // joint-space diagonal leaves a thin band (chasles-bench --section constraints).
    const double range = params.count("range") == 0         ? 0.0
                         : params.at("range") > 0.0          ? params.at("range")
                         : constraints != nullptr && !projected_space ? kConstrainedRange
                                                                      : 0.0;
    const std::uint32_t seed = MixSeed(problem.seed);
    max_iterations_ = static_cast<std::uint64_t>(params.count("max_iterations") ? params.at("max_iterations") : 0);
    if (kind_ == Kind::kRrtConnect && !map_.se2 && constraints == nullptr && t_reusable_rrt_connect &&
        t_reusable_rrt_connect->Fits(robot, params.at("range"))) {
      reused_ = std::move(t_reusable_rrt_connect);
      reused_->space->Reseed(problem.seed);
      reused_->planner->Reseed(seed);
      si_ = reused_->si;
      AttachChecker(problem);
      DefineProblem(problem);
      planner_ = reused_->planner;
      rrt_connect_ = reused_->planner.get();
      planner_->setProblemDefinition(pdef_);  // already set up: range and trees as before
      return;
    }
    ob::StateSpacePtr space;
    if (map_.se2) {
      // A car: OMPL's SE(2) curve spaces over the workspace bounds of (x, y); the heading is an
      // SO(2) angle there (its joint range only bounds the unwrapped path).
      const double rho = robot.motion().turning_radius;
      std::shared_ptr<ob::SE2StateSpace> se2;
      if (robot.kind() == RobotKind::kDubinsCar) {
        se2 = std::make_shared<CarSpace<ob::DubinsStateSpace>>(rho, problem.seed);
      } else {
        se2 = std::make_shared<CarSpace<ob::ReedsSheppStateSpace>>(rho, problem.seed);
      }
      ob::RealVectorBounds bounds(2);
      for (int i = 0; i < 2; ++i) {
        bounds.setLow(i, robot.lower_limits()[i]);
        bounds.setHigh(i, robot.upper_limits()[i]);
      }
      se2->setBounds(bounds);
      space = se2;
    } else {
      auto joints = std::make_shared<JointSpace>(n, problem.seed);
      ob::RealVectorBounds bounds(n);
      for (int i = 0; i < n; ++i) {
        bounds.setLow(i, robot.lower_limits()[i]);
        bounds.setHigh(i, robot.upper_limits()[i]);
      }
      joints->setBounds(bounds);
      space = joints;
      if (constraints != nullptr && !projected_space) joints->ProjectSamples(constraints);
    }
    if (projected_space) {
      // OMPL's projected state space over the joint space: samples and steps (delta) projected
      // onto the tightened constraints; ConstrainedSpaceInformation ties the space to si_.
      space->registerDefaultProjection(std::make_shared<FirstJointProjection>(space.get()));
      auto projected = std::make_shared<BoundedProjectedSpace>(space, std::make_shared<ExcessConstraint>(constraints));
      projected->setDelta(params.at("constraint_delta"));
      space = projected;
      si_ = std::make_shared<ob::ConstrainedSpaceInformation>(projected);
    } else {
      si_ = std::make_shared<ob::SpaceInformation>(space);
    }
    AttachChecker(problem);
    DefineProblem(problem);

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
        if (range > 0) p->setRange(range);
        planner_ = p;
        break;
      }
      case Kind::kRrt: {
        auto p = std::make_shared<Seeded<og::RRT>>(si_, seed);
        if (range > 0) p->setRange(range);
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
        if (range > 0) p->setRange(range);
        p->setGoalBias(params.at("goal_bias"));
        p->setRewireFactor(params.at("rewire_factor"));
        planner_ = p;
        break;
      }
      case Kind::kRrtConnect: {
        auto p = std::make_shared<CountedRrtConnect>(si_, seed);
        if (range > 0) p->setRange(range);
        rrt_connect_ = p.get();
        if (!map_.se2 && constraints == nullptr) {  // kept for the thread's next request (a car's SE(2) space is built anew)
          reused_ = std::make_unique<ReusableRrtConnect>(
              ReusableRrtConnect{robot.lower_limits(), robot.upper_limits(), params.at("range"),
                                 std::static_pointer_cast<JointSpace>(space), si_, p});
        }
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

    if (rrt_connect_ != nullptr) {
      result.graph_states = rrt_connect_->TreeStates();
    } else {
      ob::PlannerData data(si_);
      planner_->getPlannerData(data);
      result.graph_states = data.numVertices();
    }

    const bool exact = status == ob::PlannerStatus::EXACT_SOLUTION;
    const bool approximate = status == ob::PlannerStatus::APPROXIMATE_SOLUTION;
    if (exact && map_.se2) {
      FinishCarPath(*pdef_->getSolutionPath()->as<og::PathGeometric>(), &result);
    } else if (exact && map_.constrained) {
      // Consecutive states are joined by discrete geodesics, whose chords the motion checks
      // certified: return those chords' states.
      const std::vector<ob::State*>& states = pdef_->getSolutionPath()->as<og::PathGeometric>()->getStates();
      map_.ToEigen(states.front(), &result.path.emplace_back());
      for (std::size_t k = 0; k + 1 < states.size(); ++k) {
        std::vector<Eigen::VectorXd> geodesic;
        GeodesicMotionChecker::GeodesicStates(*si_, map_, states[k], states[k + 1], &geodesic);
        result.path.insert(result.path.end(), geodesic.begin() + 1, geodesic.end());
      }
      FinishAtGoal(&result);
    } else if (exact) {
      for (const ob::State* s : pdef_->getSolutionPath()->as<og::PathGeometric>()->getStates()) {
        Eigen::VectorXd q;
        map_.ToEigen(s, &q);
        result.path.push_back(std::move(q));
      }
      FinishAtGoal(&result);
    } else if (approximate) {
      for (const ob::State* s : pdef_->getSolutionPath()->as<og::PathGeometric>()->getStates()) {
        Eigen::VectorXd q;
        map_.ToEigen(s, &q);
        result.path.push_back(std::move(q));
      }
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
    if (reused_) {
      // Back to the thread for its next request, without this request's checker.
      si_->setStateValidityChecker(ob::StateValidityCheckerPtr());
      si_->setMotionValidator(ob::MotionValidatorPtr());
      t_reusable_rrt_connect = std::move(reused_);
    }
    reused_.reset();
    rrt_connect_ = nullptr;
    planner_.reset();
    pdef_.reset();
    si_.reset();
    checks_.store(0);
  }

 private:
  /// Validity and motion checks of si_ by the problem's checker; sets si_ up.
  void AttachChecker(const PlanningProblem& problem) {
    si_->setStateValidityChecker(std::make_shared<ValidityChecker>(si_, problem.checker, map_, &checks_));
    if (map_.constrained) {
      si_->setMotionValidator(
          std::make_shared<GeodesicMotionChecker>(si_, problem.checker, problem.max_step, map_, &checks_));
    } else if (map_.se2) {
      si_->setMotionValidator(std::make_shared<CarMotionChecker>(si_, problem.checker, problem.max_step,
                                                                 problem.checker->robot().motion().turning_radius,
                                                                 map_, &checks_));
    } else {
      si_->setMotionValidator(std::make_shared<MotionChecker>(si_, problem.checker, problem.max_step, map_, &checks_));
    }
    si_->setup();
  }

  /// pdef_: the problem's start, goal(s) and path-length objective on si_.
  void DefineProblem(const PlanningProblem& problem) {
    const ob::StateSpacePtr& space = si_->getStateSpace();
    pdef_ = std::make_shared<ob::ProblemDefinition>(si_);
    ob::ScopedState<> start(space), goal(space);
    map_.FromEigen(problem.start, start.get());
    map_.FromEigen(problem.goal, goal.get());
    pdef_->addStartState(start);
    if (problem.additional_goals.empty()) {
      pdef_->setGoalState(goal, std::max(problem.goal_tolerance, 1e-9));
    } else {
      auto goals = std::make_shared<ob::GoalStates>(si_);
      goals->addState(goal);
      for (const Eigen::VectorXd& q : problem.additional_goals) {
        ob::ScopedState<> g(space);
        map_.FromEigen(q, g.get());
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
  }

  /// A car's path: its states joined by the car's curves. Connects the exact goal along a curve,
  /// drops states the curves can skip (greedy: from each kept state the farthest state joined by a
  /// valid curve), then samples each curve into chords (every 5 degrees of heading, halved until
  /// the chord itself is a valid straight motion or no longer than max_step) and unwraps the
  /// heading from the start's. Later stages must keep this shape (keep_path_shape).
  void FinishCarPath(og::PathGeometric& solved, PlannerResult* result) const {
    std::vector<ob::State*> states;
    for (const ob::State* s : solved.getStates()) states.push_back(si_->cloneState(s));
    const auto free_states = [this, &states] {
      for (ob::State* s : states) si_->freeState(s);
    };
    // The exact goal: the nearest acceptable one, joined along a curve.
    std::vector<Eigen::VectorXd> goals = problem_.additional_goals;
    goals.insert(goals.begin(), problem_.goal);
    Eigen::VectorXd last;
    map_.ToEigen(states.back(), &last);
    const Eigen::VectorXd* goal = &goals.front();
    ob::State* goal_state = si_->allocState();
    double best = std::numeric_limits<double>::infinity();
    for (const Eigen::VectorXd& g : goals) {
      map_.FromEigen(g, goal_state);
      const double d = si_->distance(states.back(), goal_state);
      if (d < best) {
        best = d;
        goal = &g;
      }
    }
    map_.FromEigen(*goal, goal_state);
    if (best > 0.0) {
      if (!si_->checkMotion(states.back(), goal_state)) {
        si_->freeState(goal_state);
        free_states();
        result->status = PlanStatus::kApproximateSolution;
        result->message = spec_.id + " reached the goal region but the car's curve to the exact goal collides";
        return;
      }
      states.push_back(goal_state);
    } else {
      si_->freeState(states.back());
      states.back() = goal_state;
    }
    // Greedy vertex reduction along valid curves (deterministic).
    std::vector<ob::State*> kept = {states.front()};
    for (size_t i = 0; i + 1 < states.size();) {
      size_t j = states.size() - 1;
      while (j > i + 1 && !si_->checkMotion(states[i], states[j])) --j;
      kept.push_back(states[j]);
      i = j;
    }
    // Chords along each curve, heading unwrapped.
    constexpr double kChordHeading = 5.0 * kPi / 180.0;
    const CollisionChecker& checker = *problem_.checker;
    CheckCounters counters;
    result->path.clear();
    result->path.push_back(problem_.start);
    Eigen::VectorXd raw_prev = problem_.start, q;
    ob::State* s = si_->allocState();
    const auto add = [&](const ob::State* state) {
      map_.ToEigen(state, &q);
      const double raw = q[2];
      q[2] = result->path.back()[2] + WrapAngle(raw - raw_prev[2]);
      raw_prev = q;
      raw_prev[2] = raw;
      result->path.push_back(q);
    };
    for (size_t k = 0; k + 1 < kept.size(); ++k) {
      const ob::State* a = kept[k];
      const ob::State* b = kept[k + 1];
      // Stack of curve parameters still to reach, from the far end: each straight piece of the
      // curve whole, each arc every kChordHeading of heading (chords never straddle two pieces).
      std::vector<double> targets;
      const std::vector<std::pair<double, bool>> pieces = CurvePieces(a, b);
      double total = 0.0;
      for (const auto& piece : pieces) total += piece.first;
      double before = 0.0;
      std::vector<double> forward;
      for (const auto& [length, arc] : pieces) {
        const int cuts = arc ? std::max(1, static_cast<int>(std::ceil(length / kChordHeading))) : 1;
        for (int i = 1; i <= cuts; ++i) forward.push_back((before + length * i / cuts) / total);
        before += length;
      }
      if (forward.empty()) forward.push_back(1.0);
      forward.back() = 1.0;
      targets.assign(forward.rbegin(), forward.rend());
      double t_done = 0.0;
      while (!targets.empty()) {
        const double t = targets.back();
        si_->getStateSpace()->interpolate(a, b, t, s);
        Eigen::VectorXd from = result->path.back(), to;
        map_.ToEigen(s, &to);
        to[2] = from[2] + WrapAngle(to[2] - raw_prev[2]);
        const bool short_chord = (to - from).cwiseAbs().maxCoeff() <= problem_.max_step;
        const bool chord_ok = short_chord || (checker.certifies_motion()
                                                  ? checker.IsMotionCertified(from, to, &counters)
                                                  : checker.IsMotionValid(from, to, problem_.max_step, &counters));
        if (chord_ok) {
          add(s);
          targets.pop_back();
          t_done = t;
        } else {
          targets.push_back(0.5 * (t_done + t));
        }
      }
    }
    si_->freeState(s);
    checks_.fetch_add(counters.state_checks);
    for (ob::State* st : kept) si_->freeState(st);
    for (ob::State* st : states) {
      if (std::find(kept.begin(), kept.end(), st) == kept.end()) si_->freeState(st);
    }
    // The last state is the goal: exact x, y; the heading equals the goal's modulo 2π.
    Eigen::VectorXd& end = result->path.back();
    end[0] = (*goal)[0];
    end[1] = (*goal)[1];
    if (std::abs(WrapAngle(end[2] - (*goal)[2])) < 1e-9) end[2] = (*goal)[2] + std::round((end[2] - (*goal)[2]) / (2 * kPi)) * 2 * kPi;
    RemoveCollinear(&result->path);
    result->keep_path_shape = true;
    result->status = PlanStatus::kExactSolution;
    result->message = spec_.id + " found a car path through " + std::to_string(kept.size()) +
                      " states, followed by " + std::to_string(result->path.size() - 1) + " chords";
  }

  /// The pieces of the car's shortest curve a → b: (length in turning radii — for an arc its turn
  /// in radians —, is an arc), in order; zero-length pieces left out.
  std::vector<std::pair<double, bool>> CurvePieces(const ob::State* a, const ob::State* b) const {
    std::vector<std::pair<double, bool>> pieces;
    const auto add = [&pieces](double length, bool arc) {
      if (std::abs(length) > 1e-12) pieces.emplace_back(std::abs(length), arc);
    };
    if (const auto* dubins = dynamic_cast<const ob::DubinsStateSpace*>(si_->getStateSpace().get())) {
      const ob::DubinsStateSpace::DubinsPath path = dubins->dubins(a, b);
      for (int i = 0; i < 3; ++i) add(path.length_[i], path.type_[i] != ob::DubinsStateSpace::DUBINS_STRAIGHT);
    } else {
      const auto* rs = si_->getStateSpace()->as<ob::ReedsSheppStateSpace>();
      const ob::ReedsSheppStateSpace::ReedsSheppPath path = rs->reedsShepp(a, b);
      for (int i = 0; i < 5 && path.type_[i] != ob::ReedsSheppStateSpace::RS_NOP; ++i) {
        add(path.length_[i], path.type_[i] != ob::ReedsSheppStateSpace::RS_STRAIGHT);
      }
    }
    return pieces;
  }

  /// Drops waypoints that lie on the straight segment between their neighbours (a car's
  /// straight runs); the motion is unchanged.
  static void RemoveCollinear(JointPath* path) {
    if (path->size() < 3) return;
    JointPath out = {path->front()};
    for (size_t i = 1; i + 1 < path->size(); ++i) {
      const Eigen::VectorXd& a = out.back();
      const Eigen::VectorXd& b = (*path)[i];
      const Eigen::VectorXd& c = (*path)[i + 1];
      const Eigen::VectorXd ab = b - a, ac = c - a;
      const double t = ab.dot(ac) / std::max(ac.squaredNorm(), 1e-300);
      const bool on_segment = t > 0.0 && t < 1.0 && (ab - t * ac).norm() <= 1e-12 * std::max(1.0, ac.norm());
      if (!on_segment) out.push_back(b);
    }
    out.push_back(path->back());
    *path = std::move(out);
  }

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
  const CountedRrtConnect* rrt_connect_ = nullptr;  // planner_, when it is RRT-Connect
  std::unique_ptr<ReusableRrtConnect> reused_;      // its objects, to keep for the thread's next request
  std::uint64_t max_iterations_ = 0;
  StateMap map_;
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
  spec.parameters.push_back(ConstrainedSpaceParam());
  spec.parameters.push_back(ConstraintDeltaParam());
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
