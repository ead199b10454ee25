#include <algorithm>
#include <atomic>
#include <cmath>
#include <memory>
#include <utility>

#include <ompl/base/PlannerData.h>
#include <ompl/base/ProblemDefinition.h>
#include <ompl/base/SpaceInformation.h>
#include <ompl/base/spaces/RealVectorStateSpace.h>
#include <ompl/geometric/planners/prm/PRM.h>

#include "chasles/multi/space_time.h"
#include "chasles/robot/error.h"

namespace ob = ompl::base;
namespace og = ompl::geometric;

namespace chasles {
namespace {

/// SplitMix64 of the roadmap seed: OMPL's local RNG seeds are 32-bit and must not be 0.
std::uint32_t Mix(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  x ^= x >> 31;
  const auto s = static_cast<std::uint32_t>(x);
  return s == 0 ? 1u : s;
}

/// The robot's joint box, with samplers drawn from the roadmap's seed (one stream per sampler).
class SeededJointSpace : public ob::RealVectorStateSpace {
 public:
  SeededJointSpace(unsigned int dim, std::uint64_t seed) : ob::RealVectorStateSpace(dim), seed_(seed) {}
  ob::StateSamplerPtr allocDefaultStateSampler() const override {
    auto sampler = std::make_shared<ob::RealVectorStateSampler>(this);
    Reseed(sampler.get(), Mix(seed_ + 0x200 + counter_++));
    return sampler;
  }

 private:
  struct Access : ob::RealVectorStateSampler {
    using ob::RealVectorStateSampler::rng_;
  };
  static void Reseed(ob::RealVectorStateSampler* sampler, std::uint32_t seed) {
    (sampler->*(&Access::rng_)).setLocalSeed(seed);
  }
  std::uint64_t seed_;
  mutable std::atomic<std::uint64_t> counter_{0};
};

Eigen::VectorXd ToEigen(const ob::State* state, int n) {
  const auto* values = state->as<ob::RealVectorStateSpace::StateType>()->values;
  return Eigen::Map<const Eigen::VectorXd>(values, n);
}

/// Motions checked by the robot's checker: certified when it can, else at 0.005 rad steps.
class CheckerMotionValidator : public ob::MotionValidator {
 public:
  CheckerMotionValidator(const ob::SpaceInformationPtr& si, const CollisionChecker& checker)
      : ob::MotionValidator(si), checker_(checker), n_(checker.robot().num_dofs()) {}
  bool checkMotion(const ob::State* a, const ob::State* b) const override {
    return Valid(ToEigen(a, n_), ToEigen(b, n_));
  }
  bool checkMotion(const ob::State* a, const ob::State* b, std::pair<ob::State*, double>& last) const override {
    const bool ok = checkMotion(a, b);
    if (!ok) {
      if (last.first != nullptr) si_->copyState(last.first, a);
      last.second = 0.0;
    }
    return ok;
  }
  bool Valid(const Eigen::VectorXd& a, const Eigen::VectorXd& b) const {
    return checker_.IsMotionFree(a, b, 0.005);
  }

 private:
  const CollisionChecker& checker_;
  int n_;
};

/// OMPL's PRM with a seeded RNG, grown on demand (no solution search): its roadmap is ours.
class GrowingPrm : public og::PRM {
 public:
  GrowingPrm(const ob::SpaceInformationPtr& si, std::uint32_t seed) : og::PRM(si) { rng_.setLocalSeed(seed); }
  void Grow(const ob::PlannerTerminationCondition& ptc) {
    if (!sampler_) sampler_ = si_->allocValidStateSampler();
    ob::State* work = si_->allocState();
    growRoadmap(ptc, work);
    si_->freeState(work);
  }
};

}  // namespace

int Roadmap::AddVertex(const Eigen::VectorXd& q) {
  vertices.push_back(q);
  neighbors.emplace_back();
  return static_cast<int>(vertices.size()) - 1;
}

void Roadmap::AddEdge(int a, int b) {
  const int n = static_cast<int>(vertices.size());
  if (a < 0 || b < 0 || a >= n || b >= n) {
    ThrowInvalid("roadmap edge (" + std::to_string(a) + ", " + std::to_string(b) + ") names a vertex outside [0, " +
                 std::to_string(n) + ")");
  }
  if (a == b || std::find(neighbors[a].begin(), neighbors[a].end(), b) != neighbors[a].end()) return;
  neighbors[a].push_back(b);
  neighbors[b].push_back(a);
}

Roadmap BuildRoadmap(const CollisionChecker& checker, const std::vector<JointPath>& seed_paths,
                     const RoadmapOptions& options, const Termination& termination) {
  const RobotModel& robot = checker.robot();
  const int n = robot.num_dofs();
  if (seed_paths.empty() || seed_paths.front().empty()) ThrowInvalid("roadmap: the first seed path is empty");
  if (options.prm_vertices < 0) ThrowInvalid("roadmap prm_vertices = " + std::to_string(options.prm_vertices) + " must be >= 0");
  if (options.neighbors < 1) ThrowInvalid("roadmap neighbors = " + std::to_string(options.neighbors) + " must be >= 1");
  if (!(options.station_spacing > 0.0)) {
    ThrowInvalid("roadmap station_spacing = " + FormatNumber(options.station_spacing) + " must be > 0");
  }
  Roadmap coarse;
  // 1. The seed paths; equal configurations are one vertex.
  const auto find_or_add = [&coarse](const Eigen::VectorXd& q) {
    for (int v = 0; v < static_cast<int>(coarse.vertices.size()); ++v) {
      if ((coarse.vertices[v] - q).cwiseAbs().maxCoeff() <= 1e-12) return v;
    }
    return coarse.AddVertex(q);
  };
  for (std::size_t p = 0; p < seed_paths.size(); ++p) {
    int previous = -1;
    for (std::size_t k = 0; k < seed_paths[p].size(); ++k) {
      const Eigen::VectorXd& q = seed_paths[p][k];
      if (q.size() != n) {
        ThrowInvalid("roadmap seed path " + std::to_string(p) + " waypoint " + std::to_string(k) + " has " +
                     std::to_string(q.size()) + " values, robot '" + robot.name() + "' has " + std::to_string(n) +
                     " joints");
      }
      const int v = find_or_add(q);
      if (previous >= 0) coarse.AddEdge(previous, v);
      previous = v;
    }
  }
  const int seeds = static_cast<int>(coarse.vertices.size());

  // 2. OMPL's PRM over the joint box, its vertices and edges added, seed vertices linked to it.
  if (options.prm_vertices > 0 && !termination.ShouldStop()) {
    auto space = std::make_shared<SeededJointSpace>(n, options.seed);
    ob::RealVectorBounds bounds(n);
    for (int i = 0; i < n; ++i) {
      bounds.setLow(i, robot.lower_limits()[i]);
      bounds.setHigh(i, robot.upper_limits()[i]);
    }
    space->setBounds(bounds);
    auto si = std::make_shared<ob::SpaceInformation>(space);
    si->setStateValidityChecker([&checker, n](const ob::State* s) { return checker.IsValid(ToEigen(s, n)); });
    auto validator = std::make_shared<CheckerMotionValidator>(si, checker);
    si->setMotionValidator(validator);
    si->setup();
    auto problem = std::make_shared<ob::ProblemDefinition>(si);
    {
      ob::ScopedState<> start(space), goal(space);
      for (int i = 0; i < n; ++i) {
        start[i] = seed_paths.front().front()[i];
        goal[i] = seed_paths.front().back()[i];
      }
      problem->setStartAndGoalStates(start, goal);
    }
    GrowingPrm prm(si, Mix(options.seed + 0x300));
    prm.setMaxNearestNeighbors(static_cast<unsigned>(options.neighbors));
    prm.setProblemDefinition(problem);
    prm.setup();
    const unsigned target = static_cast<unsigned>(options.prm_vertices);
    prm.Grow(ob::PlannerTerminationCondition(
        [&prm, &termination, target] { return prm.milestoneCount() >= target || termination.ShouldStop(); }));
    ob::PlannerData data(si);
    prm.getPlannerData(data);
    std::vector<int> index(data.numVertices(), -1);
    for (unsigned i = 0; i < data.numVertices(); ++i) index[i] = coarse.AddVertex(ToEigen(data.getVertex(i).getState(), n));
    for (unsigned i = 0; i < data.numVertices(); ++i) {
      std::vector<unsigned> out;
      data.getEdges(i, out);
      for (unsigned j : out) coarse.AddEdge(index[i], index[j]);
    }
    // Each seed vertex to its nearest PRM vertices, by valid motions.
    const int total = static_cast<int>(coarse.vertices.size());
    for (int s = 0; s < seeds && !termination.ShouldStop(); ++s) {
      std::vector<std::pair<double, int>> by_distance;
      for (int v = seeds; v < total; ++v) by_distance.emplace_back((coarse.vertices[v] - coarse.vertices[s]).norm(), v);
      const std::size_t k = std::min<std::size_t>(by_distance.size(), static_cast<std::size_t>(options.neighbors));
      std::partial_sort(by_distance.begin(), by_distance.begin() + k, by_distance.end());
      for (std::size_t i = 0; i < k; ++i) {
        const int v = by_distance[i].second;
        if (validator->Valid(coarse.vertices[s], coarse.vertices[v])) coarse.AddEdge(s, v);
      }
    }
  }

  // 3. Stations: edges longer than station_spacing (max-norm over joints) get intermediate vertices.
  Roadmap roadmap;
  for (const Eigen::VectorXd& q : coarse.vertices) roadmap.AddVertex(q);
  for (int a = 0; a < static_cast<int>(coarse.vertices.size()); ++a) {
    for (int b : coarse.neighbors[a]) {
      if (b < a) continue;
      const Eigen::VectorXd delta = coarse.vertices[b] - coarse.vertices[a];
      const int parts = std::max(1, static_cast<int>(std::ceil(delta.cwiseAbs().maxCoeff() / options.station_spacing)));
      int previous = a;
      std::vector<int> line{a};
      for (int p = 1; p < parts; ++p) {
        const int v = roadmap.AddVertex(coarse.vertices[a] + (static_cast<double>(p) / parts) * delta);
        roadmap.AddEdge(previous, v);
        line.push_back(v);
        previous = v;
      }
      roadmap.AddEdge(previous, b);
      line.push_back(b);
      roadmap.lines.push_back(std::move(line));
    }
  }
  return roadmap;
}

}  // namespace chasles
